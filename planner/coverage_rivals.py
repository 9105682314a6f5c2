"""Which more headings to decompose so that R5's best-covering heading is not missed.

The heading search (:mod:`planner.heading_search`) estimates every heading's coverage from the
field's ragged scan: the footprints' misses at slanted line ends. On a field of a few dozen
lines that figure can be off by more than the gap between headings (it knows nothing of the
cells, whose lines each start and end on their own sides, nor of the turns' pull-back at line
ends), so the few headings planned for length may all cover 1 pp less than the best 1° fixed
heading (issue 9 item 5). Decomposing a heading into cells (:func:`planner.cell_plans.
cover_heading`) measures its cells' coverage exactly, and :func:`planner.fitted_cells.
estimate_m2` takes the turns' pull-back off it: a far better figure, at a tenth of a
millisecond a heading on a real field.

So the error of the ragged estimate is *measured* on the headings decomposed anyway, and every
heading whose ragged figure, corrected by the largest error seen, could still beat the best
decomposed one is decomposed too, best-looking first, at most :data:`MAX_RIVALS` of them
(the budget). On a field of hundreds of lines the errors are a small share of the area and
few headings qualify; on a field of twenty lines most do, and the cap leaves some out: the
ragged figure ranks them poorly, so the best-covering 1° heading can still be missed there.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: At most this many headings are decomposed for coverage beyond those planned for length
#: (the budget: with 4, the 223 real fields took about 8–13 % more CPU; with 2, +0.7 % with
#: the hand tractor and +4.6 % with the small tractor).
MAX_RIVALS = 2


def ragged_deficit_m2(
    missed_m2: FloatArray,
    pieces: IntArray,
    turn_backs: IntArray,
    reach_m: float,
    interval_m: float,
) -> FloatArray:
    """Estimate, from the ragged scan, the area every heading's fitted lines leave [m²].

    The slanted ends' misses, and each turn's two pulled-back ends (``reach_m`` each, an
    interval wide): about one turn per line piece, less one per cell (a cell starts at a
    turn-back and ends at another, so about half the turn-backs).
    """
    turns = np.maximum(pieces - turn_backs / 2.0, 0.0)
    return np.asarray(missed_m2 + 2.0 * reach_m * interval_m * turns)


def coverage_rivals(
    ragged_m2: FloatArray,
    known: dict[int, float],
    *,
    slack_m2: float = 0.0,
    limit: int | None = None,
) -> list[int]:
    """Headings not in ``known`` that could cover more than the best of ``known``.

    Parameters
    ----------
    ragged_m2 : ndarray, shape (A,)
        :func:`ragged_deficit_m2` of every heading [m²].
    known : dict
        Heading index -> its area left uncovered as measured on its cells [m²] (the
        decomposed headings; at least one).
    limit : int, optional
        At most this many are returned (default :data:`MAX_RIVALS`).

    Returns
    -------
    list of int
        Indices, the lowest ragged deficit first (ties: the lower index).

    Examples
    --------
    The ragged figure overestimated heading 0's deficit by 30 m² and heading 1's by 10 m²: the
    others' may be overestimated as much, so heading 2 (ragged 120 m², so maybe 90 m²) could
    beat the best known 95 m²; heading 3 (ragged 200 m², at least 170 m²) could not.

    >>> coverage_rivals(np.array([130.0, 105.0, 120.0, 200.0]), {0: 100.0, 1: 95.0})
    [2]
    """
    indices = np.fromiter(known, dtype=np.int64, count=len(known))
    measured = np.fromiter(known.values(), dtype=float, count=len(known))
    over_m2 = float(np.max(ragged_m2[indices] - measured))
    best_m2 = float(measured.min())
    hopeful = ragged_m2 - over_m2 < best_m2 + slack_m2
    hopeful[indices] = False
    candidates = np.flatnonzero(hopeful)
    order = np.lexsort((candidates, ragged_m2[candidates]))
    return [int(i) for i in candidates[order][: MAX_RIVALS if limit is None else limit]]
