"""Keeping the last plan through the predictions' wobble (:mod:`gfuzzy.navigation.steady`):
people's velocities averaged over the last calls, and the last plan kept over a fresh
one that arrives no sooner."""

from __future__ import annotations

import numpy as np
import pytest

from gfuzzy.errors import InputError
from gfuzzy.navigation.drivenav import _if_safe
from gfuzzy.navigation.navigator import Navigator, NavOptions, _Searched
from gfuzzy.navigation.navtypes import NavMode
from gfuzzy.navigation.steady import RecentWalks, steady_plan
from gfuzzy.trajectory import Trajectory

GOAL = (0.0, 4.0)
FAR = np.array([[4.0, 0.0, 0.0, 0.0, 0.3]])  # someone standing well off the straight line


def _tie(first: Trajectory, t: float, pose) -> Trajectory:
    """Another plan from ``pose`` at ``t``, arriving when ``first`` does (0.2 m to the side
    half-way): what a fresh search finds when the predictions only wobbled."""
    mid = 0.5 * (np.asarray(pose, float)[:2] + np.asarray(GOAL)) + np.array([0.2, 0.0])
    rows = [[t, *pose], [0.5 * (t + first.t_end), *mid], [first.t_end, *GOAL]]
    return Trajectory(np.array(rows), first.circumradius)


def test_recent_walks_average_each_person_over_the_last_calls():
    rw = RecentWalks(3)
    walker = lambda t, v: [0.25 * t, 1.0, *v, 0.3]  # noqa: E731 (its position matters little: one person)
    other = [3.0, -2.0, 0.0, 0.5, 0.3]
    out = rw.update(0.0, np.array([walker(0, (1.0, 0.0)), other]))
    np.testing.assert_allclose(out, [[1.0, 0.0], [0.0, 0.5]])
    rw.update(0.25, np.array([other[:1] + [-1.875] + other[2:], walker(1, (0.6, 0.0))]))  # rows swapped
    rw.update(0.5, np.array([walker(2, (0.2, 0.0)), [3.0, -1.75, 0.0, 0.5, 0.3]]))
    out = rw.update(0.75, np.array([walker(3, (0.4, 0.3)), [3.0, -1.625, 0.0, 0.5, 0.3], [-3.0, 0.0, 0.7, 0.0, 0.3]]))
    # the last three of each (the rows' order does not matter), a newcomer's own
    np.testing.assert_allclose(out, [[0.4, 0.1], [0.0, 0.5], [0.7, 0.0]])
    # a velocity not known yet (seen once, reported standing) is not averaged in
    rw = RecentWalks(3)
    rw.update(0.0, np.array([[0.0, 0.0, 0.0, 0.0, 0.3]]), np.array([True]))
    out = rw.update(0.25, np.array([[0.0, 0.0, 0.8, 0.0, 0.3]]), np.array([False]))
    np.testing.assert_allclose(out, [[0.8, 0.0]])
    with pytest.raises(InputError):
        NavOptions(steady_calls=-1)


def test_the_last_plan_is_kept_over_a_fresh_one_that_arrives_no_sooner(open_square, monkeypatch):
    sc, rm = open_square
    navs = {calls: Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, steady_calls=calls)) for calls in (3, 0)}
    for calls, nav in navs.items():
        first = nav.step(0.0, (0.0, -4.0), FAR)
        assert nav.last.mode in (NavMode.PLAN, NavMode.CLOSE)
        pose = first.at(0.25)
        with monkeypatch.context() as m:
            m.setattr(Navigator, "_search", lambda self, t, p, *a, first=first, **k: _Searched(_tie(first, t, p)))
            again = nav.step(0.25, pose, FAR)
        if calls:  # the robot goes on as it was going
            assert nav.last.mode == NavMode.KEPT
            times = np.linspace(0.25, first.t_end, 100)
            np.testing.assert_allclose(again.at(times), first.at(times), atol=1e-9)
        else:  # off: the fresh plan answers
            assert nav.last.mode != NavMode.KEPT
            assert np.hypot(*(again.at(0.5 * (0.25 + first.t_end)) - first.at(0.5 * (0.25 + first.t_end)))) > 0.1
    # a fresh plan that arrives sooner answers
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, steady_calls=3))
    first = nav.step(0.0, (0.0, -4.0), FAR)
    pose = first.at(0.25)
    sooner = Trajectory(np.array([[0.25, *pose], [first.t_end - 0.1, *GOAL]]), first.circumradius)
    monkeypatch.setattr(Navigator, "_search", lambda self, t, p, *a, **k: _Searched(sooner))
    nav.step(0.25, pose, FAR)
    assert nav.last.mode != NavMode.KEPT


def test_the_last_plan_is_not_kept_when_someone_walking_now_would_meet_it(open_square):
    """The recent mean velocity keeps the predictions steady; the velocity now still rules
    out a kept plan that would not keep its gaps from someone walking on as they walk now."""
    sc, rm = open_square
    nav = Navigator(sc, rm, GOAL, NavOptions(time_budget=5.0, steady_calls=3))
    standing = np.array([[3.0, -1.6, 0.0, 0.0, 0.3]])
    first = nav.step(0.0, (0.0, -4.0), standing)
    pose = first.at(0.25)
    walking = np.array([[3.0, -1.6, -1.2, 0.0, 0.3]])  # now walking across the plan, meeting it
    walks = nav._recent.update(0.25, walking)
    np.testing.assert_allclose(walks, [[-0.6, 0.0]])
    infl = nav._inflation(pose, walking)
    steady = walking.copy()
    steady[:, 2:4] = walks
    assert _if_safe(nav, first, 0.25, pose, steady, infl) is not None  # the mean velocity alone would keep it
    assert _if_safe(nav, first, 0.25, pose, walking, infl) is None
    assert steady_plan(nav, 0.25, pose, walking, walks, infl, _tie(first, 0.25, pose)) is None
