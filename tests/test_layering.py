"""Dependencies point one way (style.md §1): ``planner`` and ``navigation`` are pure.

``planner`` is geometry and ``navigation`` simulation: neither imports the web app or an I/O
stack, nor opens files, prints or reads input; ``navigation`` may use the planner, not the
reverse, and plots without pyplot's global state.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
IO_STACKS = {"app", "fastapi", "starlette", "sqlalchemy", "uvicorn", "requests", "httpx"}
FORBIDDEN_IMPORTS = {"planner": IO_STACKS | {"navigation"}, "navigation": IO_STACKS}
FORBIDDEN_CALLS = {"open", "print", "input"}


def imported_names(node: ast.AST, package: str) -> list[str]:
    """The modules an import statement names (none for other nodes); a relative import
    (level > 0) names ``package``, by definition."""
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if isinstance(node, ast.ImportFrom):
        return [package if node.level else node.module or ""]
    return []


MODULES = [
    (package, path)
    for package in FORBIDDEN_IMPORTS
    for path in sorted((ROOT / package).rglob("*.py"))
]


@pytest.mark.parametrize(
    ("package", "path"), MODULES, ids=[str(p.relative_to(ROOT)) for _, p in MODULES]
)
def test_pure_packages_import_no_io_layer_and_do_no_io(package: str, path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        for name in imported_names(node, package):
            assert name.split(".")[0] not in FORBIDDEN_IMPORTS[package], f"{path} imports {name}"
            assert not name.startswith("matplotlib.pyplot"), f"{path} imports pyplot"
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            assert node.func.id not in FORBIDDEN_CALLS, f"{path} calls {node.func.id}()"


#: Modules that import nothing of their own package. ``planner.kernel_helpers`` holds the
#: helpers (``_jit``, ``_mn``, ...) that every kernel module imports, so importing any of them
#: back would be a cycle: :mod:`planner.warm_up`, above them all, warms them all.
BASE_MODULES = ["planner/kernel_helpers.py"]


@pytest.mark.parametrize("relative", BASE_MODULES)
def test_base_modules_import_nothing_of_their_package(relative: str) -> None:
    path = ROOT / relative
    package = relative.split("/")[0]
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        for name in imported_names(node, package):
            assert name.split(".")[0] != package, f"{relative} imports {name}"


BENCHES = sorted((ROOT / "bench").rglob("*.py"))


@pytest.mark.parametrize("path", BENCHES, ids=[str(p.relative_to(ROOT)) for p in BENCHES])
def test_benches_import_no_tests(path: Path) -> None:
    """What a bench shares with the tests lives in ``bench/`` (``bench.shapes``), not ``tests/``."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        for name in imported_names(node, "bench"):
            assert name.split(".")[0] != "tests", f"{path} imports {name}"
