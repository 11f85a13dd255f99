"""The priced search (gfuzzy.timespace.soft_kernel) and the navigator's switch to it (issue 19).

A corridor of points 0.1 m apart (one step each at 1 m/s, dt 0.1) crossed at x = 1 by a
person walking across it. The hard field is the person's disc; the soft field the same
disc widened by 0.5 m (their way, their personal space). The priced search must never
enter a hard-unsafe (point, step); with no price it arrives as early as the safe-interval
search among the hard field, with a large price as late as the one among the soft field
(it yields), and in between it pays for a short crossing instead of a long wait.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.navigation.navigator import SEARCH_SHARE, Navigator, NavOptions
from gfuzzy.scene.scene import parse_scene
from gfuzzy.status import Status
from gfuzzy.timespace.soft_kernel import soft_search
from gfuzzy.timespace.spacetime import IntervalStore
from gfuzzy.timespace.timespace import MoverField, SpaceTimeGraph, sipp

N = 31  # points x = 0.0 .. 3.0


def _corridor():
    xs = np.linspace(0.0, 3.0, N)
    poses = np.column_stack([xs, np.full(N, 1.0)])
    nbrs, indptr = [], [0]
    for i in range(N):
        nbrs += [j for j in (i - 1, i + 1) if 0 <= j < N]
        indptr.append(len(nbrs))
    h = (N - 1 - np.arange(N)).astype(float)
    return SpaceTimeGraph(poses=poses, indptr=np.array(indptr), neighbors=np.array(nbrs), heuristic=h)


def _fields(speed: float = 0.5, steps: int = 120, start_y: float = 2.5):
    """The person walks down x = 1.5 from ``start_y`` at ``speed``; hard: their disc, soft: 0.5 m wider."""
    scene = parse_scene({"version": 1, "name": "cross", "bounds": [-1, -1, 4, 4], "robot": {"disc": 0.2, "vmax": 1.0},
                         "movers": [{"name": "p", "disc": 0.3, "speed": speed, "path": [[1.5, start_y], [1.5, -30.0]], "mode": "once"}]})
    hard = MoverField(scene, 0.0, 0.1, steps, 1.0)
    soft = MoverField(scene, 0.0, 0.1, steps, 1.0, clearance=0.5)
    hard.compiled = soft.compiled = True
    return hard, soft


def _steps_at(res):
    """(node, step) of every step of the answer, the waits included."""
    out = []
    for k in range(len(res.nodes)):
        last = res.steps[k + 1] if k + 1 < len(res.nodes) else res.steps[k] + 1
        out += [(res.nodes[k], s) for s in range(res.steps[k], last)]
    return out


def _unsafe(graph, field_, visits):
    store = IntervalStore(graph)
    store.set_horizon(field_, pool=True)
    bad = 0
    for v, s in visits:
        starts, ends, _ = store.get(v)
        bad += not any(a <= s <= b for a, b in zip(starts, ends, strict=True))
    return bad


def _sipp_arrival(graph, field_):
    res = sipp(graph, field_, 0, N - 1)
    assert res.status == Status.SOLVED
    return res.steps[-1]


def test_free_price_arrives_as_the_hard_search():
    graph = _corridor()
    hard, soft = _fields()
    res = soft_search(graph, hard, soft, 0, N - 1, 0.0)
    assert res.status == Status.SOLVED
    assert res.steps[-1] == _sipp_arrival(graph, hard)
    assert _unsafe(graph, hard, _steps_at(res)) == 0


def test_high_price_yields_as_the_soft_search():
    graph = _corridor()
    hard, soft = _fields()
    res = soft_search(graph, hard, soft, 0, N - 1, 100.0)
    assert res.status == Status.SOLVED
    assert res.steps[-1] == _sipp_arrival(graph, soft) > _sipp_arrival(graph, hard)
    assert _unsafe(graph, soft, _steps_at(res)) == 0


def test_moderate_price_crosses_when_yielding_costs_more():
    """A slow walker: waiting for their wider way to clear costs far more steps than the few
    spent crossing it behind their disc; with a price of 0.5 s a second the search crosses
    (never into the disc), with 100 it waits."""
    graph = _corridor()
    hard, soft = _fields(speed=0.15, steps=250, start_y=1.6)
    cheap = soft_search(graph, hard, soft, 0, N - 1, 0.5)
    dear = soft_search(graph, hard, soft, 0, N - 1, 100.0)
    assert cheap.status == dear.status == Status.SOLVED
    inside = _unsafe(graph, soft, _steps_at(cheap))
    assert 0 < inside
    assert cheap.steps[-1] + 0.5 * inside < dear.steps[-1]  # the crossing was the cheaper answer
    assert _unsafe(graph, hard, _steps_at(cheap)) == 0
    assert _unsafe(graph, soft, _steps_at(dear)) == 0


def test_blocked_by_the_hard_field_finds_nothing():
    """A person standing on the corridor: no price buys a way through their disc."""
    scene = parse_scene({"version": 1, "name": "block", "bounds": [-1, -1, 4, 4], "robot": {"disc": 0.2, "vmax": 1.0},
                         "movers": [{"name": "p", "disc": 0.3, "speed": 0.0, "path": [[1.0, 1.0], [1.0, 1.5]], "mode": "once"}]})
    hard = MoverField(scene, 0.0, 0.1, 80, 1.0)
    soft = MoverField(scene, 0.0, 0.1, 80, 1.0, clearance=0.5)
    hard.compiled = soft.compiled = True
    res = soft_search(_corridor(), hard, soft, 0, N - 1, 0.0)
    assert res.status == Status.NO_PATH


def test_intrusion_cost_is_checked():
    with pytest.raises(ValueError, match="intrusion_cost"):
        NavOptions(soft_search=True, intrusion_cost=-1.0)


@pytest.fixture(scope="module")
def open_square():
    from test_pathspace import _scene

    import gfuzzy

    scene = _scene()
    return scene, gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=300, seed=4))


def test_the_navigator_yields_only_where_yielding_is_cheap(open_square):
    """The walker of test_pathspace's crossing (due at the robot's straight way in 2.5 s):
    priced at nothing the plan is the search's without the zones (it crosses in front of
    them); priced high it lets them pass, as the tier that forbids their way; priced low it
    crosses, where the tiers would forbid the way unless it cost 5 s."""
    from test_pathspace import _intrusions

    scene, rm = open_square
    pose, goal = np.array([0.0, -3.0]), (0.0, 3.0)
    person = np.array([-2.5, -2.0, 1.0, 0.0, 0.3])
    bare = Navigator(scene, rm, goal, NavOptions(path_space=0.0, personal_space=0.0, time_budget=5.0))
    crossing = bare.step(0.0, pose, person[None])
    ways, ends = {}, {}
    for cost in (0.0, 0.5, 20.0):
        nav = Navigator(scene, rm, goal, NavOptions(soft_search=True, intrusion_cost=cost, time_budget=5.0))
        traj = nav.step(0.0, pose, person[None])
        assert nav.last.mode == "plan"
        ways[cost], ends[cost] = _intrusions(traj, person, 0.0), traj.t_end
    assert ways[0.0] > 0 and ends[0.0] == pytest.approx(crossing.t_end)
    assert ways[20.0] == 0 and ends[20.0] > ends[0.0] + 1.0  # it lets them pass
    assert ways[0.5] > 0 and ends[0.5] < ends[20.0]  # yielding costs more than the crossing's price


def test_a_goal_taken_is_told_before_the_priced_search(open_square, monkeypatch):
    """Someone standing on the goal: the priced search is not run (it would expand every
    reachable (point, step) to learn it, as at the first sight of people of unknown velocity)."""
    import gfuzzy.navigation.softcost as softcost
    from gfuzzy.navigation.navigator import GOAL_TAKEN

    def never(*args, **kwargs):
        raise AssertionError("the priced search ran")

    monkeypatch.setattr(softcost, "soft_search", never)
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, time_budget=5.0))
    nav.step(0.0, np.array([0.0, -3.0]), np.array([[0.0, 3.0, 0.0, 0.0, 0.3]]))
    assert nav.last.message == GOAL_TAKEN


def test_a_priced_search_out_of_time_leaves_the_rest_to_the_close_search(open_square, monkeypatch):
    import gfuzzy.navigation.softcost as softcost
    from gfuzzy.timespace.spacetime import SearchResult

    seen = []

    def slow(graph, hard, soft, start, goal, penalty, deadline, stores, clock):
        seen.append(deadline)
        return SearchResult(Status.TIMEOUT, message="planning time budget exhausted")

    monkeypatch.setattr(softcost, "soft_search", slow)
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, time_budget=5.0, budget_clock="cpu"))
    c0 = nav._clock()
    nav.step(0.0, np.array([0.0, -3.0]), np.array([[-2.5, -2.0, 1.0, 0.0, 0.3]]))
    assert nav.last.mode == "close"
    # it had only its share of the search's time (SEARCH_SHARE of the budget), the rest the close search's
    assert len(seen) == 1 and c0 < seen[0] <= c0 + softcost.SOFT_SHARE * SEARCH_SHARE * 5.0 + 1e-3


def test_two_priced_fields_add_their_prices():
    """A step unsafe in both priced fields pays both: the same field twice at 0.25 s a second
    each is the field once at 0.5; a field priced 0 changes nothing."""
    graph = _corridor()
    hard, soft = _fields(speed=0.15, steps=250, start_y=1.6)
    once = soft_search(graph, hard, soft, 0, N - 1, 0.5)
    twice = soft_search(graph, hard, (soft, soft), 0, N - 1, (0.25, 0.25))
    free = soft_search(graph, hard, (soft, hard), 0, N - 1, (0.5, 0.0))
    assert once.nodes == twice.nodes == free.nodes and once.steps == twice.steps == free.steps
    dear = soft_search(graph, hard, (hard, soft), 0, N - 1, (0.0, 100.0))
    assert dear.steps[-1] == _sipp_arrival(graph, soft)


def test_importing_the_navigator_without_the_precompiled_kernels_loads_no_numba():
    """The priced search's kernels are numba's until first called (as the search kernel's,
    imported only by its search): importing the navigator imported numba when they were not."""
    import os
    import subprocess
    import sys

    code = "import sys, gfuzzy.navigation.navigator; print('numba' in sys.modules)"
    env = {**os.environ, "GFUZZY_PRECOMPILED": "0"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    assert out.stdout.strip() == "False"


def _walker_scene(x: float, y: float, speed: float, disc: float = 0.3, heading=(0.0, 1.0)):
    """A scene of one person walking from (x, y) along ``heading`` at ``speed`` (a field's source)."""
    end = [x + 30.0 * heading[0], y + 30.0 * heading[1]]
    return parse_scene({"version": 1, "name": "w", "bounds": [-1, -1, 4, 4], "robot": {"disc": 0.2, "vmax": 1.0},
                        "movers": [{"name": "p", "disc": disc, "speed": speed, "path": [[x, y], end], "mode": "once"}]})


def _beside_the_start():
    """A person 0.05 m beyond the margin of the corridor's start, walking away at 0.8 m/s:
    the margin refuses the start, the exact first motion does not."""
    hard = MoverField(_walker_scene(0.0, 1.55, 0.8), 0.0, 0.1, 120, 1.0)
    soft = MoverField(_walker_scene(0.0, 1.55, 0.8), 0.0, 0.1, 120, 1.0, clearance=0.5)
    hard.compiled = soft.compiled = True
    return hard, soft


def test_first_motions_from_a_refused_start():
    """The margin refuses the start; the first motions (decided exactly) must leave it at
    step 0 and arrive as the safe-interval search does (no NO_PATH, no answer starting at
    the virtual start's step)."""
    graph = _corridor()
    hard, soft = _beside_the_start()
    assert _unsafe(graph, hard, [(0, 0)]) == 1  # the start is refused
    ref = sipp(graph, hard, 0, N - 1)
    assert ref.status == Status.SOLVED and ref.steps[:3] == [0, 1, 2]
    for price in (0.0, 1.0):
        res = soft_search(graph, hard, soft, 0, N - 1, price)
        assert res.status == Status.SOLVED, price
        assert res.nodes[:3] == [0, 1, 2] and res.steps[:3] == [0, 1, 2], price
        assert res.steps[-1] == ref.steps[-1] == N - 1
        assert _unsafe(graph, hard, [s for s in _steps_at(res) if s[1] > 0]) == 0


def _fork():
    """start 0 with two ways to the goal 4: through 1 (two steps) or through 2 and 3 (three)."""
    poses = np.array([[0.0, 1.0], [0.1, 1.0], [-0.1, 1.0], [-0.1, 0.9], [0.1, 0.9]])
    adj = ((1, 2), (0, 4), (0, 3), (2, 4), (1, 3))
    indptr = np.concatenate([[0], np.cumsum([len(a) for a in adj])])
    return SpaceTimeGraph(poses=poses, indptr=indptr, neighbors=np.array([v for a in adj for v in a]),
                          heuristic=np.array([2.0, 1.0, 2.0, 1.0, 0.0]))  # fmt: skip


def test_a_first_motion_from_a_refused_start_pays_its_price():
    """From a refused start, the first motion to point 1 at step 1 is priced (someone hurries
    past it then): at 3 s a second, waiting a step at the start (or the longer way) and
    arriving a step later is cheaper than the price, and nothing priced is entered."""
    graph = _fork()
    hard = MoverField(_walker_scene(0.0, 1.55, 0.8), 0.0, 0.1, 40, 1.0)
    soft = MoverField(_walker_scene(0.5, 0.6, 4.0, disc=0.05), 0.0, 0.1, 40, 1.0)
    hard.compiled = soft.compiled = True
    assert _unsafe(graph, hard, [(0, 0)]) == 1  # the start is refused
    assert _unsafe(graph, soft, [(1, 1)]) == 1 and _unsafe(graph, soft, [(1, 2), (2, 1), (4, 2), (4, 3)]) == 0
    ref = sipp(graph, hard, 0, 4)
    assert ref.steps == [0, 1, 2]
    free = soft_search(graph, hard, soft, 0, 4, 0.0)
    assert free.steps[-1] == 2
    dear = soft_search(graph, hard, soft, 0, 4, 3.0)
    assert dear.status == Status.SOLVED and dear.steps[-1] == 3
    assert _unsafe(graph, soft, [s for s in _steps_at(dear) if s[1] > 0]) == 0


def test_a_search_that_reaches_its_horizon_says_so():
    """A person on the corridor, stepping off it slowly (after about 12 s): with 80 steps the search finds
    nothing and says its horizon was reached (so the navigator retries with a longer one);
    with 250 it passes once they have gone."""
    graph = _corridor()
    scene = parse_scene({"version": 1, "name": "late", "bounds": [-1, -1, 4, 4], "robot": {"disc": 0.2, "vmax": 1.0},
                         "movers": [{"name": "p", "disc": 0.3, "speed": 0.05, "path": [[1.0, 1.0], [1.0, 2.5]],
                                     "mode": "once"}]})  # fmt: skip
    fields = {}
    for steps in (80, 250):
        hard = MoverField(scene, 0.0, 0.1, steps, 1.0)
        soft = MoverField(scene, 0.0, 0.1, steps, 1.0, clearance=0.5)
        hard.compiled = soft.compiled = True
        fields[steps] = soft_search(graph, hard, soft, 0, N - 1, 1.0)
    assert fields[80].status == Status.NO_PATH and fields[80].horizon_hit
    assert fields[250].status == Status.SOLVED


def _closest(traj, person) -> float:
    """The plan's least distance (centre to centre) from a person standing still."""
    ts = np.linspace(0.0, traj.t_end, 400)
    return min(float(np.hypot(*(traj.at(t)[:2] - person[:2]))) for t in ts)


def _plan(scene, rm, person, **opts):
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, time_budget=5.0, **opts))
    traj = nav.step(0.0, np.array([0.0, -3.0]), person[None])
    assert nav.last.mode == "plan"
    return traj


