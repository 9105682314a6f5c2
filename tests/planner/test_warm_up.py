"""planner.warm_up warms every kernel module of the planner, and each module only its own."""

from __future__ import annotations

import importlib
import json
import subprocess
import sys
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


#: Run in a fresh process: after the warm-up, plan one case of each kind and print the
#: kernel signatures that the plans added (each one compiled, or loaded, inside a plan).
_NEW_SIGNATURES_SCRIPT = """
import importlib, json, pkgutil, sys
from numba.core.registry import CPUDispatcher
from shapely.geometry import shape
import planner
from planner import plan_coverage
from planner.warm_up import warm_up

def signatures():
    found = {}
    for info in pkgutil.iter_modules(planner.__path__):
        module = importlib.import_module(f"planner.{info.name}")
        for name, value in vars(module).items():
            if isinstance(value, CPUDispatcher) and value.__module__ == module.__name__:
                found[f"{module.__name__}.{name}"] = {str(s) for s in value.signatures}
    return found

def feature(path, feature_id):
    for f in json.load(open(path))["features"]:
        if feature_id is None or f["properties"].get("id") == feature_id:
            return shape(f["geometry"])

warm_up()
before = signatures()
paper = feature(sys.argv[1], None)
holed = feature(sys.argv[2], "germany_2018_2019-22")
for field, options in [
    (paper, {}),
    (paper, {"vehicle": "small_tractor", "implement_width_m": 2.5}),
    (holed, {}),
    (holed, {"vehicle": "small_tractor"}),
    (holed, {"vehicle": "small_tractor", "pattern": "snake", "headland_passes": 1}),
    (holed, {"vehicle": "rover", "pattern": "spiral"}),
    (holed, {"vehicle": "paper_g1000", "objective": "fewest_lines", "angle_deg": 30.0}),
]:
    plan_coverage(field, interval_m=4.0, **options)
after = signatures()
print(json.dumps({k: sorted(v - before.get(k, set())) for k, v in after.items()
                  if v - before.get(k, set())}))
"""


def test_plans_compile_nothing_after_the_warm_up() -> None:
    """A plan after the warm-up compiles no kernel: every version it needs was warmed.

    Numba compiles a kernel per argument types, an array's write flag included: a warm-up on
    writable arrays left the heading screen's read-only scans to compile four kernels inside
    the first real plans (6 s of the 223 fields' first pass on a fresh cache).
    """
    from tests.conftest import FIELDS_DIR, PAPER_FIELD

    result = subprocess.run(
        [
            sys.executable,
            "-c",
            _NEW_SIGNATURES_SCRIPT,
            str(PAPER_FIELD),
            str(FIELDS_DIR / "germany_2018_2019.geojson"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    assert json.loads(result.stdout.strip().splitlines()[-1]) == {}
