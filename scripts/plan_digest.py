"""Hash many plans, to show that a speed change leaves every plan as it was.

``python scripts/plan_digest.py OUT.json [--quick]`` plans a fixed set of fields and writes one
SHA-256 per plan (of its GeoJSON, as the API writes it, or of the error it raised);
``python scripts/plan_digest.py --compare A.json B.json`` lists the plans that differ and exits
1 if any does. Typical use: digest ``main``, make the change, digest again, compare.

The set: the paper field at 1, 1.5, 2, 2.5 and 4 m × every vehicle preset × every pattern;
the 223 real fields at 4 m × ``hand_tractor`` and ``small_tractor``; 60 small plots at 10 m;
and (without ``--quick``) the wavy, 50-hole and comb fields of ``bench_planner``.

The GeoJSON rounds to 1e-9 degrees and to millimetres, so a last-bit difference in a float is
not seen here; the kernel tests (``tests/planner/test_*kernels.py``) compare bits.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Callable, Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from pydantic import TypeAdapter  # noqa: E402

GEOJSON_JSON = TypeAdapter(dict)


def _cases(quick: bool) -> Iterator[tuple[str, Callable[[], object]]]:
    from bench.bench_fields import DATASETS, INTERVAL_M, load
    from bench.bench_planner import PAPER, comb_field, holes_field, wavy_field
    from bench.common import small_quadrilaterals
    from planner import parse_field_geojson, plan_coverage
    from planner.vehicles import PRESETS

    spec = parse_field_geojson(json.loads(PAPER.read_text()))
    for interval in (1.0, 1.5, 2.0, 2.5, 4.0):
        for vehicle in PRESETS:
            for pattern in ("boustrophedon", "snake", "spiral"):
                yield (
                    f"paper {interval} {vehicle} {pattern}",
                    lambda i=interval, v=vehicle, p=pattern: plan_coverage(
                        spec.field_lonlat,
                        interval_m=i,
                        start_lonlat=spec.start_lonlat,
                        finish_lonlat=spec.finish_lonlat,
                        vehicle=v,
                        pattern=p,
                    ),
                )
    for vehicle in ("hand_tractor", "small_tractor"):
        for name in DATASETS:
            for field_id, field in load(name):
                yield (
                    f"{vehicle} {field_id}",
                    lambda f=field, v=vehicle: plan_coverage(f, interval_m=INTERVAL_M, vehicle=v),
                )
    for index, quad in enumerate(small_quadrilaterals(60)):
        yield f"plot {index}", lambda q=quad: plan_coverage(q, interval_m=10.0)
    if not quick:
        for name, make in (("wavy", wavy_field), ("holes", holes_field), ("comb", comb_field)):
            yield name, lambda m=make: plan_coverage(m(), interval_m=4.0)


def digest(quick: bool) -> dict[str, str]:
    """Case name -> SHA-256 of its GeoJSON (or of its error's type and text)."""
    from planner.export import plan_to_geojson

    out: dict[str, str] = {}
    for name, plan in _cases(quick):
        try:
            data = GEOJSON_JSON.dump_json(plan_to_geojson(plan()))  # type: ignore[arg-type]
        except ValueError as error:
            data = f"{type(error).__name__}: {error}".encode()
        out[name] = hashlib.sha256(data).hexdigest()
    return out


def compare(a: dict[str, str], b: dict[str, str]) -> int:
    """Print the cases that differ or are in one digest only; the count of them."""
    differ = sorted(k for k in a.keys() & b.keys() if a[k] != b[k])
    one_side = sorted(a.keys() ^ b.keys())
    for key in differ:
        print(f"differs: {key}")
    for key in one_side:
        print(f"in one digest only: {key}")
    print(
        f"{len(a.keys() & b.keys())} plans compared, {len(differ)} differ, "
        f"{len(one_side)} in one digest only"
    )
    return len(differ) + len(one_side)


def main(argv: list[str]) -> int:
    """Digest or compare, as the module's docstring says; the exit status."""
    if argv[:1] == ["--compare"] and len(argv) == 3:
        a, b = (json.loads(Path(p).read_text()) for p in argv[1:])
        return 1 if compare(a, b) else 0
    if len(argv) in (1, 2) and argv[1:] in ([], ["--quick"]):
        result = digest(quick=argv[1:] == ["--quick"])
        Path(argv[0]).write_text(json.dumps(result, indent=0, sort_keys=True))
        print(f"{len(result)} plans hashed into {argv[0]}")
        return 0
    print(__doc__, file=sys.stderr)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
