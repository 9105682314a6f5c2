"""Application settings, read from the environment (``TILLPATH_*``) by pydantic-settings."""

from __future__ import annotations

import os
from functools import lru_cache

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict

#: Esri World Imagery, the satellite layer of the map page.
ESRI_WORLD_IMAGERY_URL = (
    "https://server.arcgisonline.com/ArcGIS/rest/services/World_Imagery/MapServer/tile/{z}/{y}/{x}"
)
#: OpenStreetMap's standard tiles.
OSM_TILE_URL = "https://tile.openstreetmap.org/{z}/{x}/{y}.png"


class Settings(BaseSettings):
    """Everything the app reads from its environment.

    Each attribute can be set with ``TILLPATH_<NAME>`` (for example
    ``TILLPATH_DATABASE_URL=postgresql+psycopg://user@host/db``).

    Attributes
    ----------
    database_url : str
        SQLAlchemy URL. The default is a SQLite file under ``./data/`` (created on first use).
    satellite_tile_url, street_tile_url : str
        Leaflet tile URL templates; point them at an offline tile server if needed.
    max_body_bytes : int
        Largest request body accepted [bytes]; larger ones get 413.
    max_upload_bytes : int
        Largest track file accepted by ``POST /api/plans/{id}/runs`` [bytes] (a 6-hour u-blox
        NMEA log at 5 Hz is about 20 MB, a 6-hour 10 Hz CSV about 12 MB); larger ones get 413.
        Uploads are read as a stream, so memory does not grow with this limit.
    heavy_work_slots : int
        Plans, simulations, uploads and run scorings computed at once per worker process
        (default: the number of CPU cores).
    heavy_work_queue : int
        Further such requests that wait for a slot; more are answered 503 with ``Retry-After``.
    heavy_work_wait_s : float
        Longest wait for a slot [s]; then 503 with ``Retry-After``.
    header_timeout_s, body_idle_timeout_s : float
        ``tillpath serve`` closes a connection whose request line and headers take longer than
        this to arrive, or whose body stops arriving for this long [s].
    keep_alive_s : int
        Idle keep-alive connections are closed after this long [s].
    limit_concurrency : int
        Connections and requests a worker serves at once; more get 503 at once.
    backlog : int
        Connections the operating system queues before the server accepts them.
    planning_budget_s : float
        Longest a large field (hundreds of vertices, many holes, or over 10 ha as a spiral)
        may take to plan in one request [s]; longer gets 422 naming the limit
        (:mod:`app.budget`).
    secure_cookies : bool
        Mark the session cookie ``Secure`` (sent over HTTPS only). Turn it on behind TLS.
    dask_scheduler : str or None
        Address of a Dask scheduler (``tcp://host:8786``) that runs the background jobs
        (product.md §13). None: the server starts a local cluster of its own.
    dask_workers : int or None
        Worker processes of that local cluster (default: one per CPU core).
    warm_up_planner : bool
        Start the fork server and load the planner's kernels before the app answers
        (:func:`app.budget.warm_up`). ``tillpath serve`` does it in its own process and sets
        this for the processes of ``--workers N > 1``, which uvicorn spawns afresh.
    """

    model_config = SettingsConfigDict(env_prefix="TILLPATH_", extra="ignore")

    database_url: str = "sqlite:///./data/tillpath.db"
    satellite_tile_url: str = ESRI_WORLD_IMAGERY_URL
    street_tile_url: str = OSM_TILE_URL
    max_body_bytes: int = Field(default=2 * 1024 * 1024, ge=1)
    max_upload_bytes: int = Field(default=32 * 1024 * 1024, ge=1)
    heavy_work_slots: int = Field(default=max(2, os.cpu_count() or 2), ge=1, le=1024)
    heavy_work_queue: int = Field(default=16, ge=0, le=10_000)
    heavy_work_wait_s: float = Field(default=10.0, ge=0, le=600)
    header_timeout_s: float = Field(default=10.0, gt=0, le=3600)
    body_idle_timeout_s: float = Field(default=30.0, gt=0, le=3600)
    keep_alive_s: int = Field(default=5, ge=1, le=3600)
    limit_concurrency: int = Field(default=200, ge=1, le=100_000)
    backlog: int = Field(default=256, ge=1, le=65_535)
    planning_budget_s: float = Field(default=1.5, gt=0, le=600)
    secure_cookies: bool = False
    dask_scheduler: str | None = None
    dask_workers: int | None = Field(default=None, ge=1)
    warm_up_planner: bool = False


@lru_cache
def get_settings() -> Settings:
    """Return the process-wide settings from the environment (cached).

    Routes do not call this: they take the settings their app was made with
    (:func:`app.dependencies.request_settings`), which tests replace.
    """
    return Settings()
