"""The numba cache of the planner's kernels is emptied when any kernel's source changes."""

from __future__ import annotations

from pathlib import Path

from planner.kernel_helpers import drop_stale_kernels


def _package(root: Path) -> tuple[Path, Path]:
    package = root / "package"
    cache = package / "__pycache__"
    cache.mkdir(parents=True)
    (package / "kernels.py").write_text("@_jit\ndef f():\n    return 1\n")
    (package / "plain.py").write_text("def g():\n    return 2\n")
    return package, cache


def _compiled(cache: Path) -> None:
    for name in ("kernels.f-1.py311.nbi", "kernels.f-1.py311.1.nbc"):
        (cache / name).write_bytes(b"machine code")


def test_a_changed_kernel_source_empties_the_cache(tmp_path: Path) -> None:
    package, cache = _package(tmp_path)
    (cache / "kernels.cpython-311.pyc").write_bytes(b"bytecode")
    _compiled(cache)
    assert drop_stale_kernels(package, cache)  # no record yet: built from unknown sources
    assert not list(cache.glob("*.nb*"))
    assert (cache / "kernels.cpython-311.pyc").exists()  # only numba's files go
    _compiled(cache)
    assert not drop_stale_kernels(package, cache)  # the same sources: kept
    assert len(list(cache.glob("*.nb*"))) == 2
    (package / "kernels.py").write_text("@_jit\ndef f():\n    return 3\n")
    assert drop_stale_kernels(package, cache)
    assert not list(cache.glob("*.nb*"))


def test_a_module_without_kernels_does_not_empty_it(tmp_path: Path) -> None:
    package, cache = _package(tmp_path)
    drop_stale_kernels(package, cache)
    _compiled(cache)
    (package / "plain.py").write_text("def g():\n    return 4\n")
    assert not drop_stale_kernels(package, cache)
    assert len(list(cache.glob("*.nb*"))) == 2


def test_a_cache_it_cannot_write_is_left_alone(tmp_path: Path) -> None:
    package, cache = _package(tmp_path)
    blocked = package / "not-a-directory"
    blocked.write_text("a file where the cache would be")
    assert not drop_stale_kernels(package, blocked)
    assert blocked.read_text() == "a file where the cache would be"
