"""Random simple non-convex polygons with holes, in local metres, for property tests.

The seeded shapes themselves are :mod:`bench.shapes`' (the benches draw the same ones); this
module adds the Hypothesis strategy over them and passes them on.
"""

from __future__ import annotations

import math

from hypothesis import strategies as st
from shapely import Polygon

from bench.shapes import random_convex_jobs as random_convex_jobs
from bench.shapes import star_field as star_field


@st.composite
def fields_with_holes(
    draw: st.DrawFn, *, min_vertices: int = 3, max_vertices: int = 40, max_holes: int = 3
) -> Polygon:
    """A star-shaped (so simple), usually non-convex polygon of 0.2–20 ha with 0–3 holes."""
    n = draw(st.integers(min_vertices, max_vertices))
    seed = draw(st.integers(0, 2**32 - 1))
    size_m = 10 ** draw(st.floats(math.log10(50.0), math.log10(500.0)))
    return star_field(n, seed, size_m, draw(st.integers(0, max_holes)))
