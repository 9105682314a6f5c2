"""The request's settings as a FastAPI dependency, answered on the event loop.

:func:`app.settings.get_settings` is a plain (cached) function; as a dependency FastAPI would
run it in a worker thread, a hop there and back on every request that needs the settings
(each request does: the database session and the heavy-work queue ask for them). The app
keeps its settings in ``app.state.settings`` (:func:`app.main.create_app`);
:func:`request_settings` hands them out without a hop. Tests that want other settings for a
while override :func:`request_settings` (``app.dependency_overrides``).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import Depends, Request

from app.settings import Settings


async def request_settings(request: Request) -> Settings:
    """Return the settings of the app serving ``request``."""
    settings: Settings = request.app.state.settings
    return settings


SettingsDep = Annotated[Settings, Depends(request_settings)]
