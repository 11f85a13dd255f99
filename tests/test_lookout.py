"""A robot with a field of view looks where it has not looked (gfuzzy.navigation.lookout): a disc by
a short step, a robot with a heading by a turn in place."""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.errors import InputError
from gfuzzy.navigation.lookout import EMPTY_FACTOR, LOOK_SPEED, LOOK_TIME, Lookout, knowing_view
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.navtypes import NavMode
from gfuzzy.trajectory import Trajectory

NORTH, SOUTH = math.pi / 2, -math.pi / 2


def _angle(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


def test_the_back_never_seen_is_looked_at_first_then_only_when_stale():
    look = Lookout(180.0, 1.0, np.array([0.0, 4.0]))
    look.observe(0.0, np.array([0.0, -4.0]))  # facing the goal (north): the south half unseen
    assert _angle(look.direction(0.0), SOUTH) < math.radians(10)
    look.observe(0.25, np.array([0.0, -4.05]))  # stepped south: the view turned there
    assert look.direction(0.25) is None
    for k in range(2, 40):  # drives north again, nobody known behind it
        t = 0.25 * k
        look.observe(t, np.array([0.0, -4.0 + 0.25 * k]))
        if look.direction(t) is not None:
            break
    # an empty side waits EMPTY_FACTOR times longer than one where someone was seen
    assert t - 0.25 == pytest.approx(EMPTY_FACTOR * 1.0, abs=0.26)
    assert _angle(look.direction(t), SOUTH) < math.radians(10)


def test_someone_seen_walking_into_the_blind_side_is_looked_for_after_look_after():
    look = Lookout(180.0, 1.0, np.array([0.0, 4.0]))
    look.observe(0.0, np.array([0.0, 0.0]))
    look.observe(0.25, np.array([0.0, -0.05]))  # a look south: everything seen by now
    behind = np.array([[-0.5, -2.0, 0.0, 0.5, 0.3]])  # someone 2 m behind-left, coasted
    ahead = np.array([[0.0, 3.0, 0.0, -0.5, 0.3]])
    seen = None
    for k in range(2, 12):
        t = 0.25 * k
        look.observe(t, np.array([0.0, 0.25 * (k - 2)]))  # north
        assert look.direction(t, np.array([0.0, 0.25 * (k - 2)]), ahead) is None  # nobody known behind
        if seen is None and look.direction(t, np.array([0.0, 0.25 * (k - 2)]), behind) is not None:
            seen = t
    assert seen == pytest.approx(1.5)  # south last seen at 0.25 s: unseen for more than 1 s at the 1.5 s step


def test_navigator_looks_back_first_then_drives(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(fov=180.0))
    pose = np.array([0.0, -4.0])
    traj = nav.step(0.0, pose, np.zeros((0, 5)))
    assert nav.last.mode == NavMode.LOOK
    step = traj.at(LOOK_TIME) - pose
    assert np.hypot(*step) == pytest.approx(LOOK_SPEED * nav.vplan * LOOK_TIME)
    assert _angle(math.atan2(step[1], step[0]), SOUTH) < math.radians(10)  # away from the goal: its back
    assert np.all(traj.speeds() <= scene.robot.vmax * (1 + 1e-9))
    pose = traj.at(0.25)
    traj = nav.step(0.25, pose, np.zeros((0, 5)))
    assert nav.last.mode == NavMode.PLAN  # the back was just seen: on to the goal
    assert traj.at(0.5)[1] > pose[1] + 0.1


def test_no_look_into_a_person_walking_at_the_robot(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(fov=180.0))
    # someone 1 m south walking north at 1 m/s: stepping back south meets them within a second
    traj = nav.step(0.0, np.array([0.0, -3.0]), np.array([[0.0, -4.3, 0.0, 1.0, 0.3]]))
    assert nav.last.mode != NavMode.LOOK
    assert traj.at(0.25)[1] >= -3.0 - 1e-9 or abs(traj.at(0.25)[0]) > 0.05  # not backing into them


def test_a_look_never_replaces_a_fallback(open_square, monkeypatch):
    """The back never seen would be looked at first (above), but when no search answers the
    fallback's motion stands: a look is checked over a second only, the evasion over more."""
    from gfuzzy.navigation.navigator import _Searched

    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(fov=180.0))
    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(None, "exhausted"))
    person = np.array([[2.5, -2.0, -0.2, 0.0, 0.3]])  # far enough that no fallback waits for them
    nav.step(0.0, np.array([0.0, -4.0]), person)
    assert nav.last.mode in (NavMode.DIRECT, NavMode.PREVIOUS, NavMode.EVASIVE)


