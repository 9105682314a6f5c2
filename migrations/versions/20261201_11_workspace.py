"""The cooperative's workspace: organisations, users, tokens, sessions, the field registry.

Every plan, simulation and run gets an ``organisation_id``; the rows that exist already move
into the organisation ``default`` (made only when there are rows to move), and each plan gets
a field of its own in the registry, made from its stored request (boundary, name, gates), so
nothing is lost. The first account (``tillpath users create`` or the page's sign-up) joins
``default`` as its owner.

Revision ID: 20261201_11
Revises: 0003
Create Date: 2026-12-01
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "20261201_11"
down_revision: str | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

DEFAULT_ORGANISATION = "default"
BATCH = 500


def _ts() -> sa.DateTime:
    return sa.DateTime(timezone=True)


def _create_tables() -> None:
    op.create_table(
        "organisations",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("name", sa.String(length=100), nullable=False),
        sa.Column("created_at", _ts(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_organisations")),
        sa.UniqueConstraint("name", name=op.f("uq_organisations_name")),
    )
    op.create_table(
        "users",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("username", sa.String(length=100), nullable=False),
        sa.Column("password_hash", sa.String(length=255), nullable=False),
        sa.Column("created_at", _ts(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_users")),
        sa.UniqueConstraint("username", name=op.f("uq_users_username")),
    )
    op.create_table(
        "memberships",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("organisation_id", sa.Integer(), nullable=False),
        sa.Column("role", sa.String(length=16), nullable=False),
        sa.ForeignKeyConstraint(
            ["user_id"], ["users.id"], name=op.f("fk_memberships_user_id_users"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["organisation_id"],
            ["organisations.id"],
            name=op.f("fk_memberships_organisation_id_organisations"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_memberships")),
        sa.UniqueConstraint("user_id", "organisation_id", name=op.f("uq_memberships_user_id")),
    )
    op.create_index(op.f("ix_memberships_user_id"), "memberships", ["user_id"])
    op.create_index(op.f("ix_memberships_organisation_id"), "memberships", ["organisation_id"])
    op.create_table(
        "api_tokens",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("organisation_id", sa.Integer(), nullable=True),
        sa.Column("kind", sa.String(length=16), nullable=False),
        sa.Column("name", sa.String(length=100), nullable=False),
        sa.Column("token_sha256", sa.String(length=64), nullable=False),
        sa.Column("prefix", sa.String(length=16), nullable=False),
        sa.Column("created_at", _ts(), nullable=False),
        sa.Column("last_used_at", _ts(), nullable=True),
        sa.Column("revoked_at", _ts(), nullable=True),
        sa.ForeignKeyConstraint(
            ["user_id"], ["users.id"], name=op.f("fk_api_tokens_user_id_users"), ondelete="CASCADE"
        ),
        sa.ForeignKeyConstraint(
            ["organisation_id"],
            ["organisations.id"],
            name=op.f("fk_api_tokens_organisation_id_organisations"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_api_tokens")),
        sa.UniqueConstraint("token_sha256", name=op.f("uq_api_tokens_token_sha256")),
    )
    op.create_index(op.f("ix_api_tokens_user_id"), "api_tokens", ["user_id"])
    op.create_index(op.f("ix_api_tokens_organisation_id"), "api_tokens", ["organisation_id"])
    op.create_table(
        "login_sessions",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("token_sha256", sa.String(length=64), nullable=False),
        sa.Column("user_id", sa.Integer(), nullable=False),
        sa.Column("organisation_id", sa.Integer(), nullable=True),
        sa.Column("csrf_token", sa.String(length=64), nullable=False),
        sa.Column("created_at", _ts(), nullable=False),
        sa.Column("expires_at", _ts(), nullable=False),
        sa.ForeignKeyConstraint(
            ["user_id"],
            ["users.id"],
            name=op.f("fk_login_sessions_user_id_users"),
            ondelete="CASCADE",
        ),
        sa.ForeignKeyConstraint(
            ["organisation_id"],
            ["organisations.id"],
            name=op.f("fk_login_sessions_organisation_id_organisations"),
            ondelete="SET NULL",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_login_sessions")),
        sa.UniqueConstraint("token_sha256", name=op.f("uq_login_sessions_token_sha256")),
    )
    op.create_index(op.f("ix_login_sessions_user_id"), "login_sessions", ["user_id"])
    op.create_table(
        "login_attempts",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("username", sa.String(length=100), nullable=False),
        sa.Column("address", sa.String(length=64), nullable=False),
        sa.Column("at", _ts(), nullable=False),
        sa.Column("succeeded", sa.Boolean(), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_login_attempts")),
    )
    op.create_index(op.f("ix_login_attempts_username"), "login_attempts", ["username"])
    op.create_index(op.f("ix_login_attempts_address"), "login_attempts", ["address"])
    op.create_index(op.f("ix_login_attempts_at"), "login_attempts", ["at"])
    op.create_table(
        "fields",
        sa.Column("id", sa.Integer(), autoincrement=True, nullable=False),
        sa.Column("organisation_id", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(length=200), nullable=False),
        sa.Column("boundary", sa.JSON(), nullable=False),
        sa.Column("boundary_sha256", sa.String(length=64), nullable=False),
        sa.Column("start", sa.JSON(), nullable=True),
        sa.Column("finish", sa.JSON(), nullable=True),
        sa.Column("notes", sa.Text(), nullable=False),
        sa.Column("created_at", _ts(), nullable=False),
        sa.Column("updated_at", _ts(), nullable=False),
        sa.ForeignKeyConstraint(
            ["organisation_id"],
            ["organisations.id"],
            name=op.f("fk_fields_organisation_id_organisations"),
            ondelete="CASCADE",
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_fields")),
    )
    op.create_index(op.f("ix_fields_organisation_id"), "fields", ["organisation_id"])
    op.create_index(op.f("ix_fields_boundary_sha256"), "fields", ["boundary_sha256"])
    op.create_index(op.f("ix_fields_created_at"), "fields", ["created_at"])


def _boundary_sha256(boundary: Any) -> str:
    text = json.dumps(boundary, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _move_rows() -> None:
    """Put the existing rows into ``default``; give each plan a field of its own."""
    bind = op.get_bind()
    plans = sa.table(
        "plans",
        sa.column("id", sa.Integer()),
        sa.column("name", sa.String()),
        sa.column("created_at", _ts()),
        sa.column("request", sa.JSON()),
        sa.column("organisation_id", sa.Integer()),
        sa.column("field_id", sa.Integer()),
    )
    organisations = sa.table(
        "organisations",
        sa.column("id", sa.Integer()),
        sa.column("name", sa.String()),
        sa.column("created_at", _ts()),
    )
    fields = sa.table(
        "fields",
        sa.column("id", sa.Integer()),
        sa.column("organisation_id", sa.Integer()),
        sa.column("name", sa.String()),
        sa.column("boundary", sa.JSON()),
        sa.column("boundary_sha256", sa.String()),
        sa.column("start", sa.JSON()),
        sa.column("finish", sa.JSON()),
        sa.column("notes", sa.Text()),
        sa.column("created_at", _ts()),
        sa.column("updated_at", _ts()),
    )
    counts = [
        bind.scalar(sa.select(sa.func.count()).select_from(sa.table(name)))
        for name in ("plans", "simulations", "runs")
    ]
    if not any(counts):
        return
    now = dt.datetime.now(dt.UTC)
    if bind.dialect.name == "sqlite":
        now = now.replace(tzinfo=None)
    org_id = bind.execute(
        organisations.insert()
        .values(name=DEFAULT_ORGANISATION, created_at=now)
        .returning(organisations.c.id)
    ).scalar_one()
    last = 0
    while True:
        rows = bind.execute(
            sa.select(plans.c.id, plans.c.name, plans.c.created_at, plans.c.request)
            .where(plans.c.id > last)
            .order_by(plans.c.id)
            .limit(BATCH)
        ).all()
        if not rows:
            break
        for plan_id, name, created_at, request in rows:
            request = request or {}
            boundary = request.get("field") or {"type": "Polygon", "coordinates": []}
            field_id = bind.execute(
                fields.insert()
                .values(
                    organisation_id=org_id,
                    name=((name or "").strip() or f"plan {plan_id}")[:200],
                    boundary=boundary,
                    boundary_sha256=_boundary_sha256(boundary),
                    start=request.get("start"),
                    finish=request.get("finish"),
                    notes="",
                    created_at=created_at,
                    updated_at=created_at,
                )
                .returning(fields.c.id)
            ).scalar_one()
            bind.execute(
                plans.update()
                .where(plans.c.id == plan_id)
                .values(organisation_id=org_id, field_id=field_id)
            )
        last = rows[-1][0]
    for name in ("simulations", "runs"):
        table = sa.table(name, sa.column("organisation_id", sa.Integer()))
        bind.execute(table.update().values(organisation_id=org_id))


def upgrade() -> None:
    _create_tables()
    op.add_column("plans", sa.Column("organisation_id", sa.Integer(), nullable=True))
    op.add_column("plans", sa.Column("field_id", sa.Integer(), nullable=True))
    op.add_column("simulations", sa.Column("organisation_id", sa.Integer(), nullable=True))
    op.add_column("runs", sa.Column("organisation_id", sa.Integer(), nullable=True))
    _move_rows()
    with op.batch_alter_table("plans") as batch:
        batch.alter_column("organisation_id", existing_type=sa.Integer(), nullable=False)
        batch.create_foreign_key(
            op.f("fk_plans_organisation_id_organisations"),
            "organisations",
            ["organisation_id"],
            ["id"],
            ondelete="CASCADE",
        )
        batch.create_foreign_key(
            op.f("fk_plans_field_id_fields"), "fields", ["field_id"], ["id"], ondelete="SET NULL"
        )
        batch.create_index(op.f("ix_plans_organisation_id"), ["organisation_id"])
        batch.create_index(op.f("ix_plans_field_id"), ["field_id"])
    for name in ("simulations", "runs"):
        with op.batch_alter_table(name) as batch:
            batch.alter_column("organisation_id", existing_type=sa.Integer(), nullable=False)
            batch.create_foreign_key(
                op.f(f"fk_{name}_organisation_id_organisations"),
                "organisations",
                ["organisation_id"],
                ["id"],
                ondelete="CASCADE",
            )
            batch.create_index(op.f(f"ix_{name}_organisation_id"), ["organisation_id"])


def downgrade() -> None:
    for name in ("runs", "simulations"):
        with op.batch_alter_table(name) as batch:
            batch.drop_index(op.f(f"ix_{name}_organisation_id"))
            batch.drop_constraint(
                op.f(f"fk_{name}_organisation_id_organisations"), type_="foreignkey"
            )
            batch.drop_column("organisation_id")
    with op.batch_alter_table("plans") as batch:
        batch.drop_index(op.f("ix_plans_field_id"))
        batch.drop_index(op.f("ix_plans_organisation_id"))
        batch.drop_constraint(op.f("fk_plans_field_id_fields"), type_="foreignkey")
        batch.drop_constraint(op.f("fk_plans_organisation_id_organisations"), type_="foreignkey")
        batch.drop_column("field_id")
        batch.drop_column("organisation_id")
    for table in (
        "fields",
        "login_attempts",
        "login_sessions",
        "api_tokens",
        "memberships",
        "users",
        "organisations",
    ):
        op.drop_table(table)
