"""Build hook: put the page's files, the npm libraries and the migrations inside the wheel.

Everything else about the package is in pyproject.toml. In a checkout the app reads
templates/, static/, node_modules/, migrations/ and alembic.ini where they are; a wheel carries
copies under ``app/_share/`` (see :mod:`app.resources`), so ``pip install tillpath-*.whl &&
tillpath serve`` works from any directory. The npm packages are those of package.json's
``dependencies``, as ``npm ci`` installed them: run it before building.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent
#: Files and folders of the checkout that the installed app needs.
SHARED = ("templates", "static", "migrations", "alembic.ini")
IGNORED = shutil.ignore_patterns("__pycache__", "*.pyc")


class BuildPyWithShare(build_py):
    """``build_py`` that also copies :data:`SHARED` and the npm packages into ``app/_share``."""

    def run(self) -> None:
        """Build the packages, then copy the shared files beside them (not when editable)."""
        super().run()
        if getattr(self, "editable_mode", False):
            return  # an editable install reads the checkout itself
        share = Path(self.build_lib) / "app" / "_share"
        shutil.rmtree(share, ignore_errors=True)
        share.mkdir(parents=True)
        for name in SHARED:
            source = ROOT / name
            if source.is_dir():
                shutil.copytree(source, share / name, ignore=IGNORED)
            else:
                shutil.copy2(source, share / name)
        packages = json.loads((ROOT / "package.json").read_text())["dependencies"]
        for package in packages:
            source = ROOT / "node_modules" / package
            if not (source / "package.json").is_file():
                raise SystemExit(
                    f"error: node_modules/{package} is missing: run `npm ci --ignore-scripts` "
                    "(or `make install`) before building the wheel"
                )
            shutil.copytree(source, share / "node_modules" / package, ignore=IGNORED)


setup(cmdclass={"build_py": BuildPyWithShare})
