"""The count of sharp turns (bench.move_corners): the exported points' rounding is not a corner."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from bench.move_corners import ROUNDING_M, SEAM_M, curvatures, turn_seams
from planner.projection import field_frame

RADIUS_M = 3.0


@settings(max_examples=60, deadline=None)
@given(
    step_m=st.floats(0.05, 0.5),
    start_rad=st.floats(-math.pi, math.pi),
    angles=st.lists(st.floats(0.0, 2.0 * math.pi), min_size=40, max_size=40),
)
def test_an_arc_of_the_radius_is_never_sharp_however_its_points_are_rounded(
    step_m: float, start_rad: float, angles: list[float]
) -> None:
    """Points on an arc of the turning radius, each moved up to the rounding in any direction."""
    turned = start_rad + np.arange(40) * step_m / RADIUS_M
    arc = RADIUS_M * np.column_stack([np.cos(turned), np.sin(turned)])
    shift = ROUNDING_M * np.column_stack([np.cos(angles), np.sin(angles)])

    assert (curvatures(arc + shift) <= 1.0 / RADIUS_M * (1.0 + 1e-6)).all()


def test_rounding_noise_alone_can_make_an_arc_look_a_tenth_tighter() -> None:
    """Why the allowance: at 6 cm steps, 0.08 mm shifts tighten the circle by over a tenth."""
    turned = np.arange(3) * 0.06 / RADIUS_M
    arc = RADIUS_M * np.column_stack([np.cos(turned), np.sin(turned)])
    pinched = arc.copy()
    pinched[1] += arc[1] / np.hypot(*arc[1]) * ROUNDING_M  # the middle point out: tighter

    unrounded = curvatures(pinched, rounding_m=0.0)
    assert unrounded[0] > 1.1 / RADIUS_M
    assert curvatures(pinched)[0] <= 1.0 / RADIUS_M


def test_a_corner_is_sharp() -> None:
    """A right angle on half-metre steps: a corner the vehicle cannot drive."""
    corner = np.array([[0.0, 0.0], [0.5, 0.0], [1.0, 0.0], [1.0, 0.5], [1.0, 1.0]])
    assert curvatures(corner).max() > 2.0


@pytest.mark.parametrize("tighter", [1.03, 1.05])
def test_an_arc_a_little_tighter_than_the_radius_is_sharp_on_half_metre_steps(
    tighter: float,
) -> None:
    """The allowance is no bigger than the rounding: on 0.5 m steps, 3 % tighter shows."""
    radius_m = RADIUS_M / tighter
    turned = np.arange(10) * 0.5 / radius_m
    arc = radius_m * np.column_stack([np.cos(turned), np.sin(turned)])
    assert (curvatures(arc) > 1.0 / RADIUS_M * (1.0 + 1e-6)).all()


def test_a_seam_reaches_half_a_metre_along_a_round_driven_once_round() -> None:
    """A round driven once round ends where it starts: its seam with the turn after it
    still reaches half a metre back along its last step (not its start-to-end length, 0)."""
    field_lonlat = shapely.box(115.20, -8.61, 115.21, -8.60)
    frame = field_frame(field_lonlat)
    ring = np.array([(0, 0), (10, 0), (10, 10), (0, 10), (0, 5), (0, 1), (0, 0)], dtype=float)
    turn = np.array([(0, 0), (0.2, -1.0), (1.0, -2.0), (2.0, -2.5)])
    line = np.array([(2.0, -2.5), (9.0, -2.5)])

    def segment(kind: str, xy: np.ndarray) -> SimpleNamespace:
        lon, lat = frame.to_lonlat_xy(*xy.T)
        return SimpleNamespace(kind=kind, lonlat=np.column_stack([lon, lat]).tolist())

    plan = SimpleNamespace(
        field_lonlat=field_lonlat,
        segments=[segment("round", ring), segment("turn", turn), segment("line", line)],
    )
    ((k, seam),) = turn_seams(plan, ("line", "round"))  # type: ignore[arg-type]
    assert k == 1
    assert np.allclose(seam[0], (0.0, SEAM_M), atol=1e-6)
    assert np.allclose(seam[-1], (2.0 + SEAM_M, -2.5), atol=1e-6)
