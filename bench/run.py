"""Run every benchmark module and write ``docs/benchmarks.md``.

Each ``bench/bench_*.py`` module exposes ``run() -> str``, returning a Markdown section with
its figures and the budget they are held to. Sections appear in module-name order.
"""

from __future__ import annotations

import datetime as dt
import importlib
import os
import platform
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def machine_description() -> str:
    """Describe the machine the figures were measured on."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    try:
        mem_kb = int(Path("/proc/meminfo").read_text().split()[1])
        memory = f"{mem_kb / 1024 / 1024:.0f} GiB"
    except (OSError, ValueError, IndexError):
        memory = "unknown memory"
    try:
        commit = subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True
        ).stdout.strip()
    except OSError:
        commit = ""
    return (
        f"{cpu}, {os.cpu_count()} cores, {memory}; Python {platform.python_version()}; "
        f"{platform.system()} {platform.release()}; commit {commit or 'uncommitted'}"
    )


def main() -> None:
    """Run the benchmarks named on the command line (default: all) and write the report."""
    wanted = sys.argv[1:]
    modules = sorted(p.stem for p in (ROOT / "bench").glob("bench_*.py"))
    if wanted:
        modules = [m for m in modules if any(w in m for w in wanted)]
    sections = []
    for name in modules:
        print(f"running {name} …", file=sys.stderr, flush=True)
        module = importlib.import_module(f"bench.{name}")
        section = module.run()
        print(section, flush=True)
        sections.append(section)
    if wanted:
        return  # a partial run prints but does not overwrite the report
    report = [
        "# Benchmarks",
        "",
        "Measured by `make bench` (`python -m bench.run`), which rewrites this file.",
        f"Machine: {machine_description()}.",
        f"Date: {dt.date.today().isoformat()}.",
        "",
        *sections,
    ]
    (ROOT / "docs" / "benchmarks.md").write_text("\n".join(report).rstrip() + "\n")


if __name__ == "__main__":
    main()
