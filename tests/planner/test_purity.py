"""The planner is pure geometry: it imports no I/O layer and does no I/O (style.md §1)."""

import ast
from pathlib import Path

import pytest

PLANNER = Path(__file__).resolve().parents[2] / "planner"
FORBIDDEN_MODULES = {"app", "navigation", "fastapi", "sqlalchemy", "starlette", "requests", "httpx"}
FORBIDDEN_CALLS = {"open", "print", "input"}


@pytest.mark.parametrize(
    "path", sorted(PLANNER.rglob("*.py")), ids=lambda p: str(p.relative_to(PLANNER))
)
def test_planner_module_does_no_io(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [node.module or ""]
        else:
            names = []
        for name in names:
            assert name.split(".")[0] not in FORBIDDEN_MODULES, f"{path.name} imports {name}"
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name):
            assert node.func.id not in FORBIDDEN_CALLS, f"{path.name} calls {node.func.id}()"
