"""The line-angle search (R5): which headings to try, and which (heading, variant) wins.

Coverage comes first: a heading is a candidate only if its coverage is within
:data:`COVERAGE_SLACK` of the best candidate's, and among those the objective decides. The
coarse candidates (every edge direction and a 1° sweep) are then refined locally around the
best few at 0.1°, so a plan is as short as a 0.1° brute force would find.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from planner.errors import PlanTooLargeError
from planner.ordering import VariantLengths
from planner.types import Objective

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: Step of the fine sweep of headings [deg], on top of every edge direction.
SWEEP_STEP_DEG = 1.0
#: At most this many edge directions are tried, the longest edges' first: a boundary traced
#: from GPS has many short edges whose directions are noise.
MAX_EDGE_HEADINGS = 180
#: A plan with more tillage lines than this is refused (product.md §3).
MAX_LINES = 20_000
#: Path lengths closer than this count as equal, so ties break the same way every time [m].
_TIE_M = 1e-6
#: A heading whose coverage is more than this below the best candidate's is never chosen
#: (R5: 0.2 percentage points).
COVERAGE_SLACK = 0.002
#: Local refinement: the best this many distinct eligible headings are swept ...
REFINE_SEEDS = 16
#: ... at this step [deg], nine on each side (filling the 1° sweep).
REFINE_STEP_DEG = 0.1
#: ... and so are the best-covering this many, for coverage (the rule's bound).
COVERAGE_SEEDS = 3
#: Rounds of refinement: the first around the seeds, the next around a winner that moved.
REFINE_ROUNDS = 3
#: Seeds may be this far below the best coverage (the sweep between them may not be).
SEED_SLACK = 0.007
#: Seeds of one refinement round are at least this far apart [deg].
_SEED_GAP_DEG = 1.5
#: The refinement sweep around a centre, in steps of REFINE_STEP_DEG.
_OFFSETS = REFINE_STEP_DEG * np.arange(-9, 10)


def candidate_headings(ring_xy: FloatArray, fixed_deg: float | None = None) -> FloatArray:
    """Headings to try: every edge direction of the ring plus a 1° sweep, in [0, 180).

    A ring of more than :data:`MAX_EDGE_HEADINGS` edges contributes its longest edges'
    directions only.

    Parameters
    ----------
    ring_xy : ndarray, shape (m, 2)
        The field's exterior, local [m], not closed.
    fixed_deg : float or None
        If given, only this heading.

    Returns
    -------
    ndarray
        Sorted, unique headings [deg].

    Examples
    --------
    >>> ring = np.array([[0.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    >>> h = candidate_headings(ring)
    >>> len(h), 45.0 in h, 0.0 in h
    (180, True, True)
    """
    if fixed_deg is not None:
        return np.array([float(fixed_deg)])
    nxt = np.concatenate([ring_xy[1:], ring_xy[:1]])  # np.roll(ring_xy, -1, axis=0), cheaper
    dx = nxt[:, 0] - ring_xy[:, 0]
    dy = nxt[:, 1] - ring_xy[:, 1]
    length = np.hypot(dx, dy)
    longest = np.argsort(-length, kind="stable")[:MAX_EDGE_HEADINGS]
    longest = longest[length[longest] > 0]
    edges = np.degrees(np.arctan2(dx[longest], dy[longest])) % 180.0
    sweep = np.arange(0.0, 180.0, SWEEP_STEP_DEG)
    headings = np.concatenate([sweep, edges.round(9) % 180.0])
    return _sorted_unique(headings)


def _sorted_unique(values: FloatArray) -> FloatArray:
    """``np.unique`` of finite headings: sorted, each value once.

    Its sort-and-compare path without the wrapper (a few hundred values: the wrapper's
    checks cost more than the work). The headings come from ``% 180.0`` and are never NaN
    nor ``-0.0``, so which of two equal values is kept does not show.
    """
    ordered = np.sort(values)
    keep = np.empty(len(ordered), dtype=bool)
    keep[:1] = True
    np.not_equal(ordered[1:], ordered[:-1], out=keep[1:])
    return ordered[keep]


def select_plan(
    lengths: VariantLengths | None,
    line_counts_per_heading: IntArray,
    objective: Objective,
    *,
    interval_m: float | None = None,
    eligible: npt.NDArray[np.bool_] | None = None,
    tied: FloatArray | None = None,
) -> tuple[int, int]:
    """Pick the (heading index, variant index) the objective prefers.

    ``shortest_path`` minimises the whole path; ``fewest_lines`` minimises the line count,
    then the path. Ties go to the first heading and variant, so the choice is deterministic.
    Headings that need more than :data:`MAX_LINES` lines, and those not ``eligible`` (if
    given: the coverage rule of R5), are never chosen. ``tied``: :func:`tied_lengths` of
    ``lengths``, if the caller has it (then ``lengths`` may be None).

    Raises
    ------
    PlanTooLargeError
        If every heading needs more than :data:`MAX_LINES` lines.

    Examples
    --------
    >>> from planner.ordering import VariantLengths
    >>> lengths = VariantLengths(np.array([10.0, 9.0]), np.zeros((2, 4)), np.array(
    ...     [[1.0, 2.0, 3.0, 4.0], [5.0, 5.0, 5.0, 0.5]]))
    >>> select_plan(lengths, np.array([3, 4]), "shortest_path")
    (1, 3)
    >>> select_plan(lengths, np.array([3, 4]), "fewest_lines")
    (0, 0)
    """
    counts = line_counts_per_heading
    if counts.min() > MAX_LINES:
        at = f"at {interval_m:g} m " if interval_m else ""
        raise PlanTooLargeError(
            "interval_m",
            f"{at}the field needs at least {int(counts.min()):,} tillage lines; tillpath "
            f"plans at most {MAX_LINES:,}: choose a wider interval or a smaller field",
        )
    if tied is None:
        assert lengths is not None, "select_plan needs the lengths or their tied_lengths"
        tied = tied_lengths(lengths)
    total = tied
    allowed = counts <= MAX_LINES
    if eligible is not None and (allowed & eligible).any():
        allowed = allowed & eligible
    total = np.where(allowed[:, None], total, np.inf)
    if objective == "fewest_lines":
        fewest = counts == counts[allowed].min()
        total = np.where(fewest[:, None], total, np.inf)
    flat = int(total.argmin())
    return flat // 4, flat % 4


def tied_lengths(lengths: VariantLengths) -> FloatArray:
    """Path lengths rounded to :data:`_TIE_M`, so that ties break the same way every time."""
    # Array methods, not the np.* wrappers (the same operation, less call overhead): the
    # search rounds and reduces a few hundred values at a time, a dozen times.
    rounded: FloatArray = (lengths.total / _TIE_M).round() * _TIE_M
    return rounded


#: ``lengths(headings) -> (path lengths of the four variants, line counts)``.
LengthScorer = Callable[[FloatArray], tuple[VariantLengths, IntArray]]
#: ``coverage(headings) -> coverage ratios``.
CoverageScorer = Callable[[FloatArray], FloatArray]


@dataclass(frozen=True, slots=True)
class HeadingChoice:
    """The heading the search settled on.

    Attributes
    ----------
    heading_deg : float
    variant : int
        Index into :data:`planner.ordering.VARIANTS`.
    coverage_ratio : float
        Its coverage, as the scorer gave it.
    coverage_given_up_pp : float
        How far below the best candidate's coverage it is, in percentage points (≥ 0).
    alternatives : tuple of (float, int)
        Other (heading, variant) pairs worth planning in full when the scorer's coverage is
        not the plan's (a vehicle's pulled-back line ends): the best-covering scored
        headings, at least :data:`_SEED_GAP_DEG` apart, best first.
    line_count : int
        Lines at the chosen heading (0 if not known).
    alternative_line_counts : tuple of int
        Lines at each alternative.
    alternative_coverage : tuple of float
        Each alternative's coverage, as the scorer gave it.
    scored_headings : ndarray or None
        Every heading the search scored [deg] (the coarse candidates and the refined ones).
    scored_coverage : ndarray or None
        Their coverage as the scorer gave it; NaN where it was not needed (scored for length
        only) or the heading needs more than :data:`MAX_LINES` lines.
    scored_variants : ndarray or None
        The shortest variant at each.
    scored_lengths : ndarray or None
        The shortest variant's path length at each, as the scorer gave it and rounded as the
        search ranks them [m].
    scored_line_counts : ndarray or None
        Lines at each.
    """

    heading_deg: float
    variant: int
    coverage_ratio: float
    coverage_given_up_pp: float
    alternatives: tuple[tuple[float, int], ...] = ()
    line_count: int = 0
    alternative_line_counts: tuple[int, ...] = ()
    alternative_coverage: tuple[float, ...] = ()
    scored_headings: FloatArray | None = None
    scored_coverage: FloatArray | None = None
    scored_variants: IntArray | None = None
    scored_lengths: FloatArray | None = None
    scored_line_counts: IntArray | None = None


def coverage_eligible(coverage: FloatArray) -> npt.NDArray[np.bool_]:
    """Headings whose coverage is within :data:`COVERAGE_SLACK` of the best (R5).

    Examples
    --------
    >>> coverage_eligible(np.array([0.998, 0.955, 0.9965, 0.9959])).tolist()
    [True, False, True, False]
    """
    return np.asarray(coverage >= coverage.max() - COVERAGE_SLACK - 1e-12)


def search_headings(
    lengths_of: LengthScorer,
    coverage_of: CoverageScorer,
    headings_deg: FloatArray,
    objective: Objective,
    *,
    interval_m: float | None = None,
    refine: bool = True,
) -> HeadingChoice:
    """Choose the heading and variant: coverage first, then ``objective``; refined locally.

    Every coarse candidate is scored for length and coverage; the best few eligible ones
    (:func:`coverage_eligible`) are then swept at :data:`REFINE_STEP_DEG`; the refined headings
    that would beat the coarse choice are scored for coverage too, and the rule holds over
    every heading scored.

    Parameters
    ----------
    lengths_of, coverage_of : callable
        Score an array of headings: path lengths of the four variants and line counts; and
        coverage ratios.
    headings_deg : ndarray
        The coarse candidates (:func:`candidate_headings`).
    objective : {"shortest_path", "fewest_lines"}
    interval_m : float, optional
        For the error message of a plan too large.
    refine : bool
        Sweep finer around the best candidates (off for a fixed heading).

    Returns
    -------
    HeadingChoice

    Raises
    ------
    PlanTooLargeError
        If every heading needs more than :data:`MAX_LINES` lines.

    Examples
    --------
    Path length is least at 37.2°, coverage the same everywhere: the 1° sweep finds 37°, the
    refinement 37.2°.

    >>> from planner.ordering import VariantLengths
    >>> def lengths_of(h):
    ...     total = 100.0 + np.abs(h - 37.2)
    ...     return VariantLengths(total, np.zeros((len(h), 4)), np.zeros((len(h), 4))), np.full(
    ...         len(h), 3)
    >>> choice = search_headings(lengths_of, lambda h: np.ones(len(h)), np.arange(0.0, 180.0),
    ...                          "shortest_path")
    >>> round(choice.heading_deg, 6), choice.coverage_given_up_pp
    (37.2, 0.0)
    """
    headings = np.asarray(headings_deg, dtype=float)
    lengths, counts = lengths_of(headings)
    tied = tied_lengths(lengths)  # rounded once: every pick below reads them
    least = _least(tied)
    # One heading (a fixed angle) gives nothing up, whatever its coverage.
    coverage = coverage_of(headings) if len(headings) > 1 else np.ones(1)
    affordable = counts <= MAX_LINES
    eligible = affordable & coverage_eligible(np.where(affordable, coverage, -np.inf))
    best, variant = select_plan(
        lengths, counts, objective, interval_m=interval_m, eligible=eligible, tied=tied
    )
    best_coverage = float(coverage[affordable].max()) if affordable.any() else 0.0
    chosen = (float(headings[best]), variant, float(coverage[best]))
    chosen_at = best  # its index in the pool: the pool only grows at its end
    if refine:
        # Seeds may fall a little short of the rule: coverage varies fast between degrees.
        hopeful = affordable & (coverage >= best_coverage - SEED_SLACK)
        picked = _seeds(least, counts, hopeful, headings, objective, REFINE_SEEDS)
        # The rule's bound is the best coverage, which also peaks between the coarse
        # headings: the first round sweeps round the best-covering one too, for coverage.
        by_coverage = np.where(affordable, coverage, -np.inf)
        tops = _spread(np.lexsort((headings, -by_coverage)), headings, affordable, COVERAGE_SEEDS)
        top_grid = (headings[tops] / REFINE_STEP_DEG).round() * REFINE_STEP_DEG
        # Repeats are harmless: the sweep round them is made unique below.
        centres = np.concatenate([[headings[best]], top_grid, headings[picked]])
        pool = _Pool(headings, counts, coverage, tied, least)
        for round_ in range(REFINE_ROUNDS):
            # On the 0.1° grid (an edge direction's neighbours too), around each centre.
            grid = (centres / REFINE_STEP_DEG).round() * REFINE_STEP_DEG
            near = ((grid[:, None] + _OFFSETS).ravel() % 180.0).round(9)
            near = _sorted_unique(near)  # then those not scored yet (np.setdiff1d, cheaper)
            # A set of plain floats, not np.isin: a few hundred values, and isin sorts both.
            scored = set(pool.headings.tolist())
            near = np.array([h for h in near.tolist() if h not in scored], dtype=float)
            near_lengths, near_counts = lengths_of(near) if len(near) else _no_scores(pool)
            pool = pool.extend(near, near_lengths, near_counts, np.full(len(near), np.nan))
            # Coverage for every scored heading that would beat the choice (the shortest
            # headings often trade coverage for length: the constrained optimum sits on the
            # coverage bound), also those a previous round scored for length only.
            key = _objective_key(pool.least, pool.counts, objective)
            wanted = np.isnan(pool.coverage) & (key < key[chosen_at])
            if round_ == 0:
                # Within the sweep of a best-covering heading: column by column, as the least
                # gap along an axis of a few costs more (finite gaps: min <= t iff any <= t).
                close = np.zeros(len(pool.headings), dtype=bool)
                for top in top_grid.tolist():
                    gap = np.abs((pool.headings - top + 90.0) % 180.0 - 90.0)
                    close |= gap <= 9.5 * REFINE_STEP_DEG
                wanted |= np.isnan(pool.coverage) & close
            if not wanted.any():
                break
            pool.coverage[wanted] = coverage_of(pool.headings[wanted])
            best_coverage = max(best_coverage, float(np.nanmax(pool.coverage)))
            ok = (pool.counts <= MAX_LINES) & (
                pool.coverage >= best_coverage - COVERAGE_SLACK - 1e-12
            )
            i, variant = select_plan(None, pool.counts, objective, eligible=ok, tied=pool.tied)
            moved = float(pool.headings[i]) != chosen[0]
            chosen = (float(pool.headings[i]), variant, float(pool.coverage[i]))
            chosen_at = i
            if not moved:
                break
            centres = np.array([chosen[0]])  # re-centre on a refined winner
    else:
        pool = _Pool(headings, counts, coverage, tied, least)
    alternatives, at = _best_covering(pool, objective, chosen[0])
    given_up = max(best_coverage - chosen[2], 0.0) * 100.0
    alternative_counts = tuple(int(pool.counts[i]) for i in at)
    alternative_coverage = tuple(float(pool.coverage[i]) for i in at)
    return HeadingChoice(
        chosen[0],
        chosen[1],
        chosen[2],
        given_up,
        alternatives,
        int(pool.counts[chosen_at]),
        alternative_counts,
        alternative_coverage,
        pool.headings,
        np.where(pool.counts <= MAX_LINES, pool.coverage, np.nan),
        pool.tied.argmin(axis=1),  # as of the rounded lengths: × _TIE_M keeps their order
        pool.least,
        pool.counts,
    )


#: Alternatives :func:`search_headings` offers for a re-check with the plan's own coverage.
ALTERNATIVES = 3


def _best_covering(
    pool: _Pool, objective: Objective, chosen_deg: float
) -> tuple[tuple[tuple[float, int], ...], list[int]]:
    """Return the best-covering scored headings, a seed gap apart, each with its best variant.

    And their indices in the pool.
    """
    coverage = np.where(
        (pool.counts <= MAX_LINES) & np.isfinite(pool.coverage), pool.coverage, -np.inf
    )
    total = pool.tied
    order = np.lexsort(
        (pool.headings, _objective_key(pool.least, pool.counts, objective), -coverage)
    )
    picked = _spread(order, pool.headings, np.isfinite(coverage), ALTERNATIVES)
    return tuple((float(pool.headings[i]), int(total[i].argmin())) for i in picked), picked


def _spread(
    order: IntArray, headings: FloatArray, usable: npt.NDArray[np.bool_], k: int
) -> list[int]:
    """Return the first ``k`` usable indices of ``order``, each a seed gap from those before.

    Plain floats: there are hundreds of candidates but only a few picks.
    """
    picked: list[int] = []
    taken: list[float] = []
    heading_of = headings.tolist()
    ok = usable.tolist()
    for i in order.tolist():
        if not ok[i] or len(picked) == k:
            break
        h = heading_of[i]
        for t in taken:  # a loop, not all(...): no generator per candidate
            if not abs((t - h + 90.0) % 180.0 - 90.0) >= _SEED_GAP_DEG:
                break
        else:
            picked.append(i)
            taken.append(h)
    return picked


@dataclass(frozen=True, slots=True)
class _Pool:
    """Every heading scored so far; coverage NaN where it was not needed.

    Their lengths only as :func:`tied_lengths` (all the picks read).
    """

    headings: FloatArray
    counts: IntArray
    coverage: FloatArray
    tied: FloatArray  # tied_lengths of the scorer's lengths
    least: FloatArray  # _least(tied)

    def extend(
        self, headings: FloatArray, lengths: VariantLengths, counts: IntArray, coverage: FloatArray
    ) -> _Pool:
        tied = tied_lengths(lengths)
        return _Pool(
            np.concatenate([self.headings, headings]),
            np.concatenate([self.counts, counts]),
            np.concatenate([self.coverage, coverage]),
            np.concatenate([self.tied, tied]),
            np.concatenate([self.least, _least(tied)]),
        )


def _no_scores(pool: _Pool) -> tuple[VariantLengths, IntArray]:
    """Empty scores, shaped like the pool's."""
    empty = np.zeros((0, 4))
    return VariantLengths(np.zeros(0), empty, empty), np.zeros(0, dtype=np.int64)


def _least(tied: FloatArray) -> FloatArray:
    """``tied.min(axis=1)`` of the four variants, as two ``np.minimum`` steps.

    The same numbers (the least of four is the least whichever pairs are compared first;
    NaN wins in both), at a quarter of the cost: a reduction along a length-4 axis costs
    ~12 µs on a few hundred headings, and the search needs it for every pool.
    """
    return np.minimum(np.minimum(tied[:, 0], tied[:, 1]), np.minimum(tied[:, 2], tied[:, 3]))


def _objective_key(least: FloatArray, counts: IntArray, objective: Objective) -> FloatArray:
    """Return what the objective minimises per heading: line count and length in one number.

    ``least``: :func:`_least` of :func:`tied_lengths`; rounding is monotone, so it is the
    least length per heading, rounded.
    """
    return objective_key(np.where(counts <= MAX_LINES, least, np.inf), counts, objective)


def objective_key(lengths_m: FloatArray, counts: IntArray, objective: Objective) -> FloatArray:
    """Return what ``objective`` ranks headings by: line count first, then length.

    ``lengths_m``: each heading's path length [m]; ``counts``: its line count. One number
    per heading (a line outweighs any length, 1e12 m), so that one ``<`` compares both.
    """
    if objective == "fewest_lines":
        return np.asarray(lengths_m + counts * 1e12)
    return np.asarray(lengths_m)


def _seeds(
    least: FloatArray,
    counts: IntArray,
    eligible: npt.NDArray[np.bool_],
    headings: FloatArray,
    objective: Objective,
    k: int,
) -> IntArray:
    """Return the best ``k`` eligible headings by the objective, a seed gap apart."""
    key = np.where(eligible, _objective_key(least, counts, objective), np.inf)
    picked = _spread(np.lexsort((headings, key)), headings, np.isfinite(key), k)
    return np.asarray(picked, dtype=np.int64)
