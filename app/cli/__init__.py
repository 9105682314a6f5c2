"""The ``tillpath`` command line (typer).

Each command group lives in its own module and registers itself here, so that ``tillpath plan``
does not pay for importing the web server.
"""

from __future__ import annotations

import sys
from typing import Annotated

import typer

from app.cli import accounts, batch, plan, server, simulate
from app.cli.common import EXIT_BAD_INPUT

cli = typer.Typer(
    name="tillpath",
    help="Plan, simulate and check tillage paths for autonomous walk-behind tractors.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _show_version(value: bool) -> None:
    if value:
        from importlib.metadata import version

        typer.echo(f"tillpath {version('tillpath')}")
        raise typer.Exit(0)


@cli.callback()
def _main_options(
    _version: Annotated[
        bool,
        typer.Option(
            "--version", is_eager=True, callback=_show_version, help="Print the version and exit."
        ),
    ] = False,
) -> None:
    """Plan, simulate and check tillage paths for autonomous walk-behind tractors."""


plan.register(cli)
simulate.register(cli)
server.register(cli)
accounts.register(cli)
batch.register(cli)


def main() -> None:
    """Entry point of the ``tillpath`` script.

    Usage errors (a missing file argument, a non-number where a number belongs) are printed
    as ``error: …`` with exit status 2, like the planner's own input errors.
    """
    # No arguments: the help, and success (product.md §10).
    args = sys.argv[1:] or ["--help"]
    try:
        result = cli(args=args, standalone_mode=False)
    except typer.Abort:
        typer.echo("aborted", err=True)
        sys.exit(130)
    except typer.TyperException as exc:
        # typer vendors click: its UsageError/BadParameter derive from TyperException.
        message = exc.format_message() if hasattr(exc, "format_message") else str(exc)
        typer.echo(f"error: {message}", err=True)
        sys.exit(getattr(exc, "exit_code", EXIT_BAD_INPUT))
    sys.exit(result if isinstance(result, int) else 0)
