"""planner.warm_up warms every kernel module of the planner, and each module only its own."""

from __future__ import annotations

import importlib
from contextlib import ExitStack
from pathlib import Path
from unittest import mock

import planner
from planner.warm_up import warm_up

KERNEL_MODULES = sorted(p.stem for p in Path(planner.__file__).parent.glob("*kernels.py"))


def test_every_kernel_module_is_warmed_once() -> None:
    """A kernel module added without a line in ``planner.warm_up`` fails here."""
    assert "kernels" in KERNEL_MODULES and len(KERNEL_MODULES) >= 6
    with ExitStack() as stack:
        calls = {
            name: stack.enter_context(
                mock.patch.object(importlib.import_module(f"planner.{name}"), "warm_up")
            )
            for name in KERNEL_MODULES
        }
        warm_up()
    assert {name: call.call_count for name, call in calls.items()} == dict.fromkeys(
        KERNEL_MODULES, 1
    )


def test_the_base_kernels_warm_only_their_own() -> None:
    """``planner.kernels.warm_up`` calls no other module's warm-up (they import it)."""
    others = [name for name in KERNEL_MODULES if name != "kernels"]
    with ExitStack() as stack:
        calls = [
            stack.enter_context(
                mock.patch.object(importlib.import_module(f"planner.{name}"), "warm_up")
            )
            for name in others
        ]
        importlib.import_module("planner.kernels").warm_up()
    assert [call.call_count for call in calls] == [0] * len(others)


def test_warm_up_runs() -> None:
    warm_up()
