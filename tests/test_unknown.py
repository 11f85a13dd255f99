"""People whose velocity is not known yet (seen once) are predicted as walkers of unknown
direction (gfuzzy.navigation.unknown)."""

from __future__ import annotations

import numpy as np
import pytest

from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.sensing import UNKNOWN_CAP, UNKNOWN_GROWTH, Sensor, SensorOptions
from gfuzzy.navigation.unknown import unknown_growth, unknown_positions
from gfuzzy.scene.scene import parse_scene


def test_the_sensor_marks_who_was_seen_once():
    sensor = Sensor(_bare(), SensorOptions())
    walker = np.array([[1.0, 0.0, 0.0, 0.5, 0.3]])
    sensor.observe(0.0, np.zeros(2), 0.0, walker)
    assert sensor.unknown.tolist() == [True]  # one sighting: no velocity yet
    walker[0, 1] = 0.125
    obs = sensor.observe(0.25, np.zeros(2), 0.0, walker)
    assert sensor.unknown.tolist() == [False]
    assert obs[0, 3] == pytest.approx(0.5)
    exact = Sensor(_bare(), SensorOptions(velocity="exact"))
    exact.observe(0.0, np.zeros(2), 0.0, walker)
    assert exact.unknown.tolist() == [False]


def _bare():
    return parse_scene({
        "version": 1, "name": "s", "bounds": [-10, -10, 10, 10], "robot": {"disc": 0.3, "vmax": 1.0},
        "obstacles": [], "movers": [], "queries": [],
    })  # fmt: skip


def test_growth_is_a_walking_pace_capped_for_the_unknown_only():
    obs = np.array([[1.0, 2.0, 0.0, 0.0, 0.3], [3.0, 0.0, 0.0, 0.0, 0.3], [5.0, 0.0, 1.0, 0.0, 0.3]])
    known = unknown_positions(obs, [True, False, True])  # the walker's velocity is known after all
    assert known.tolist() == [[1.0, 2.0]]
    g = unknown_growth(known, obs, np.array([0.0, 0.5, 5.0]))
    assert g[:, 0].tolist() == pytest.approx([0.0, 0.5 * UNKNOWN_GROWTH, UNKNOWN_CAP])
    assert not g[:, 1:].any()
    assert not unknown_positions(obs, None).size


def test_the_robot_keeps_away_from_someone_of_unknown_velocity_beside_it(open_square):
    scene, rm = open_square
    person = np.array([[-0.9, -4.0, 0.0, 0.0, 0.3]])  # beside the robot, seen once
    far = []
    for unknown in (None, [True]):
        nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(budget_clock="cpu", time_budget=1.0))
        traj = nav.step(0.0, np.array([0.0, -4.0]), person, unknown)
        pts = traj.at(np.linspace(0.5, 1.0, 6))[:, :2]
        far.append(float(np.hypot(*(pts - person[0, :2]).T).min()))
    # standing, they are passed close by; walking anywhere, they are given a wide berth
    assert far[1] > far[0] + 0.25


def test_a_script_sets_the_walking_pace_in_one_place(monkeypatch):
    # the constants live in sensing; the prediction and the lookout read them when called,
    # so a measurement script that patches sensing patches all three (they were imported by
    # name, and a patch of sensing changed the tracker only)
    from gfuzzy.navigation import sensing
    from gfuzzy.navigation.lookout import Lookout

    monkeypatch.setattr(sensing, "UNKNOWN_GROWTH", 2.0)
    monkeypatch.setattr(sensing, "UNKNOWN_CAP", 1.5)
    obs = np.array([[0.0, -7.3, 0.0, 0.0, 0.3]])  # seen once, 7 m behind the robot's disc
    g = unknown_growth(obs[:, :2], obs, np.array([0.5, 5.0]))
    assert g[:, 0].tolist() == pytest.approx([1.0, 1.5])
    look = Lookout(180.0, 1.0, np.array([0.0, 4.0]))
    look.observe(0.0, np.array([0.0, 0.0]))
    look.observe(0.25, np.array([0.0, -0.05]))  # a look south
    for k in range(2, 7):
        look.observe(0.25 * k, np.array([0.0, 0.0]))  # facing north
    # within reach at 2 m/s (+ 1 m/s of the robot, 3 s: 9 m), not at 1 m/s (6 m)
    assert look.stale(1.5, np.zeros(2), obs, 1.0, obs[:, :2]).any()
    monkeypatch.setattr(sensing, "UNKNOWN_GROWTH", 1.0)
    assert not look.stale(1.5, np.zeros(2), obs, 1.0, obs[:, :2]).any()
