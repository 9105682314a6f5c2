"""The examples in the app's docstrings run (pytest collects doctests only under planner/)."""

from __future__ import annotations

import doctest

import pytest

import app.errors
import app.services
import app.track_fixes
import app.tracks


@pytest.mark.parametrize("module", [app.errors, app.services, app.tracks, app.track_fixes])
def test_docstring_examples_hold(module: object):
    result = doctest.testmod(module, raise_on_error=False)  # type: ignore[arg-type]
    assert result.attempted > 0
    assert result.failed == 0
