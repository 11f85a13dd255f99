"""gfuzzy.planner.straighten: fewer corners for a differential drive, every motion certified."""

from __future__ import annotations

import math

import numpy as np

from gfuzzy.check.check import check_trajectory
from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.planner.driveretime import retime_drive
from gfuzzy.planner.straighten import corners, straighten
from gfuzzy.scene.scene import Query, parse_scene
from gfuzzy.timespace.drive import turn_path


def _scene(obstacles=()):
    return parse_scene({
        "version": 1, "name": "st", "bounds": [0, 0, 8, 4],
        "robot": {"box": [0.6, 0.4], "vmax": 1.0, "kinematics": "unicycle"},
        "obstacles": list(obstacles), "movers": [], "queries": [],
    })  # fmt: skip


START, GOAL = np.array([1.0, 1.0, 0.0]), np.array([7.0, 1.0, math.pi / 2])
ZIGZAG = np.array([[2.0, 1.2], [3.0, 0.9], [4.0, 1.3], [5.0, 0.8], [6.0, 1.1]])


def test_a_zigzag_in_the_open_becomes_one_straight():
    scene = _scene()
    path = turn_path(START, ZIGZAG, GOAL)
    assert len(corners(path)) == 7
    out = straighten(StaticGeometry(scene), path)
    assert len(corners(out)) == 2  # start and goal: one straight between them
    np.testing.assert_array_equal(out[0], START)
    np.testing.assert_array_equal(out[-1], GOAL)


def test_a_wall_keeps_a_corner_and_every_motion_is_certified():
    # a wall between the start and the goal with a gap above it
    scene = _scene([{"box": {"center": [4.0, 1.0], "size": [0.2, 2.0]}}])
    via = np.array([[3.0, 2.7], [5.0, 2.7]])
    path = turn_path(START, np.vstack([[2.0, 1.6], via, [6.0, 1.5]]), GOAL)
    geometry = StaticGeometry(scene)
    assert all(geometry.motion_free(a, b) for a, b in zip(path[:-1], path[1:], strict=True))
    out = straighten(geometry, path)
    assert 2 < len(corners(out)) < len(corners(path))
    rt = retime_drive(scene, out, 0.0, 0.07, 2.0, 60.0)
    rep = check_trajectory(scene, rt.trajectory.waypoints, Query("q", tuple(START), tuple(GOAL), 0.0))
    assert rep.valid, rep.reason  # independent: the wall, the bounds, the row rule


def test_a_path_that_reverses_is_left_alone():
    path = np.array([[1.0, 1.0, 0.0], [2.0, 1.0, 0.0], [1.5, 1.0, 0.0], [1.5, 1.0, 1.0]])
    assert corners(path) is None
    assert straighten(StaticGeometry(_scene()), path) is path
