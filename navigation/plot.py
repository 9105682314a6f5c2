"""A picture of a run: the field, the plan and the tracks, and the cross-track error over time.

Rendered by matplotlib's Agg renderer through a bare :class:`~matplotlib.figure.Figure`: no
display, no pyplot, no global backend switch (so a web process importing this is unaffected).
Returns PNG bytes.
"""

from __future__ import annotations

import io

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from navigation.metrics import cross_track_errors
from navigation.route import build_route, match_by_leg
from navigation.simulator import SimulationLog


def plot_simulation(log: SimulationLog, *, title: str | None = None, dpi: int = 120) -> bytes:
    """Render ``log`` as a PNG: map on the left, cross-track error over time on the right.

    Returns
    -------
    bytes
        The PNG file's content.
    """
    frame = log.frame
    pieces = build_route(log.plan, frame)
    field = frame.to_local(log.plan.field_lonlat)

    fig = Figure(figsize=(12, 6), dpi=dpi, layout="constrained")
    FigureCanvasAgg(fig)
    ax_map, ax_err = fig.subplots(1, 2, width_ratios=[1.1, 1.0])

    # Field (holes white), plan, tracks.
    fx, fy = field.exterior.xy
    ax_map.fill(fx, fy, color="#e8f2dc", zorder=0, label="field")
    ax_map.plot(fx, fy, color="#4d7a2a", lw=1.2, zorder=1)
    for hole in field.interiors:
        hx, hy = hole.xy
        ax_map.fill(hx, hy, color="white", zorder=1)
        ax_map.plot(hx, hy, color="#4d7a2a", lw=1.0, zorder=1)
    wx, wy = frame.to_local_xy(
        [w.lon for w in log.plan.waypoints], [w.lat for w in log.plan.waypoints]
    )
    ax_map.plot(wx, wy, color="#555555", lw=1.0, ls="--", zorder=2, label="plan")
    ax_map.scatter(wx, wy, s=18, color="#555555", zorder=3)
    ax_map.plot(
        log.gps_x_m, log.gps_y_m, ".", ms=2, color="#e39b2d", alpha=0.6, zorder=3, label="GPS fixes"
    )
    ax_map.plot(
        log.est_x_m, log.est_y_m, color="#2c7fb8", lw=1.0, zorder=4, label="filter estimate"
    )
    ax_map.plot(log.true_x_m, log.true_y_m, color="#c0392b", lw=1.6, zorder=5, label="true track")
    ax_map.annotate(
        "start", (wx[0], wy[0]), textcoords="offset points", xytext=(4, -10), fontsize=8
    )
    ax_map.annotate(
        "finish", (wx[-1], wy[-1]), textcoords="offset points", xytext=(4, -10), fontsize=8
    )
    ax_map.set_aspect("equal", adjustable="datalim")
    ax_map.set_xlabel("east [m]")
    ax_map.set_ylabel("north [m]")
    ax_map.legend(loc="upper left", fontsize=8, framealpha=0.9)
    ax_map.grid(True, lw=0.3, alpha=0.5)

    m = log.metrics
    gps_name = getattr(log.config.gps, "name", str(log.config.gps))
    ax_map.set_title(
        title
        or (
            f"{log.config.guidance.mode} guidance, {gps_name} GPS: "
            f"{'completed' if m.completed else 'NOT completed'} in {m.time_s:.0f} s"
        ),
        fontsize=10,
    )

    # Both to the line being driven (the waypoint the tractor steered to).
    xte, _, _ = cross_track_errors(
        pieces,
        log.true_x_m,
        log.true_y_m,
        match_by_leg(pieces, log.true_x_m, log.true_y_m, log.target),
    )
    xte_est, _, _ = cross_track_errors(
        pieces, log.est_x_m, log.est_y_m, match_by_leg(pieces, log.est_x_m, log.est_y_m, log.target)
    )
    ax_err.plot(log.time_s, xte, color="#c0392b", lw=1.2, label="true track")
    ax_err.plot(
        log.time_s,
        xte_est,
        color="#2c7fb8",
        lw=0.8,
        alpha=0.8,
        label="filter estimate (what the tractor believes)",
    )
    ax_err.axhline(
        m.threshold_m, color="#888888", ls=":", lw=1.0, label=f"threshold {m.threshold_m:g} m"
    )
    for s in m.stretches:
        ax_err.axvspan(s.start_s, s.end_s, color="#f5b7b1", alpha=0.5, lw=0)
    ax_err.set_xlabel("time [s]")
    ax_err.set_ylabel("cross-track error on tillage lines [m]")
    ax_err.set_ylim(bottom=0.0)
    ax_err.grid(True, lw=0.3, alpha=0.5)
    ax_err.legend(loc="upper right", fontsize=8)
    rms = "–" if m.cross_track_rms_m is None else f"{m.cross_track_rms_m:.2f} m"
    ax_err.set_title(
        f"cross-track RMS {rms}, waypoint error max {m.waypoint_error_max_m:.2f} m, "
        f"coverage {m.coverage_ratio:.1%}",
        fontsize=10,
    )
    if not np.isfinite(xte).any():
        ax_err.text(0.5, 0.5, "no fix on a tillage line", transform=ax_err.transAxes, ha="center")

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    return buffer.getvalue()
