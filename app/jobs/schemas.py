"""What the jobs API answers."""

from __future__ import annotations

import datetime as dt
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field

JobStatus = Literal["queued", "running", "done", "failed", "cancelled"]


class JobRead(BaseModel):
    """A background job (product.md §13)."""

    model_config = ConfigDict(from_attributes=True)

    id: int
    kind: str = Field(description="`simulation` or `monte_carlo` (later: bulk imports).")
    status: JobStatus
    progress: float = Field(ge=0, le=1, description="How far it has got, 0–1.")
    result: dict[str, Any] | None = Field(
        description="What it produced (when done): for simulations the stored simulation's id "
        "and, for a Monte Carlo batch, the summary of each metric."
    )
    result_url: str | None = Field(description="Where the stored result is (when done).")
    error: str | None = Field(description="Why it failed, naming the input and the problem.")
    attempts: int = Field(description="How many times a worker started it.")
    created_at: dt.datetime
    started_at: dt.datetime | None
    updated_at: dt.datetime
    finished_at: dt.datetime | None
