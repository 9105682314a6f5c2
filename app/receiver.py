"""How good the receiver behind a run was, and what that means for its figures (product.md §8).

A run is scored from the fixes its own receiver logged. With RTK those are within centimetres
of where the tractor was; with a single-frequency receiver such as the paper's u-blox NEO-M8N
(2.5 m CEP) they are off by metres, and slowly, so the run's cross-track errors, waypoint
errors and coverage are only estimates of that size: a simulated M8N run scored from its own
receiver shows 99 % coverage where the true track covered 82 % (docs/simulation.md).
:func:`receiver_report` says so plainly, from the fix qualities the log carried.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from app.track_fixes import FIX_QUALITIES

#: Share of fixes of a grade above which the whole run counts as that grade.
MAJORITY: Final = 0.9

_NOTES: Final[dict[str, str]] = {
    "centimetre": "RTK fixed: the figures are accurate to a few centimetres.",
    "decimetre": (
        "RTK float or mixed RTK: the figures are accurate to a few decimetres; cross-track "
        "errors below that are not measurable."
    ),
    "metre": (
        "These figures rest on a receiver of metre-level accuracy (single or DGPS fixes, "
        "like a u-blox NEO-M8N's 2.5 m CEP): cross-track errors, waypoint errors and coverage "
        "are estimates that can be off by a couple of metres."
    ),
    "unknown": (
        "The log does not say how good its fixes were. If it came from a single-frequency "
        "receiver such as a u-blox NEO-M8N, treat these figures as metre-level estimates."
    ),
}


def receiver_report(
    quality: Sequence[str | None], hdop: npt.ArrayLike, satellites: npt.ArrayLike
) -> dict[str, Any]:
    """Summarise a run's fix qualities: the share of each, and what the figures are worth.

    Parameters
    ----------
    quality : sequence of str or None
        Each fix's quality (:data:`app.track_fixes.FIX_QUALITIES`), None where unknown.
    hdop, satellites : sequences of float
        NaN where unknown.

    Returns
    -------
    dict
        ``shares`` (each quality and ``unknown``, summing to 1), ``hdop_median``,
        ``satellites_median``, ``accuracy`` (``centimetre``, ``decimetre``, ``metre`` or
        ``unknown``), ``metre_level`` (true unless the fixes were mostly RTK) and ``note``.

    Examples
    --------
    >>> r = receiver_report(["rtk_fixed"] * 8 + ["rtk_float", "single"], [0.9] * 10, [14] * 10)
    >>> r["shares"]["rtk_fixed"], r["accuracy"], r["metre_level"]
    (0.8, 'decimetre', False)
    >>> receiver_report(["single"] * 3, [1.2] * 3, [9] * 3)["accuracy"]
    'metre'
    """
    n = len(quality)
    counts = {name: 0 for name in FIX_QUALITIES}
    unknown = 0
    for q in quality:
        if q in counts:
            counts[q] += 1
        else:
            unknown += 1
    shares = {name: (count / n if n else 0.0) for name, count in counts.items()}
    shares["unknown"] = unknown / n if n else 0.0
    known = 1.0 - shares["unknown"]
    if n == 0 or known < 0.5:
        accuracy = "unknown"
    elif shares["rtk_fixed"] >= MAJORITY - 1e-9:
        accuracy = "centimetre"
    elif shares["rtk_fixed"] + shares["rtk_float"] >= MAJORITY - 1e-9:
        accuracy = "decimetre"
    else:
        accuracy = "metre"
    h = np.asarray(hdop, dtype=float)
    s = np.asarray(satellites, dtype=float)
    return {
        "fixes": n,
        "shares": shares,
        "hdop_median": float(np.nanmedian(h)) if np.isfinite(h).any() else None,
        "satellites_median": float(np.nanmedian(s)) if np.isfinite(s).any() else None,
        "accuracy": accuracy,
        "metre_level": accuracy in ("metre", "unknown"),
        "note": _NOTES[accuracy],
    }