def test_the_personal_space_is_priced(open_square):
    """Someone standing 0.75 m beside the robot's straight way (no way of theirs to keep off):
    free, the plan goes straight past them, inside their personal space; dear, it keeps out
    of it, in the one-field mode and with the personal space priced on its own
    (``discomfort_cost``)."""
    scene, rm = open_square
    person = np.array([0.75, 0.0, 0.0, 0.0, 0.3])
    opts = NavOptions()
    space = 2 * scene.robot.circumradius + opts.safety_buffer + opts.personal_space  # 0.85 m centre to centre
    free = _closest(_plan(scene, rm, person, intrusion_cost=0.0), person)
    assert free < space
    assert _closest(_plan(scene, rm, person, intrusion_cost=20.0), person) >= space
    assert _closest(_plan(scene, rm, person, intrusion_cost=0.0, discomfort_cost=20.0), person) >= space
    assert _closest(_plan(scene, rm, person, intrusion_cost=20.0, discomfort_cost=0.0), person) < space


def test_with_discomfort_cost_the_ways_keep_their_own_price(open_square):
    """test_the_navigator_yields_only_where_yielding_is_cheap's walker with the personal space
    priced apart: the ways dear and the personal space free, the robot lets them pass; the
    ways free, it crosses in front of them."""
    from test_pathspace import _intrusions

    scene, rm = open_square
    person = np.array([-2.5, -2.0, 1.0, 0.0, 0.3])
    dear = _plan(scene, rm, person, intrusion_cost=20.0, discomfort_cost=0.0)
    free = _plan(scene, rm, person, intrusion_cost=0.0, discomfort_cost=0.0)
    assert _intrusions(dear, person, 0.0) == 0 and dear.t_end > free.t_end + 1.0
    assert _intrusions(free, person, 0.0) > 0


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "x"])
def test_discomfort_cost_is_checked(bad):
    with pytest.raises(ValueError, match="discomfort_cost"):
        NavOptions(soft_search=True, discomfort_cost=bad)


