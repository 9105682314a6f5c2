"""``tillpath users create`` and ``tillpath tokens create`` (product.md §10, §12).

Both read ``TILLPATH_DATABASE_URL`` like the server and migrate the database first. The
password comes on standard input (``--password-stdin``), never as an argument a process list
would show; a token is printed once, alone on the last line of standard output.
"""

from __future__ import annotations

import sys
from enum import StrEnum
from typing import TYPE_CHECKING, Annotated

import typer

from app.cli.common import fail

if TYPE_CHECKING:
    from sqlalchemy.orm import Session


class RoleChoice(StrEnum):
    """Roles in an organisation."""

    owner = "owner"
    planner = "planner"
    viewer = "viewer"


def _session() -> Session:
    """Migrate the configured database, then open a session on it."""
    from sqlalchemy.orm import Session

    from app.cli.server import upgrade
    from app.db import get_engine
    from app.settings import get_settings

    upgrade()
    return Session(get_engine(get_settings().database_url), expire_on_commit=False)


def users_create(
    name: Annotated[str, typer.Argument(metavar="NAME", help="Username.")],
    org: Annotated[str, typer.Option("--org", help="Organisation (made if missing).")] = "default",
    role: Annotated[RoleChoice, typer.Option("--role", help="Role in the organisation.")] = (
        RoleChoice.owner
    ),
    password_stdin: Annotated[
        bool, typer.Option("--password-stdin", help="Read the password from standard input.")
    ] = False,
) -> None:
    """Add a user with a role in an organisation; an existing user just gets the role."""
    from sqlalchemy import select
    from sqlalchemy.exc import SQLAlchemyError

    from app import accounts
    from app.auth_models import User
    from app.errors import AccountError

    if not password_stdin:
        fail("--password-stdin: give the password on standard input (it is never an argument)")
    password = sys.stdin.readline().rstrip("\r\n")
    try:
        with _session() as session:
            existed = session.scalar(select(User).where(User.username == name.strip()))
            user = accounts.create_user(session, name, password, organisation=org, role=role.value)
            what = "gave" if existed else "created"
            typer.echo(
                f"{what} user {user.username!r} the role {role.value} in organisation {org!r}",
                err=True,
            )
            if existed:
                typer.echo("(the existing password was kept)", err=True)
    except AccountError as exc:
        fail(str(exc))
    except SQLAlchemyError as exc:
        fail(f"database: {exc}")


def tokens_create(
    user: Annotated[str, typer.Option("--user", help="Whose token it is.")],
    device: Annotated[
        bool,
        typer.Option("--device", help="A device token: posts fixes to live runs, nothing else."),
    ] = False,
    name: Annotated[str, typer.Option("--name", help="A label, e.g. the tractor's name.")] = "",
    org: Annotated[
        str | None,
        typer.Option("--org", help="The device token's organisation; default: the user's first."),
    ] = None,
) -> None:
    """Make an API token; it is printed once, alone on the last line of standard output."""
    from sqlalchemy import select
    from sqlalchemy.exc import SQLAlchemyError

    from app import accounts
    from app.auth_models import Membership, Organisation
    from app.errors import AccountError

    try:
        with _session() as session:
            owner = accounts.find_user(session, user)
            organisation_id = None
            if device:
                if org is None:
                    organisation = accounts.first_organisation(session, owner)
                else:
                    found = session.scalar(select(Organisation).where(Organisation.name == org))
                    member = found and session.scalar(
                        select(Membership).where(
                            Membership.user_id == owner.id,
                            Membership.organisation_id == found.id,
                        )
                    )
                    if found is None or member is None:
                        fail(f"--org: {user!r} is not a member of an organisation {org!r}")
                    organisation = found
                organisation_id = organisation.id
            made = accounts.create_token(
                session, owner, name=name, device=device, organisation_id=organisation_id
            )
            kind = "device" if device else "personal"
            typer.echo(
                f"{kind} token {made.row.name!r} (id {made.row.id}) for {owner.username!r}; "
                "it is shown only now:",
                err=True,
            )
            typer.echo(made.token)
    except AccountError as exc:
        fail(str(exc))
    except SQLAlchemyError as exc:
        fail(f"database: {exc}")


def register(cli: typer.Typer) -> None:
    """Add the ``users`` and ``tokens`` groups to ``cli``."""
    users = typer.Typer(help="Manage accounts.", no_args_is_help=True)
    users.command("create")(users_create)
    cli.add_typer(users, name="users")
    tokens = typer.Typer(help="Manage API tokens.", no_args_is_help=True)
    tokens.command("create")(tokens_create)
    cli.add_typer(tokens, name="tokens")
