"""Filter consistency: χ² bounds of the mean NEES and NIS (Bar-Shalom, Li & Kirubarajan 2001, §5.4).

A filter is consistent when its errors are as large as its covariance says. The normalised
estimation error squared ``NEES = e' P⁻¹ e`` of an ``n``-dimensional error is χ²(n)
distributed, so the mean of ``N`` independent samples, times ``N``, is χ²(nN): its two-sided
95 % interval is :func:`chi2_mean_bounds`. The same holds for the normalised innovation
squared ``NIS = ν' S⁻¹ ν`` of the measurement updates.

Which samples are independent matters. The NEES of one run is correlated in time (the
receiver's wander lasts about a minute), so over a Monte Carlo batch each run's time-averaged
NEES counts as one sample and the bounds come from the number of runs (conservative: the time
average varies less than one draw). A consistent filter's innovations are white, so the NIS
counts every update.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt
from scipy.stats import chi2  # type: ignore[import-untyped]


def chi2_mean_bounds(dof: int, n_samples: int, *, level: float = 0.95) -> tuple[float, float]:
    """Two-sided ``level`` interval of the mean of ``n_samples`` χ²(``dof``) draws.

    Examples
    --------
    >>> low, high = chi2_mean_bounds(2, 50)
    >>> round(low, 3), round(high, 3)
    (1.484, 2.591)
    """
    if dof < 1 or n_samples < 1:
        raise ValueError("dof and n_samples must be ≥ 1")
    tail = 0.5 * (1.0 - level)
    total = dof * n_samples
    return (
        float(chi2.ppf(tail, total) / n_samples),
        float(chi2.ppf(1.0 - tail, total) / n_samples),
    )


def normalised_squares(
    errors: Sequence[npt.ArrayLike], covariances: Sequence[npt.ArrayLike]
) -> npt.NDArray[np.float64]:
    """``e' C⁻¹ e`` of each error and its covariance (a NEES or NIS sample), in input order.

    The same values, bit for bit, as ``e @ np.linalg.solve(C, e)`` one sample at a time, but
    one batched solve per dimension: a run's thousand samples cost one numpy call, not a
    thousand (LAPACK solves each matrix alike, stacked or not).

    Parameters
    ----------
    errors : sequence of 1-D arrays
        Error (or innovation) vectors; their lengths may differ from sample to sample.
    covariances : sequence of 2-D arrays
        The matching covariances, each square of its error's length.

    Returns
    -------
    array
        One value per sample.

    Examples
    --------
    >>> normalised_squares([[2.0, 0.0], [3.0]], [[[4.0, 0.0], [0.0, 1.0]], [[9.0]]]).tolist()
    [1.0, 1.0]
    """
    if len(errors) != len(covariances):
        raise ValueError("errors and covariances differ in length")
    out = np.empty(len(errors))
    by_dim: dict[int, list[int]] = {}
    vectors = [np.asarray(e, dtype=float) for e in errors]
    for i, e in enumerate(vectors):
        by_dim.setdefault(len(e), []).append(i)
    for dim, rows in by_dim.items():
        e = np.array([vectors[i] for i in rows]).reshape(len(rows), dim, 1)
        c = np.array([covariances[i] for i in rows], dtype=float).reshape(len(rows), dim, dim)
        # Stacked matmul of (1 × dim) by (dim × 1) sums as the per-sample dot does.
        out[rows] = (e.transpose(0, 2, 1) @ np.linalg.solve(c, e))[:, 0, 0]
    return out


def batch_consistency(
    means: Sequence[float], *, dof: int, level: float = 0.95
) -> dict[str, float | bool | int]:
    """Average the per-run mean NEES (or NIS) over a Monte Carlo batch, with its χ² bounds.

    Parameters
    ----------
    means : sequence of float
        One time-averaged statistic per run.
    dof : int
        Its degrees of freedom.

    Returns
    -------
    dict
        ``mean``, ``low``, ``high``, ``within`` (the mean lies within the bounds), ``runs``.

    Examples
    --------
    >>> batch_consistency([1.8, 2.2, 2.0], dof=2)["within"]
    True
    """
    if not means:
        raise ValueError("means: needs at least one run")
    mean = float(sum(means) / len(means))
    low, high = chi2_mean_bounds(dof, len(means), level=level)
    return {
        "mean": mean,
        "low": low,
        "high": high,
        "within": low <= mean <= high,
        "runs": len(means),
    }
