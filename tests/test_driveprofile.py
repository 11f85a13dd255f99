"""The speed layer of a differential drive (gfuzzy/fuzzy/driveprofile.py, planner.retime_drive).

The oracle reads the timed rows alone and shares no code with the profile builder: it
takes each row pair's forward speed and turning rate, integrates them from the start pose,
and checks the bounds (vmax, wmax, amax, amax / r), rest at every corner, and that the
poses are the path's.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.errors import InputError
from gfuzzy.fuzzy.driveprofile import drive_profile
from gfuzzy.fuzzy.profile import profile_times
from gfuzzy.planner.driveretime import retime_drive
from gfuzzy.scene.scene import parse_scene

VMAX, AMAX, R = 1.0, 2.0, 0.5  # a box 0.8 x 0.6: circumscribed radius 0.5
WMAX = 1.5


def scene_doc(movers=(), obstacles=(), robot=None):
    return {
        "version": 1,
        "name": "dp",
        "bounds": [0, 0, 8, 6],
        "robot": robot or {"box": [0.8, 0.6], "vmax": VMAX, "amax": AMAX, "kinematics": "unicycle", "wmax": WMAX},
        "obstacles": list(obstacles),
        "movers": list(movers),
        "queries": [],
    }


# a turn at the start, a straight of 3 m cut in three rows, a left corner, a straight of
# 2 m, a right corner, 1.5 m, then the goal's heading
PATH = np.array([
    [1.0, 1.0, 0.5], [1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [3.0, 1.0, 0.0], [4.0, 1.0, 0.0],
    [4.0, 1.0, 1.2], [4.0, 1.0, math.pi / 2], [4.0, 3.0, math.pi / 2], [4.0, 3.0, 0.0],
    [5.5, 3.0, 0.0], [5.5, 3.0, -1.0],
])  # fmt: skip


def _wrap(a):
    return (np.asarray(a) + math.pi) % (2 * math.pi) - math.pi


def oracle(rows: np.ndarray, path: np.ndarray, vmax: float, wmax: float, amax: float, r: float):
    """Problems of a differential drive's timed rows, as strings (empty: none)."""
    bad = []
    t, x, y, h = rows.T
    dt = np.diff(t)
    dx, dy, dh = np.diff(x), np.diff(y), _wrap(np.diff(h))
    v = (np.cos(h[:-1]) * dx + np.sin(h[:-1]) * dy) / dt  # forward speed of each row pair
    w = dh / dt
    moving = np.hypot(dx, dy) > 1e-12
    if np.any(moving & (np.abs(dh) > 1e-12)):
        bad.append("turns while moving")
    if np.any(v < -1e-12) or v.max() > vmax * (1 + 1e-9) or np.abs(w).max() > wmax * (1 + 1e-9):
        bad.append(f"bounds: v {v.min()}..{v.max()}, |w| {np.abs(w).max()}")
    if np.any(np.hypot(dx, dy) + r * np.abs(dh) > vmax * dt * (1 + 1e-9)):
        bad.append("configuration speed above vmax")
    # integrate v and w from the start pose
    xi, yi, hi = [x[0]], [y[0]], [h[0]]
    for k in range(len(dt)):
        xi.append(xi[-1] + v[k] * dt[k] * math.cos(hi[-1]))
        yi.append(yi[-1] + v[k] * dt[k] * math.sin(hi[-1]))
        hi.append(hi[-1] + w[k] * dt[k])
    if np.max(np.hypot(np.array(xi) - x, np.array(yi) - y)) > 1e-6 or np.max(np.abs(_wrap(np.array(hi) - h))) > 1e-6:
        bad.append("the integrated poses leave the rows")
    # accelerations: between the mean speeds of neighbouring row pairs of one kind
    for k in range(len(dt) - 1):
        mid = 0.5 * (dt[k] + dt[k + 1])
        if moving[k] and moving[k + 1] and abs(v[k + 1] - v[k]) > amax * mid * (1 + 1e-6):
            bad.append(f"linear acceleration {abs(v[k + 1] - v[k]) / mid} at t={t[k + 1]}")
        turning = not moving[k] and not moving[k + 1]
        if turning and abs(w[k + 1] - w[k]) > amax / r * mid * (1 + 1e-6):
            bad.append(f"angular acceleration {abs(w[k + 1] - w[k]) / mid} at t={t[k + 1]}")
        if moving[k] != moving[k + 1]:  # a corner: the robot reaches it and leaves it from rest
            if abs(v[k]) > amax * dt[k] / 2 * (1 + 1e-6) or abs(w[k]) > amax / r * dt[k] / 2 * (1 + 1e-6):
                bad.append(f"arrives at the corner at t={t[k + 1]} moving")
            if abs(v[k + 1]) > amax * dt[k + 1] / 2 * (1 + 1e-6) or abs(w[k + 1]) > amax / r * dt[k + 1] / 2 * (1 + 1e-6):
                bad.append(f"leaves the corner at t={t[k + 1]} moving")
    # every row on the path, in order
    seg = [(path[i], path[i + 1]) for i in range(len(path) - 1)]
    at = 0
    for row in rows[:, 1:]:
        while at < len(seg):
            a, b = seg[at]
            ab = b[:2] - a[:2]
            f = 0.0 if ab @ ab == 0 else float(np.clip((row[:2] - a[:2]) @ ab / (ab @ ab), 0, 1))
            on_xy = np.hypot(*(a[:2] + f * ab - row[:2])) < 1e-9
            dh_ab = _wrap(b[2] - a[2])
            g = 0.0 if dh_ab == 0 else _wrap(row[2] - a[2]) / dh_ab
            on_h = abs(_wrap(a[2] + (g if ab @ ab == 0 else 0.0) * dh_ab - row[2])) < 1e-9 and -1e-9 <= g <= 1 + 1e-9
            if on_xy and on_h:
                break
            at += 1
        else:
            bad.append(f"row {row} is not on the path (in order)")
            break
    if np.max(np.abs(rows[-1, 1:] - path[-1])) > 1e-9:
        bad.append("does not end at the goal")
    return bad


