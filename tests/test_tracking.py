"""Unicycle path tracking under speed-limit profiles."""

from __future__ import annotations

import numpy as np
import pytest

from gfuzzy.fuzzy import fuzzy
from gfuzzy.learning import tracking
from gfuzzy.learning.tracking import TrackingOptions, UnicycleLimits
from gfuzzy.status import Status

LIM = UnicycleLimits()
PATHS = tracking.synthetic_paths()


def _check_bounds(r, lim: UnicycleLimits, dt: float):
    eps = 1e-9
    assert np.all(r.v >= -eps) and np.all(r.v <= lim.vmax + eps)
    assert np.all(np.abs(r.omega) <= lim.omega_max + eps)
    assert np.all(np.abs(np.diff(r.v)) <= lim.amax * dt + eps)
    assert np.all(np.abs(np.diff(r.omega)) <= lim.alpha_max * dt + eps)
    np.testing.assert_allclose(np.diff(r.t), dt)


def test_straight_line_has_no_lateral_error():
    path = PATHS["straight"]
    r = tracking.track(path, limits=LIM)
    assert r.status is Status.SOLVED
    assert r.max_lateral_error < 1e-9
    assert np.all(np.abs(r.xy[:, 1]) < 1e-9)
    assert r.violations.total == 0
    assert r.max_abs_omega < 1e-9
    # Trapezoid: 10 m at 1 m/s with 1 m/s^2 ramps takes 11 s; the run stops
    # goal_tolerance short, at about sqrt(2 * 0.02) m/s.
    assert 10.7 < r.traversal_time <= 11.0
    assert r.xy[-1, 0] == pytest.approx(10.0, abs=0.03)
    _check_bounds(r, LIM, 0.02)


@pytest.mark.parametrize("name", ["s_curve", "zigzag", "hairpin", "arc"])
@pytest.mark.parametrize("profile", ["constant", "fuzzy"])
def test_bounds_respected(name, profile):
    path = PATHS[name]
    prof = None if profile == "constant" else fuzzy.speed_limit(path, LIM.vmax, LIM.amax)
    r = tracking.track(path, prof, LIM)
    assert r.status is Status.SOLVED
    _check_bounds(r, LIM, 0.02)
    assert np.linalg.norm(r.xy[-1] - path[-1]) < 0.1
    n = r.t.size
    for arr in (r.theta, r.v, r.omega, r.omega_cmd, r.v_ref, r.s, r.lateral_error):
        assert arr.shape == (n,)
    assert r.xy.shape == (n, 2)
    assert np.all(np.diff(r.s) >= 0)  # progress along the path never goes back
    assert r.max_lateral_error == pytest.approx(r.lateral_error.max())
    assert r.max_abs_omega_cmd >= r.max_abs_omega - 1e-12


def test_speed_stays_under_the_limit():
    path = PATHS["zigzag"]
    s, v = fuzzy.speed_limit(path, LIM.vmax, LIM.amax)
    r = tracking.track(path, (s, v), LIM)
    limit = np.sqrt(np.interp(r.s, s, v**2))  # as track reads it
    # One step of slack: the limit is read at the mid-step position.
    assert np.all(r.v <= limit + LIM.amax * 0.02 + 1e-9)


def test_fuzzy_limiter_helps_at_sharp_corners():
    path = PATHS["zigzag"]
    const = tracking.track(path, None, LIM)
    fz = tracking.track(path, fuzzy.speed_limit(path, LIM.vmax, LIM.amax), LIM)
    assert const.violations.omega > 0  # vmax into a 90 degree corner asks too much
    assert fz.violations.steps < const.violations.steps
    assert fz.max_abs_omega_cmd < const.max_abs_omega_cmd
    assert fz.max_lateral_error < const.max_lateral_error
    assert fz.traversal_time > const.traversal_time  # the price


def test_timeout_status():
    r = tracking.track(PATHS["straight"], None, LIM, TrackingOptions(timeout_factor=0.1))
    assert r.status is Status.TIMEOUT
    assert r.traversal_time < 10


def test_degenerate_path():
    r = tracking.track([[1.0, 2.0], [1.0, 2.0]])
    assert r.status is Status.SOLVED and r.t.size == 1
    np.testing.assert_allclose(r.xy, [[1.0, 2.0]])


@pytest.mark.parametrize(
    "args",
    [
        dict(path_xy=np.zeros((3, 3))),
        dict(path_xy=[[0, 0], [np.inf, 0]]),
        dict(path_xy=[[0, 0], [1, 0]], profile=([0.0, 1.0], [1.0])),
        dict(path_xy=[[0, 0], [1, 0]], profile=([0.0, 0.0], [1.0, 1.0])),
        dict(path_xy=[[0, 0], [1, 0]], profile=([0.0, 1.0], [1.0, -1.0])),
    ],
)
def test_bad_input(args):
    with pytest.raises(ValueError):
        tracking.track(**args)


@pytest.mark.parametrize("field", ["vmax", "omega_max", "amax", "alpha_max"])
def test_bad_limits(field):
    with pytest.raises(ValueError):
        UnicycleLimits(**{field: 0.0})


def test_constant_profile():
    s, v = tracking.constant_profile(PATHS["corner"], 1.5, 0.5)
    assert v[0] == 0 and v[-1] == 0 and v.max() == pytest.approx(1.5)
    assert np.all(np.abs(np.diff(v**2)) <= 2 * 0.5 * np.diff(s) + 1e-12)