def test_a_robot_in_someones_way_pays_from_the_first_step(open_square):
    """The tiers, which forbid a person's way, give a robot standing in it time to step out
    (the ghosts over it appear later, test_pathspace); priced, there is no such window: the
    ghosts over the robot count from now."""
    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True))
    obs = np.array([[0.0, 0.0, 1.0, 0.0, 0.3]])
    pose = np.array([1.5, 0.0])  # ahead of them, in their way
    forbidden, _ = nav._path_ghosts(pose, obs)
    ((rows, _),), prices = nav._priced_zones(pose, obs)
    assert prices == [nav.options.intrusion_cost]
    ghosts = rows[len(obs):]
    over = np.hypot(*(ghosts[:, :2] - pose).T) < nav.robot.circumradius + ghosts[:, 4] + 0.3
    assert over.any() and np.all(ghosts[over, 5] == 0.0)
    f_over = np.hypot(*(forbidden[:, :2] - pose).T) < nav.robot.circumradius + forbidden[:, 4] + 0.3
    assert np.all(forbidden[f_over, 5] > 0)  # (the tiers' window)


def test_a_search_out_of_horizon_is_retried_with_twice_the_slack(open_square, monkeypatch):
    """When the priced search reaches its horizon without an answer, the navigator searches
    again with twice the slack past the roadmap's estimate (and that answer stands)."""
    import gfuzzy.navigation.softcost as softcost
    from gfuzzy.timespace.spacetime import SearchResult

    real, horizons = softcost.soft_search, []

    def short_first(graph, hard, soft, start, goal, *args):
        horizons.append((hard.steps, float(graph.heuristic[start])))
        if len(horizons) == 1:
            return SearchResult(Status.NO_PATH, message="the search horizon was reached", horizon_hit=True)
        return real(graph, hard, soft, start, goal, *args)

    monkeypatch.setattr(softcost, "soft_search", short_first)
    scene, rm = open_square
    opts = NavOptions(soft_search=True, time_budget=5.0)
    nav = Navigator(scene, rm, (0.0, 3.0), opts)
    nav.step(0.0, np.array([0.0, -3.0]), np.array([[-2.5, -2.0, 1.0, 0.0, 0.3]]))
    assert nav.last.mode == "plan" and len(horizons) == 2
    (first, h0), (second, _) = horizons
    slack = (opts.plan_slack + opts.prediction_horizon) / opts.dt
    assert first == math.ceil(h0 + slack) and second == math.ceil(h0 + 2 * slack)


