"""The searches' effort adapted to the budget's pressure (gfuzzy/navigation/effort.py)."""

from __future__ import annotations

import numpy as np
import pytest

from gfuzzy.errors import InputError
from gfuzzy.navigation.effort import BACKOFF, RECOVER, ROOM, Effort
from gfuzzy.navigation.navigator import Navigator, NavOptions

PERSON = np.array([[2.0, 0.0, 0.0, 0.0, 0.3]])  # standing aside, within the robot's reach


def _spied(nav: Navigator) -> list:
    """The effort (path space, plan slack, prediction horizon) of every field the searches build."""
    seen = []
    field = nav._field

    def spy(*args, **kwargs):
        seen.append((nav.options.path_space, nav.options.plan_slack, nav.options.prediction_horizon))
        return field(*args, **kwargs)

    nav._field = spy
    return seen


def _clocked(nav: Navigator, tick: list) -> None:
    """A fake budget clock that advances by ``tick[0]`` at every reading."""
    now = [0.0]

    def clock():
        now[0] += tick[0]
        return now[0]

    nav._clock = clock


def test_a_call_out_of_time_cuts_the_next_searches_effort_until_calls_have_room(open_square):
    """On a slow computer the searches ran out of the budget call after call and the evasive
    motion answered (20 people: a call in two or three). After a call whose searches ran out
    of time the next searches drop the path space (one search without the ghosts), after a
    second also half the plan slack, the people predicted as before; after ``RECOVER``
    calls that finished with room one level of effort returns. The old code searched with
    full effort again (and ran out again)."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=0.1))
    seen, tick = _spied(nav), [0.05]  # every reading of the clock 50 ms later: the calls run out
    _clocked(nav, tick)
    for k in range(2):
        nav.step(0.25 * k, np.array([0.0, -4.0]), PERSON)
        assert nav.last.out_of_time and nav.last.mode == "evasive"
    tick[0] = 1e-6  # from now on the calls have room
    efforts = []
    for k in range(2, 2 * RECOVER + 4):
        del seen[:]
        nav.step(0.25 * k, np.array([0.0, -4.0]), PERSON)
        assert not nav.last.out_of_time and nav.last.mode in ("plan", "close")
        efforts.append(seen[0])
        assert (nav.options.path_space, nav.options.plan_slack) == (1.25, 8.0)  # the checks keep the full options
    assert efforts[:RECOVER] == [(0.0, 4.0, 5.0)] * RECOVER
    assert efforts[RECOVER : 2 * RECOVER] == [(0.0, 8.0, 5.0)] * RECOVER
    assert efforts[2 * RECOVER :] == [(1.25, 8.0, 5.0)] * 2


def test_without_effort_levels_every_search_has_full_effort(open_square):
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 4.0), NavOptions(time_budget=0.1, effort_levels=0))
    seen, tick = _spied(nav), [0.05]
    _clocked(nav, tick)
    nav.step(0.0, np.array([0.0, -4.0]), PERSON)
    assert nav.last.out_of_time
    tick[0] = 1e-6
    nav.step(0.25, np.array([0.0, -4.0]), PERSON)
    assert seen[-1] == (1.25, 8.0, 5.0)


def test_a_return_to_full_effort_that_runs_out_again_waits_twice_as_long():
    """A setting whose full effort never fits would pay an evasion every few calls: each
    return that runs out of time within ``RECOVER`` calls doubles the calls with room the
    next needs (up to ``BACKOFF`` times); ``RECOVER`` calls that fit at the returned level
    reset it. A call without room (over ``ROOM`` of the searches' share) restarts the count."""
    effort = Effort(NavOptions(effort_levels=2))
    room, tight = (ROOM * 0.075 / 2, 0.075), (0.9 * 0.075, 0.075)
    effort.record(True, 0.1, 0.075)
    effort.record(True, 0.1, 0.075)
    effort.record(True, 0.1, 0.075)
    assert effort.level == 2  # no further than the levels
    for _ in range(RECOVER - 1):
        effort.record(False, *room)
    effort.record(False, *tight)  # no room: the count starts again
    for _ in range(RECOVER):
        effort.record(False, *room)
    assert effort.level == 1
    effort.record(True, 0.1, 0.075)  # the return ran out at once
    assert effort.level == 2
    for _ in range(2 * RECOVER - 1):
        effort.record(False, *room)
    assert effort.level == 2
    effort.record(False, *room)
    assert effort.level == 1
    for _ in range(RECOVER):  # the returned level fits: back to RECOVER calls
        effort.record(False, *tight)
    for _ in range(RECOVER):
        effort.record(False, *room)
    assert effort.level == 0
    waits = []  # the backoff is bounded: each return runs out of time at once
    effort.record(True, 0.1, 0.075)
    for _ in range(8):
        calls = 0
        while effort.level == 1:
            effort.record(False, *room)
            calls += 1
        waits.append(calls)
        effort.record(True, 0.1, 0.075)  # back at full effort, out of time again
    # the first wait is already doubled (the return to level 0 above ran out at once): 8, 16, 32, 32, ...
    assert waits == [2 * RECOVER, 4 * RECOVER] + [RECOVER * BACKOFF] * 6


@pytest.mark.parametrize("levels", [-1, 1.5, True, 9])
def test_a_bad_effort_levels_is_refused(levels):
    with pytest.raises(InputError, match="effort_levels"):
        NavOptions(effort_levels=levels)
