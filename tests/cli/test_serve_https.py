"""``tillpath serve --certfile --keyfile``: HTTPS, which a phone's GPS needs (product.md §6)."""

from __future__ import annotations

import os
import shutil
import ssl
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from app.testing import REPO, free_port

TILLPATH = [sys.executable, "-c", "from app.cli import main; main()"]


def self_signed(tmp_path: Path) -> tuple[Path, Path]:
    """A throw-away certificate for 127.0.0.1, made by openssl (Debian's)."""
    openssl = shutil.which("openssl")
    if openssl is None:
        pytest.fail("openssl is needed to make a test certificate (apt-get install openssl)")
    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(
        [openssl, "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
         "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
         "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True, timeout=60,
    )  # fmt: skip
    return cert, key


def test_serve_with_a_certificate_answers_https(tmp_path: Path) -> None:
    cert, key = self_signed(tmp_path)
    port = free_port()
    env = {**os.environ, "TILLPATH_DATABASE_URL": f"sqlite:///{tmp_path / 't.db'}"}
    command = [*TILLPATH, "serve", "--port", str(port), "--certfile", str(cert)]
    command += ["--keyfile", str(key), "--no-access-log"]
    log = (tmp_path / "serve.log").open("wb")
    process = subprocess.Popen(command, cwd=REPO, env=env, stdout=log, stderr=log)
    context = ssl.create_default_context(cafile=str(cert))
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                url = f"https://127.0.0.1:{port}/api/health"
                with urllib.request.urlopen(url, context=context, timeout=2) as answer:
                    assert answer.status == 200
                    break
            except (OSError, ssl.SSLError):
                assert process.poll() is None, (tmp_path / "serve.log").read_text()
                assert time.monotonic() < deadline, "no HTTPS answer in 60 s"
                time.sleep(0.3)
        with urllib.request.urlopen(
            f"https://127.0.0.1:{port}/", context=context, timeout=5
        ) as page:
            assert page.status == 200
    finally:
        process.terminate()
        try:
            process.wait(timeout=15)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        log.close()
    assert "serving on https://" in (tmp_path / "serve.log").read_text()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--certfile", "cert.pem"], "--certfile and --keyfile: give both"),
        (["--certfile", "missing.pem", "--keyfile", "missing.pem"], "is not a file"),
        (["--certfile", "junk.pem", "--keyfile", "junk.pem"], "cannot use them for HTTPS"),
    ],
)
def test_serve_refuses_bad_certificates(tmp_path: Path, args: list[str], message: str) -> None:
    (tmp_path / "cert.pem").write_text("x")
    (tmp_path / "junk.pem").write_text("not a certificate")
    result = subprocess.run(
        [*TILLPATH, "serve", *args],
        capture_output=True, text=True, cwd=tmp_path, timeout=60,
        env={**os.environ, "TILLPATH_DATABASE_URL": f"sqlite:///{tmp_path / 't.db'}"},
    )  # fmt: skip
    assert result.returncode == 2
    assert result.stderr.startswith("error: ") and message in result.stderr
    assert "Traceback" not in result.stderr
