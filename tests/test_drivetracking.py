"""gfuzzy.learning.drivetracking: a differential drive tracking a timed plan."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_driveprofile import PATH, scene_doc

from gfuzzy.errors import InputError
from gfuzzy.learning.drivetracking import DriveGains, reference_at, track_drive
from gfuzzy.learning.tracking import UnicycleLimits
from gfuzzy.planner.driveretime import retime_drive
from gfuzzy.scene.scene import parse_scene

R, VMAX, AMAX, WMAX = 0.5, 1.0, 2.0, 1.5
LIMITS = UnicycleLimits(vmax=VMAX, omega_max=WMAX, amax=AMAX, alpha_max=AMAX / R)


@pytest.fixture(scope="module")
def layered():
    return retime_drive(parse_scene(scene_doc()), PATH, 0.0, 0.07, AMAX, 60.0).trajectory.waypoints


def _unlayered():
    t, rows = 0.0, [[0.0, *PATH[0]]]
    for a, b in zip(PATH[:-1], PATH[1:], strict=True):
        t += np.hypot(*(b[:2] - a[:2])) / VMAX + abs((b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi) / WMAX
        rows.append([t, *b])
    return np.array(rows)


def test_the_layered_plan_is_followed_closely_within_the_bounds(layered):
    res = track_drive(layered, LIMITS)
    assert res.status == "solved"
    assert res.plan_violations.steps == 0
    assert res.max_position_error < 0.02 and res.max_lateral_error < 0.02
    g = DriveGains()
    assert np.all(res.v >= -1e-12) and res.v.max() <= VMAX + 1e-12 and np.abs(res.omega).max() <= WMAX + 1e-12
    assert np.abs(np.diff(res.v)).max() <= AMAX * g.dt + 1e-12
    assert np.abs(np.diff(res.omega)).max() <= AMAX / R * g.dt + 1e-12
    assert res.arrival_time == pytest.approx(layered[-1, 0], abs=0.5)


def test_the_unlayered_plan_jumps_and_is_followed_worse(layered):
    rows = _unlayered()
    good, bad = track_drive(layered, LIMITS), track_drive(rows, LIMITS)
    assert bad.plan_violations.acceleration > 0
    assert bad.max_position_error > 3 * good.max_position_error


def test_reference_at_reads_the_rows():
    rows = np.array([[0.0, 0.0, 0.0, 0.0], [1.0, 1.0, 0.0, 0.0], [2.0, 1.0, 0.0, 0.0], [3.0, 1.0, 0.0, 1.0]])
    poses, v, w = reference_at(rows, np.array([0.5, 1.5, 2.5, 4.0]))
    np.testing.assert_allclose(poses, [[0.5, 0, 0], [1, 0, 0], [1, 0, 0.5], [1, 0, 1]], atol=1e-12)
    # the mean speeds sit at the motions' middles; a wait is at rest
    np.testing.assert_allclose(v, [1.0, 0.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(w, [0.0, 0.0, 1.0, 0.0], atol=1e-12)


def test_bad_rows_are_refused():
    with pytest.raises(InputError):
        track_drive(np.array([[0.0, 0.0, 0.0, 0.0]]), LIMITS)
    with pytest.raises(InputError):
        track_drive(np.array([[0.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]), LIMITS)


def _there_and_back(leg=1.0, a=1.0, dt=0.07):
    """Rows driving ``leg`` m forward along x and back, each way from rest to rest at
    acceleration ``a`` (a triangle speed profile), heading 0 throughout."""
    half = math.sqrt(leg / a)  # accelerate for half, brake for half
    t = np.arange(0.0, 2 * half + 1e-9, dt)
    t[-1] = 2 * half
    x = np.where(t <= half, 0.5 * a * t**2, leg - 0.5 * a * (2 * half - t) ** 2)
    back = leg - x[1:]
    tt = np.concatenate([t, 2 * half + t[1:]])
    xx = np.concatenate([x, back])
    return np.column_stack([tt, xx, np.zeros_like(xx), np.zeros_like(xx)])


def test_a_reversal_is_a_rest():
    """Forward then backward: the robot brakes to rest where its travel reverses (it reaches
    the turning point and does not overrun it), then drives back, within the bounds."""
    rows = _there_and_back()
    res = track_drive(rows, LIMITS, reverse=True)
    assert res.status == "solved"
    g = DriveGains()
    far = int(np.argmax(res.poses[:, 0]))
    assert res.poses[far, 0] == pytest.approx(1.0, abs=0.03), res.poses[far]
    assert abs(res.v[far]) <= AMAX * g.dt + 1e-12  # at rest there, to within one step's change
    assert res.t[far] == pytest.approx(2.0, abs=0.2)  # at the plan's reversal, not before
    assert res.v.min() < -0.5 and res.v.max() > 0.5  # it drove both ways
    assert np.abs(res.v).max() <= VMAX + 1e-12 and np.abs(np.diff(res.v)).max() <= AMAX * g.dt + 1e-12
    assert res.max_position_error < 0.05


@pytest.mark.parametrize("field", ["kx", "dt", "settle", "violation_tolerance", "goal_tolerance"])
@pytest.mark.parametrize("value", [math.inf, math.nan, -1.0])
def test_gains_must_be_finite_with_sensible_signs(field, value):
    with pytest.raises(InputError, match=f"DriveGains.{field}"):
        DriveGains(**{field: value})
