"""The job engine's local cluster settings (``app.jobs.engine``)."""

from __future__ import annotations

import pytest

from app.jobs.engine import QUIET_CLUSTER


@pytest.mark.parametrize("key", sorted(QUIET_CLUSTER))
def test_quiet_cluster_keys_exist_in_dask_config(key: str) -> None:
    """``dask.config.set`` takes any key: a misspelt one would be set and silently ignored."""
    import dask
    import distributed  # noqa: F401  (loads the distributed.* defaults)

    dask.config.get(key)  # raises KeyError for a key dask does not know
