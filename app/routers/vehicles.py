"""``/api/vehicles``: the vehicle presets (product.md §3a), for the page and API clients."""

from __future__ import annotations

import dataclasses
from typing import Any

from fastapi import APIRouter

import planner
from app.auth import Viewer

router = APIRouter(tags=["vehicles"])


@router.get("/vehicles")
def list_vehicles(access: Viewer) -> dict[str, list[dict[str, Any]]]:
    """List the vehicle presets with their figures (sources: docs/vehicles.md)."""
    del access  # any signed-in member may read them
    return {"items": [dataclasses.asdict(v) for v in planner.PRESETS.values()]}
