"""The workers' warm-up plugin (``app.kernels_plugin``) on a real local cluster."""

from __future__ import annotations


def _web_app_imported() -> bool:
    import sys

    return "app.jobs.service" in sys.modules


def test_registering_the_plan_batch_plugin_does_not_load_the_web_app_in_workers() -> None:
    """A worker unpickles the plugin by importing its module: outside ``app.jobs``, whose
    package imports the web app (about 1 s a worker inside ``plan-batch``'s run)."""
    from distributed import Client

    from app.kernels_plugin import KernelWarmUp
    from app.local_cluster import start_local_cluster

    with start_local_cluster(1) as cluster, Client(cluster, set_as_default=False) as client:
        client.register_plugin(KernelWarmUp())
        (imported,) = client.run(_web_app_imported).values()
    assert imported is False