@pytest.mark.parametrize("backend", ["compiled", "reference"])
def test_the_priced_search_is_warmed_whatever_the_backend(open_square, monkeypatch, backend):
    """The priced search runs numba's kernels with either backend: a navigator with
    ``soft_search`` loads them when it is built, not inside its first step's budget (with
    the reference backend the first step took 391 ms and answered evasive)."""
    import gfuzzy.timespace.soft_kernel as soft_kernel

    calls = []
    monkeypatch.setattr(soft_kernel, "warm", lambda: calls.append(1))
    scene, rm = open_square
    Navigator(scene, rm, (0.0, 3.0), NavOptions(backend=backend))
    assert calls == []
    Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, backend=backend))
    assert calls == [1]


def _priced_answer(monkeypatch, nav, rows) -> None:
    """The priced search answers ``rows`` (from the graph and start it spliced)."""
    from gfuzzy.navigation.navtypes import _Searched
    from gfuzzy.navigation.softcost import SoftCost
    from gfuzzy.trajectory import Trajectory

    real = SoftCost._soft_plan

    def answer(self, *args, **kwargs):
        found = real(self, *args, **kwargs)
        return _Searched(Trajectory(rows, nav.robot.circumradius), "", found.detailed, False, found.graph, found.start)

    monkeypatch.setattr(SoftCost, "_soft_plan", answer)


