"""The built wheel installs into a fresh venv and serves the page from any directory."""

from __future__ import annotations

import os
import subprocess
import sys
import sysconfig
import time
import urllib.request
from pathlib import Path

import pytest

from app.testing import REPO, free_port

pytestmark = pytest.mark.slow


def get(url: str) -> tuple[int, bytes]:
    with urllib.request.urlopen(url, timeout=5) as response:
        return response.status, response.read()


def test_wheel_installs_into_a_fresh_venv_and_serves_the_page(tmp_path: Path) -> None:
    dist = tmp_path / "dist"
    subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(dist), str(REPO)],
        check=True,
        timeout=180,
    )
    (wheel,) = dist.glob("tillpath-*.whl")
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    python = venv / "bin" / "python"
    # The dependencies come from this environment (installing them again from the lock would
    # take minutes); the project itself only from the wheel. Paths listed in a .pth file are
    # added without running their own .pth files, so this checkout's editable hook stays out.
    site = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    Path(site, "tillpath-test-deps.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    subprocess.run(
        [str(python), "-m", "pip", "install", "--quiet", "--no-deps", str(wheel)],
        check=True,
        timeout=120,
    )
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    where = subprocess.run(
        [str(python), "-c", "import app; print(app.__file__)"],
        cwd=elsewhere,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    assert where.startswith(site), where
    # As docs/deploy.md advises after an install: compile the planner's numba kernels now
    # (about 9 s of CPU, once), into the installed package's cache, rather than while
    # `tillpath serve` starts below (it loads them before it answers).
    subprocess.run(
        [str(python), "-c", "from planner.warm_up import warm_up; warm_up()"],
        cwd=elsewhere,
        check=True,
        timeout=600,
        # The package's own cache is the one checked below, wherever NUMBA_CACHE_DIR points.
        env={k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"},
    )
    assert list(Path(site, "planner", "__pycache__").glob("kernels.*.nbi")), "no kernel cache"
    version = subprocess.run(
        [str(venv / "bin" / "tillpath"), "--version"], capture_output=True, text=True, check=True
    )
    assert version.stdout.strip() == "tillpath 0.1.0"

    port = free_port()
    env = {
        **os.environ,
        "TILLPATH_DATABASE_URL": f"sqlite:///{tmp_path / 'wheel.db'}",
        "TILLPATH_DASK_WORKERS": "1",
    }
    log = (tmp_path / "serve.log").open("wb")
    server = subprocess.Popen(
        [str(venv / "bin" / "tillpath"), "serve", "--port", str(port)],
        cwd=elsewhere,
        env=env,
        stdout=log,
        stderr=log,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:
            assert server.poll() is None, (tmp_path / "serve.log").read_text()
            try:
                if get(f"{base}/api/health")[0] == 200:
                    break
            except OSError:
                pass
            assert time.monotonic() < deadline, (tmp_path / "serve.log").read_text()
            time.sleep(0.3)
        status, page = get(f"{base}/")
        assert status == 200 and b'id="map"' in page
        for path in ("/static/js/map.js", "/vendor/leaflet/leaflet.js", "/docs"):
            assert get(base + path)[0] == 200, path
    finally:
        server.terminate()
        server.wait(timeout=30)
        log.close()
