"""``tillpath serve`` and ``tillpath db upgrade``: run the web app and migrate its database."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from app.cli.common import fail


def upgrade(url: str | None = None) -> str:
    """Migrate the database at ``url`` (default: the settings') to the newest revision.

    Returns
    -------
    str
        The URL migrated, with any password hidden.
    """
    from sqlalchemy.engine import make_url
    from sqlalchemy.exc import SQLAlchemyError

    from app.db import upgrade_database
    from app.settings import get_settings

    url = url or get_settings().database_url
    shown = make_url(url).render_as_string(hide_password=True)
    try:
        upgrade_database(url)
    except (SQLAlchemyError, OSError) as exc:
        fail(f"database: cannot migrate {shown}: {exc}")
    return shown


def _needs_first_account() -> bool:
    """Tell whether the configured database has no user yet."""
    from sqlalchemy.exc import SQLAlchemyError
    from sqlalchemy.orm import Session

    from app.accounts import user_count
    from app.db import get_engine
    from app.settings import get_settings

    try:
        with Session(get_engine(get_settings().database_url)) as session:
            return user_count(session) == 0
    except SQLAlchemyError:
        return False


def check_tls_files(certfile: Path | None, keyfile: Path | None) -> None:
    """Refuse a half-given or unreadable certificate pair before the server starts.

    Raises
    ------
    typer.Exit
        Through :func:`app.cli.common.fail` (``error: …``, status 2).
    """
    if (certfile is None) != (keyfile is None):
        fail("--certfile and --keyfile: give both to serve HTTPS, or neither")
    for option, path in (("--certfile", certfile), ("--keyfile", keyfile)):
        if path is not None and not path.is_file():
            fail(f"{option}: {path} is not a file")
    if certfile is not None and keyfile is not None:
        import ssl

        try:
            ssl.create_default_context(ssl.Purpose.CLIENT_AUTH).load_cert_chain(certfile, keyfile)
        except (ssl.SSLError, OSError) as exc:
            fail(f"--certfile/--keyfile: cannot use them for HTTPS ({exc})")


def register(cli: typer.Typer) -> None:
    """Add ``serve`` and the ``db`` group to ``cli``."""
    db = typer.Typer(help="Manage the database.", no_args_is_help=True)

    @db.command("upgrade")
    def db_upgrade() -> None:
        """Apply the migrations to TILLPATH_DATABASE_URL (default: ./data/tillpath.db)."""
        shown = upgrade()
        typer.echo(f"database {shown} is up to date", err=True)

    cli.add_typer(db, name="db")

    @cli.command()
    def serve(
        host: Annotated[str, typer.Option(help="Address to listen on.")] = "127.0.0.1",
        port: Annotated[int, typer.Option(min=1, max=65535, help="TCP port.")] = 8000,
        workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 1,
        access_log: Annotated[
            bool, typer.Option("--access-log/--no-access-log", help="Log every request.")
        ] = True,
        certfile: Annotated[
            Path | None,
            typer.Option(help="TLS certificate (PEM) to serve HTTPS: phones' GPS needs it."),
        ] = None,
        keyfile: Annotated[
            Path | None, typer.Option(help="Private key (PEM) of --certfile.")
        ] = None,
    ) -> None:
        """Migrate the database, then serve the map page and the API (uvicorn).

        Background jobs run on a local Dask cluster started with the server (one worker
        process per core; TILLPATH_DASK_WORKERS), or on the cluster TILLPATH_DASK_SCHEDULER
        names.
        """
        import os

        import uvicorn

        from app.budget import warm_up
        from app.serving import UvicornChangedError, uvicorn_options
        from app.settings import get_settings

        check_tls_files(certfile, keyfile)
        try:
            options = uvicorn_options(get_settings())
        except UvicornChangedError as exc:
            fail(f"{exc}; install the locked version (pip install -r requirements.lock)")
        from app.local_cluster import start_local_cluster

        # The fork server and the planner's kernels load while the database migrates.
        warming = warm_up()
        shown = upgrade()
        scheme = "https" if certfile else "http"
        typer.echo(f"database {shown} is up to date; serving on {scheme}://{host}:{port}", err=True)
        if host in ("0.0.0.0", "::"):
            typer.echo(
                f"open {scheme}://<this computer's address>:{port} on a phone on the same network",
                err=True,
            )
        if _needs_first_account():
            typer.echo(
                f"no account yet: open {scheme}://{host}:{port}/ to create the first one "
                "(or run `tillpath users create NAME --password-stdin`)",
                err=True,
            )
        if warming.is_alive():
            typer.echo("loading the planner (after an install it compiles, once: ~10 s)", err=True)
        warming.join()  # so that no request waits for it
        cluster = None
        settings = get_settings()
        if workers > 1:
            # uvicorn spawns each worker afresh: each warms its own fork server and kernels
            # (from the cache this process just filled) before it answers.
            os.environ["TILLPATH_WARM_UP_PLANNER"] = "true"
        if workers > 1 and settings.dask_scheduler is None:
            # Several web processes share one local cluster, started (and stopped) here.
            cluster = start_local_cluster(settings.dask_workers or os.cpu_count() or 1)
            os.environ["TILLPATH_DASK_SCHEDULER"] = cluster.scheduler_address
        try:
            uvicorn.run(
                "app.main:create_app",
                factory=True,
                host=host,
                port=port,
                workers=workers,
                access_log=access_log,
                proxy_headers=True,
                ssl_certfile=str(certfile) if certfile else None,
                ssl_keyfile=str(keyfile) if keyfile else None,
                **options,
            )
        finally:
            if cluster is not None:
                cluster.close()