def test_a_navigator_with_a_full_view_never_looks(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0))
    nav.step(0.0, np.array([0.0, -4.0]), np.zeros((0, 5)))
    assert nav.last.mode == NavMode.PLAN


def test_options_know_the_sensor_and_reject_a_bad_fov():
    assert knowing_view(NavOptions(), 180.0).fov == 180.0
    assert knowing_view(NavOptions(fov=90.0), 180.0).fov == 90.0  # the user's own choice stays
    assert knowing_view(NavOptions(), 360.0).fov == 360.0
    for bad in (0.0, -10.0, 400.0, math.nan):
        with pytest.raises(InputError):
            NavOptions(fov=bad)
    with pytest.raises(InputError):
        NavOptions(look_after=0.0)


def _first_look_behind(person, unknown=None) -> float:
    """When a robot that looked south at 0.25 s, then drives north, first finds the south
    stale with ``person`` (1, 5) behind it."""
    look = Lookout(180.0, 1.0, np.array([0.0, 4.0]))
    look.observe(0.0, np.array([0.0, 0.0]))
    look.observe(0.25, np.array([0.0, -0.05]))  # a look south: everything seen by now
    for k in range(2, 40):
        t = 0.25 * k
        pose = np.array([0.0, 0.25 * (k - 2)])
        look.observe(t, pose)  # north
        found = look.direction(t, pose, person) if unknown is None else look.direction(t, pose, person, unknown=unknown)
        if found is not None:
            return t
    return math.inf


def test_someone_standing_on_the_blind_side_waits_as_an_empty_side():
    """A person seen standing behind the robot is not walking toward it, and the robot drives
    where it looks: their side waits as an empty one (``EMPTY_FACTOR * look_after``), not
    ``look_after``; among people standing about, the robot no longer looks every other step."""
    standing = np.array([[-0.5, -2.0, 0.0, 0.0, 0.3]])
    assert _first_look_behind(np.array([[-0.5, -2.0, 0.0, 0.5, 0.3]])) == pytest.approx(1.5)  # walking
    assert _first_look_behind(standing) - 0.25 == pytest.approx(EMPTY_FACTOR * 1.0, abs=0.26)


def test_someone_seen_once_on_the_blind_side_counts_as_walking():
    """A person seen once is reported standing, but their velocity is not known: they may be
    walking, and their side is looked at after ``look_after`` as a walker's."""
    standing = np.array([[-0.5, -2.0, 0.0, 0.0, 0.3]])
    assert _first_look_behind(standing, unknown=standing[:, :2]) == pytest.approx(1.5)


# ---------------------------------------------------------------- a robot with a heading
def _floor(robot: dict, obstacles=()):
    from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
    from gfuzzy.scene.scene import parse_scene

    doc = {"version": 1, "name": "floor", "bounds": [0, 0, 10, 10], "robot": robot, "obstacles": list(obstacles),
           "movers": []}  # fmt: skip
    scene = parse_scene(doc, "<floor>")
    return scene, build_roadmap(scene, RoadmapOptions(vertices=150, seed=3))


DRIVE = {"disc": 0.3, "vmax": 1.0, "kinematics": "unicycle", "wmax": 1.0}
POSE = np.array([3.0, 3.0, 0.0])  # facing east, towards the goal
GOAL = (9.0, 3.0, 0.0)
#: Someone known behind-left (bearing 127 degrees), walking to pass 0.8 m behind the robot in 2 s.
WALKER = np.array([1.8, 4.6, 0.8, -0.3, 0.3])


def _walker_at(t: float) -> np.ndarray:
    return np.array([[*(WALKER[:2] + t * WALKER[2:4]), *WALKER[2:]]])


