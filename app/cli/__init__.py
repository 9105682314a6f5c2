"""The ``tillpath`` command line (typer).

Each command group lives in its own module and registers itself here, so that ``tillpath plan``
does not pay for importing the web server.
"""

from __future__ import annotations

import typer

from app.cli import plan, server, simulate

cli = typer.Typer(
    name="tillpath",
    help="Plan, simulate and check tillage paths for autonomous walk-behind tractors.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
plan.register(cli)
simulate.register(cli)
server.register(cli)


def main() -> None:
    """Entry point of the ``tillpath`` script."""
    cli()
