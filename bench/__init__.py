"""Benchmarks against the budgets of product.md §11 (run with ``make bench``)."""
