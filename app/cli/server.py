"""Placeholder: the owner of this module replaces it."""

from __future__ import annotations

import typer


def register(cli: typer.Typer) -> None:
    """Add this module's commands to ``cli``."""
