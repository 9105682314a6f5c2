"""Keep each fix's quality, HDOP and satellite count (product.md §8).

Revision ID: 20261201_10
Revises: 20261201_11
Create Date: 2026-12-01
"""

from __future__ import annotations

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "20261201_10"
down_revision: str | None = "0014_jobs"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    # Nullable columns added to an existing table: no rewrite of the rows on either database.
    with op.batch_alter_table("fixes") as batch:
        batch.add_column(sa.Column("quality", sa.String(length=16), nullable=True))
        batch.add_column(sa.Column("hdop", sa.Double(), nullable=True))
        batch.add_column(sa.Column("satellites", sa.SmallInteger(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table("fixes") as batch:
        batch.drop_column("satellites")
        batch.drop_column("hdop")
        batch.drop_column("quality")