def test_the_last_priced_plan_is_kept_when_the_fresh_one_costs_more(open_square, monkeypatch):
    """A fresh search spliced from a slightly different pose went back to a roadmap vertex
    before going on, arriving 0.5 s later: the robot undid its last move every period,
    0.4 m from a goal two people stood beside (softcost2, 20 invisible, episode 55). The
    last plan, as safe and cheaper at the price, is kept (the old test asked it to arrive
    the soft costs, 5.5 s, sooner)."""
    scene, rm = open_square
    far = np.array([[4.5, -4.5, 0.0, 0.0, 0.3]])  # someone standing far away: the priced search runs
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, time_budget=5.0))
    first = nav.step(0.0, np.array([0.0, -3.0]), far)
    assert nav.last.mode == "plan"
    t = 0.25
    pose = first.at(t)
    w = first.waypoints
    back = np.vstack([[t, *pose], [t + 0.25, *w[0, 1:]], w + [0.5, 0.0, 0.0]])  # back to the start, then as before
    _priced_answer(monkeypatch, nav, back)
    traj = nav.step(t, pose, far)
    assert nav.last.mode == "kept"
    assert traj.t_end == pytest.approx(first.t_end)
    assert np.allclose(traj.at(t + 0.25), first.at(t + 0.25))