@pytest.fixture(scope="module")
def empty_scene():
    return parse_scene(scene_doc())


def test_the_layered_rows_pass_the_oracle_and_check(empty_scene):
    rt = retime_drive(empty_scene, PATH, 0.0, 0.07, AMAX, 60.0)
    assert rt.status == "solved", rt.message
    rows = rt.trajectory.waypoints
    assert oracle(rows, PATH, VMAX, WMAX, AMAX, R) == []
    rep = check_trajectory(empty_scene, rows)
    assert rep.valid, rep.reason


def test_the_oracle_rejects_the_unlayered_timing(empty_scene):
    # the same path driven at full speed with instant starts and stops (the search's rows)
    t, rows = 0.0, [[0.0, *PATH[0]]]
    for a, b in zip(PATH[:-1], PATH[1:], strict=True):
        t += np.hypot(*(b[:2] - a[:2])) / VMAX + abs(_wrap(b[2] - a[2])) / WMAX
        rows.append([t, *b])
    rows = np.array(rows)
    assert check_trajectory(empty_scene, rows).valid  # legal for check, which has no amax
    assert any("corner" in p or "acceleration" in p for p in oracle(rows, PATH, VMAX, WMAX, AMAX, R))


def test_check_rejects_a_doctored_layered_trajectory(empty_scene):
    rows = retime_drive(empty_scene, PATH, 0.0, 0.07, AMAX, 60.0).trajectory.waypoints
    moving = np.nonzero(np.hypot(*np.diff(rows[:, 1:3], axis=0).T) > 0.01)[0]
    turned = rows.copy()
    turned[moving[5] + 1, 3] += 0.05  # turns while it moves
    assert "turns while moving" in check_trajectory(empty_scene, turned).reason
    slid = rows.copy()
    slid[moving[5] + 1, 2] += 0.01  # slides sideways on the first straight (along x)
    assert "slides sideways" in check_trajectory(empty_scene, slid).reason
    spinning = np.nonzero(np.abs(_wrap(np.diff(rows[:, 3]))) > 0.05)[0]
    fast = rows.copy()
    fast[spinning[0] + 1 :, 0] -= 0.5 * np.diff(rows[:, 0])[spinning[0]]  # the turn twice as fast
    assert "faster than wmax" in check_trajectory(empty_scene, fast).reason


