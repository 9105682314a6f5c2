"""Keep each run's fix count on its row, so a live poll counts nothing (issue 15).

``runs.fix_count`` is raised in the transaction that stores each batch of fixes
(:func:`app.ingest.store_fixes`); existing runs get theirs counted here.

Revision ID: 20261201_15
Revises: 20261201_10
Create Date: 2026-12-01
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "20261201_15"
down_revision: str | None = "20261201_10"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("runs") as batch:
        batch.add_column(
            sa.Column("fix_count", sa.Integer(), nullable=False, server_default=sa.text("0"))
        )
    # One pass over the fixes' (run_id, t) key, however many runs.
    op.execute(
        "UPDATE runs SET fix_count = (SELECT count(*) FROM fixes WHERE fixes.run_id = runs.id)"
    )


def downgrade() -> None:
    with op.batch_alter_table("runs") as batch:
        batch.drop_column("fix_count")
