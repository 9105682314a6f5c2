"""navigation is pure simulation: it may import planner, never the web app or I/O stacks."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "navigation"
FORBIDDEN = ("app", "fastapi", "starlette", "sqlalchemy", "uvicorn", "requests", "httpx")


@pytest.mark.parametrize("path", sorted(PACKAGE.glob("*.py")), ids=lambda p: p.name)
def test_navigation_does_not_import_the_app_or_io(path: Path) -> None:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            names = [node.module or ""]
        else:
            continue
        for name in names:
            assert name.split(".")[0] not in FORBIDDEN, f"{path.name} imports {name}"
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("matplotlib.pyplot"):
            pytest.fail(f"{path.name} imports pyplot (global state)")