def test_a_straight_and_a_turn_alone_take_the_closed_form_times():
    # from rest to rest: L / v + v / a when the cruise speed is reached
    straight = np.array([[0.0, 0.0, 0.0], [4.0, 0.0, 0.0]])
    p = drive_profile(straight, R, VMAX, AMAX, WMAX)
    assert profile_times(p.s, p.v)[-1] == pytest.approx(4.0 / VMAX + VMAX / AMAX, rel=1e-3)
    # a quarter turn in place: metric length r pi/2 at r wmax, the metric acceleration amax
    turn = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, math.pi / 2]])
    p = drive_profile(turn, R, VMAX, AMAX, WMAX)
    length, cruise = R * math.pi / 2, R * WMAX
    assert p.stops.size == 0 and p.turning.all()
    assert profile_times(p.s, p.v)[-1] == pytest.approx(length / cruise + cruise / AMAX, rel=5e-3)  # ds = 0.05 sampling


def test_the_robot_rests_at_every_corner_and_nowhere_else():
    p = drive_profile(PATH, R, VMAX, AMAX, WMAX)
    knots = np.concatenate([[0.0], np.cumsum(
        np.hypot(*np.diff(PATH[:, :2], axis=0).T) + R * np.abs(_wrap(np.diff(PATH[:, 2]))))])  # fmt: skip
    # straight meets turn at poses 1, 4, 6, 7, 8, 9; the straights' inner rows (2, 3) and the
    # turn's inner row (5) are no stops
    assert np.allclose(p.stops, knots[[1, 4, 6, 7, 8, 9]])
    assert np.all(np.interp(p.stops, p.s, p.v) == 0.0)
    assert np.all(np.interp(knots[[2, 3, 5]], p.s, p.v) > 0.3)
    # a turn left then right: a stop where the turning direction changes
    zig = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.6], [0.0, 0.0, 0.1]])
    assert drive_profile(zig, R, VMAX, AMAX, WMAX).stops.size == 1


def test_the_fuzzy_rules_brake_before_a_sharp_corner():
    # the same 3 m straight before a quarter turn and before a half turn: the sharper turn
    # ahead lowers the speed bound on the approach (the fuzzy rule), beyond the braking ramp
    def approach(turn):
        path = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 0.0, turn], [3.0 + 2 * math.cos(turn), 2 * math.sin(turn), turn]])
        p = drive_profile(path, R, VMAX, AMAX, WMAX)
        return np.interp(2.4, p.s, p.v)

    ramp = math.sqrt(2 * AMAX * 0.6)  # braking from 2.4 m to rest at 3 m
    assert approach(3.0) < approach(1.0) < min(VMAX, ramp) + 1e-9


def test_a_path_that_turns_while_moving_is_refused():
    with pytest.raises(InputError, match="turns while it moves"):
        drive_profile(np.array([[0.0, 0.0, 0.0], [1.0, 0.5, 0.3]]), R, VMAX, AMAX, WMAX)


def test_a_drive_that_may_reverse_stops_where_it_changes_direction():
    robot = {"disc": 0.2, "vmax": VMAX, "amax": AMAX, "kinematics": "unicycle", "reverse": True}
    scene = parse_scene(scene_doc(robot=robot))
    path = np.array([[1.0, 1.0, 0.0], [3.0, 1.0, 0.0], [2.0, 1.0, 0.0], [2.0, 1.0, 1.0]])
    p = drive_profile(path, 0.2, VMAX, AMAX, scene.robot.turn_rate)
    assert np.allclose(p.stops, [2.0, 3.0])  # the reversal, then the turn
    rt = retime_drive(scene, path, 0.0, 0.07, AMAX, 30.0)
    rows = rt.trajectory.waypoints
    assert check_trajectory(scene, rows).valid
    forward = np.cos(rows[:-1, 3]) * np.diff(rows[:, 1])
    assert forward.min() < 0 < forward.max()
    # the robot is at rest at x = 3: the rows reach it and leave it at most amax dt^2 / 2 away
    at = np.nonzero(np.isclose(rows[:, 1], 3.0))[0]
    assert at.size and np.all(np.abs(np.diff(rows[at[0] - 1 : at[-1] + 2, 1])) <= AMAX * 0.07**2 / 2 * (1 + 1e-6) + 1e-12)


def test_motions_of_no_length_are_dropped(empty_scene):
    path = np.vstack([PATH[:3], PATH[2] + [1e-13, 0.0, 0.0], PATH[3:-1], PATH[-1] + [0.0, 0.0, 1e-12], PATH[-1]])
    rt = retime_drive(empty_scene, path, 0.0, 0.07, AMAX, 60.0)
    assert rt.status == "solved"
    assert oracle(rt.trajectory.waypoints, PATH, VMAX, WMAX, AMAX, R) == []
    np.testing.assert_array_equal(rt.trajectory.waypoints[-1, 1:], PATH[-1])