def test_a_differential_drive_looks_by_turning_in_place_only_as_far_as_needed():
    """Its view is about its heading: the look is a turn in place (the row rule, at most
    wmax), toward someone known behind it, until their side is just inside the view's edge
    (TURN_MARGIN), then standing; nothing looks at the empty back (a turn costs seconds)."""
    from gfuzzy.check.check import _unicycle_problem, check_trajectory
    from gfuzzy.navigation.lookout import TURN_MARGIN

    scene, rm = _floor(DRIVE)
    nav = Navigator(scene, rm, GOAL, NavOptions(fov=180.0))
    nobody = nav.step(0.0, POSE, np.zeros((0, 5)))
    assert nav.last.mode != NavMode.LOOK  # the back never seen, but nobody known there
    nav = Navigator(scene, rm, GOAL, NavOptions(fov=180.0))
    traj = nav.step(0.0, POSE, WALKER[None])
    assert nav.last.mode == NavMode.LOOK
    w = traj.waypoints
    assert _unicycle_problem(scene.robot, w) is None and check_trajectory(scene, w).valid
    assert np.all(w[:, 1:3] == POSE[:2])  # in place
    sector = math.radians(125.0)  # the walker's (10-degree sectors: 120-130)
    assert w[1, 3] == pytest.approx(sector - math.pi / 2 + TURN_MARGIN)  # 45 degrees, no more
    assert abs(w[1, 3]) / (w[1, 0] - w[0, 0]) <= 1.0 + 1e-9
    assert nobody.at(1.0)[2] == pytest.approx(0.0)  # it drives on east


def test_a_turn_look_is_refused_when_someone_walks_at_the_robot_or_the_sweep_hits_a_wall():
    scene, rm = _floor(DRIVE)
    nav = Navigator(scene, rm, GOAL, NavOptions(fov=180.0))
    nav._lookout.observe(0.0, POSE)
    stand = Trajectory(np.array([[0.0, *POSE], [1.0, *POSE]]), 0.3)
    assert nav._lookout.turn_look(nav, 0.0, POSE, WALKER[None], stand) is not None
    at_robot = np.array([[2.4, 3.8, 0.6, -0.8, 0.3]])  # same side, walking into the robot
    assert nav._lookout.turn_look(nav, 0.0, POSE, at_robot, stand) is None
    # a long footprint 0.2 m from a wall on its left: any turn sweeps its corners into it
    robot = {"footprint": [[0.4, 0.15], [-0.4, 0.15], [-0.4, -0.15], [0.4, -0.15]], "vmax": 1.0,
             "kinematics": "unicycle", "wmax": 1.0}  # fmt: skip
    wall = {"box": {"center": [3.0, 3.7], "size": [4.0, 1.0]}}  # its south face at y = 3.2
    scene, rm = _floor(robot, [wall])
    nav = Navigator(scene, rm, GOAL, NavOptions(fov=180.0))
    nav._lookout.observe(0.0, POSE)
    far = np.array([[0.5, 4.8, 0.8, -0.6, 0.3]])  # behind-left, beyond the wall's end, coming
    assert nav._lookout.turn(0.0, POSE, far) is not None
    assert nav._lookout.turn_look(nav, 0.0, POSE, far, stand) is None


def test_the_turn_look_reveals_a_walker_behind_then_the_robot_drives_on():
    """Closed loop, 0.25 s a step: the robot turns until the walker behind-left, whom a
    view about its heading (east) does not take in, is in view, then plans on."""
    from gfuzzy.check.check import _unicycle_problem
    from gfuzzy.navigation.crowdpolicies import piece_of
    from gfuzzy.navigation.sensing import in_fov

    scene, rm = _floor(DRIVE)
    nav = Navigator(scene, rm, GOAL, NavOptions(fov=180.0))
    pose, rows, modes, seen = POSE.copy(), [np.array([0.0, *POSE])], [], None
    assert not in_fov(pose[:2], pose[2], _walker_at(0.0)[:, :2], 180.0)[0]
    for k in range(24):
        t = 0.25 * k
        if seen is None and in_fov(pose[:2], pose[2], _walker_at(t)[:, :2], 180.0)[0]:
            seen = t
        traj = nav.step(t, pose, _walker_at(t))
        modes.append(nav.last.mode)
        piece = piece_of(traj, t, t + 0.25)
        rows.extend(piece[1:])
        pose = piece[-1, 1:].copy()
    assert modes[0] == NavMode.LOOK and seen is not None and seen <= 1.0
    assert NavMode.LOOK not in modes[int(seen / 0.25) + 1 :]  # seen: no more looks at them
    assert pose[0] > POSE[0] + 1.0  # and on towards the goal
    w = np.array(rows)
    assert _unicycle_problem(scene.robot, w[np.r_[True, np.diff(w[:, 0]) > 1e-9]]) is None
