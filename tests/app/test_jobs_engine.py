"""The job engine (``app.jobs.engine``): one warm-up of its workers, by the plugin."""

from __future__ import annotations

import pytest


def test_the_engine_warms_its_workers_once_by_the_plugin(monkeypatch: pytest.MonkeyPatch):
    """One warm-up: the plugin (kernels, then the job kinds), and no client.run besides."""
    from unittest import mock

    import distributed

    from app.jobs.engine import JobEngine
    from app.kernels_plugin import KernelWarmUp

    client = mock.MagicMock()
    monkeypatch.setattr(distributed, "Client", mock.MagicMock(return_value=client))
    engine = JobEngine("sqlite:///unused.db", scheduler_address="tcp://127.0.0.1:1")
    monkeypatch.setattr(engine, "sweep", lambda: None)
    engine.start()
    engine.stop()
    (plugin,), _ = client.register_plugin.call_args
    assert client.register_plugin.call_count == 1
    assert isinstance(plugin, KernelWarmUp) and plugin.job_kinds
    client.run.assert_not_called()


def test_the_plugin_imports_the_job_kinds_only_when_asked():
    """In a fresh interpreter: the kernels alone, then the kinds' modules too."""
    import subprocess
    import sys

    code = (
        "import sys; from app.kernels_plugin import _warm_up; "
        "_warm_up(False); print('app.jobs.simulations' in sys.modules); "
        "_warm_up(True); print('app.jobs.simulations' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]