def test_a_fresh_plan_cheaper_at_the_price_replaces_the_last(open_square, monkeypatch):
    """The rule keeps the last plan only while it is as good: the same fresh plan 0.2 s
    sooner (the last one re-timed) is taken."""

    scene, rm = open_square
    far = np.array([[4.5, -4.5, 0.0, 0.0, 0.3]])
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, time_budget=5.0))
    first = nav.step(0.0, np.array([0.0, -3.0]), far)
    t = 1.0
    pose = first.at(t)
    w = first.waypoints[first.waypoints[:, 0] > t + 1e-6]
    sooner = np.vstack([[t, *pose], w - [0.2, 0.0, 0.0]])  # the rest of it, 0.2 s sooner (a faster first leg)
    _priced_answer(monkeypatch, nav, sooner)
    traj = nav.step(t, pose, far)
    assert nav.last.mode == "plan"
    assert traj.t_end == pytest.approx(first.t_end - 0.2)


def test_the_price_is_halved_while_the_planned_arrival_slips(open_square, monkeypatch):
    """A robot that does not get on with its plan (held at its start: the arrival slips a
    second per second, as among a stream of people each plan yields again) has its price
    halved after SLIP_WINDOW s, and again while it goes on slipping; a fixed price never
    escalated (softcost2, 20 visible, episode 32: the arrival slipped from 17.4 s to 27.5 s)."""
    import gfuzzy.navigation.softcost as softcost

    seen = []
    real = softcost.soft_search

    def spy(graph, hard, soft, start, goal, prices, *args):
        seen.append(tuple(prices))
        return real(graph, hard, soft, start, goal, prices, *args)

    monkeypatch.setattr(softcost, "soft_search", spy)
    scene, rm = open_square
    far = np.array([[4.5, -4.5, 0.0, 0.0, 0.3]])
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, intrusion_cost=4.0, time_budget=5.0))
    for t in np.arange(0.0, 7.0, 0.5):  # two windows of SLIP_WINDOW (3 s) and a half
        nav.step(float(t), np.array([0.0, -3.0]), far)
        assert nav.last.mode == "plan"
    prices = [p[0] for p in seen]
    assert prices[0] == 4.0 and prices == sorted(prices, reverse=True)
    assert prices[-1] == 1.0  # halved twice: it slipped over two windows


def test_a_lowered_price_is_doubled_back_once_the_arrival_holds(open_square):
    import gfuzzy.navigation.softcost as softcost

    scene, rm = open_square
    nav = Navigator(scene, rm, (0.0, 3.0), NavOptions(soft_search=True, intrusion_cost=4.0, time_budget=5.0))
    nav._price_scale = 0.25
    nav._arrivals = ((0.0, 10.0), (softcost.SLIP_WINDOW, 10.0 + softcost.SLIP_LIMIT - 0.1))
    nav._price_slip(softcost.SLIP_WINDOW + 0.5)
    assert nav._price_scale == 0.5
    nav._arrivals = ((4.0, 10.0), (4.0 + softcost.SLIP_WINDOW, 10.0))
    nav._price_slip(4.5 + softcost.SLIP_WINDOW)
    nav._arrivals = ((8.0, 10.0), (8.0 + softcost.SLIP_WINDOW, 10.0))
    nav._price_slip(8.5 + softcost.SLIP_WINDOW)
    assert nav._price_scale == 1.0  # never above the set price
    assert nav._priced_zones(np.array([0.0, -3.0]), np.array([[4.5, -4.5, 0.0, 0.0, 0.3]]))[1] == [4.0]
