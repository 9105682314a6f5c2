"""Where the app's own files are: inside the installed wheel, or in the checkout.

A wheel carries templates/, static/, the npm libraries (node_modules/), migrations/ and
alembic.ini under ``app/_share/`` (copied there by setup.py's build hook); a checkout (and an
editable install) has them beside the ``app`` package.
"""

from __future__ import annotations

from functools import lru_cache
from importlib.resources import files
from pathlib import Path


@lru_cache(maxsize=1)
def resource_root() -> Path:
    """Return the folder that holds ``templates/``, ``static/`` and ``node_modules/``."""
    package = Path(str(files("app")))
    share = package / "_share"
    if (share / "templates").is_dir():
        return share
    return package.parent
