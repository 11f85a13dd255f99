"""A disc robot with a field of view looks where it has not looked (gfuzzy.navigation.lookout)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import unhurried

from gfuzzy.errors import InputError
from gfuzzy.navigation.lookout import EMPTY_FACTOR, LOOK_SPEED, LOOK_TIME, Lookout, knowing_view
from gfuzzy.navigation.navigator import Navigator, NavOptions
from gfuzzy.navigation.navtypes import NavMode

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
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried(fov=180.0))
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
    nav = Navigator(scene, rm, (0.0, 4.0), unhurried())
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
