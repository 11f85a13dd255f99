"""The retiming chains give the same answers on both backends (``PlanOptions.backend``).

The speed layer (:func:`gfuzzy.planner.retime.retime_profile`), the refined path's timing
(:func:`retime_path`) and a differential drive's layer (:func:`retime_drive`, :func:`retime_blend`)
run the safe-interval search on a chain whose groups are pairs of points not evenly spaced
(a profile accelerates, a drive turns in place). The compiled search and its safety kernels
must answer exactly as the reference: the same status, message and waits, the same rows to
the last bit; every answer passes the independent check.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gfuzzy.check.check import check_trajectory
from gfuzzy.fuzzy.fuzzy import FuzzyOptions, expert_rules, speed_limit
from gfuzzy.planner import retime as retime_module
from gfuzzy.planner.driveblend import retime_blend
from gfuzzy.planner.driveretime import retime_drive
from gfuzzy.planner.planner import PlanOptions, plan
from gfuzzy.planner.retime import retime_path, retime_profile
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import Query, parse_scene
from gfuzzy.status import Status

ROBOTS = {
    "disc": {"disc": 0.2},
    "box": {"box": [0.5, 0.3]},
    "footprint": {"footprint": [[0.3, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.3, -0.2]]},
}
W, H = 8.0, 5.0
DT = 0.1


def random_case(seed: int, shape: str, unicycle: bool):
    """A scene of 2-5 movers, and a path of three legs among them."""
    rng = np.random.default_rng([seed, len(shape), int(unicycle)])
    point = lambda: [float(rng.uniform(0.5, W - 0.5)), float(rng.uniform(0.5, H - 0.5))]  # noqa: E731
    movers = []
    for i in range(int(rng.integers(2, 6))):
        m = {"name": f"m{i}"}
        m.update({"disc": float(rng.uniform(0.1, 0.25))} if rng.random() < 0.6 else {"box": [0.3, 0.2]})
        m.update(speed=float(rng.uniform(0.2, 1.0)), path=[point() for _ in range(2)],
                 mode=str(rng.choice(["loop", "bounce", "once"])), offset=float(rng.uniform(0, 2)))  # fmt: skip
        movers.append(m)
    robot = {**ROBOTS[shape], "vmax": 1.0, "amax": 1.5}
    if unicycle:
        robot["kinematics"] = "unicycle"
    if rng.random() < 0.3:
        robot["mover_clearance"] = 0.1
    doc = {"version": 1, "name": f"backends-{seed}", "bounds": [0, 0, W, H], "robot": robot, "movers": movers}
    scene = parse_scene(doc)
    xy = np.array([[0.6, 0.6], point(), point(), [W - 0.6, H - 0.6]])
    heads = np.arctan2(*np.diff(xy, axis=0)[:, ::-1].T)
    if unicycle:  # turns in place and straights along the heading
        rows = [[*xy[0], float(rng.uniform(-3, 3))]]
        for k, h in enumerate(heads):
            rows += [[*xy[k], h], [*xy[k + 1], h]]
        rows.append([*xy[-1], float(rng.uniform(-3, 3))])
        path = np.array(rows)
    elif shape == "disc":
        path = xy
    else:
        path = np.column_stack([xy, np.append(heads, heads[-1])])
    return scene, path


def same(a, b) -> bool:
    """Status, message, waits and rows identical (to the last bit)."""
    if a.status is not b.status or a.message != b.message or list(a.waits) != list(b.waits):
        return False
    if a.trajectory is None or b.trajectory is None:
        return a.trajectory is None and b.trajectory is None
    return np.array_equal(a.trajectory.waypoints, b.trajectory.waypoints)


def both(scene, path, t0, hold, fn):
    """``fn(backend)`` on each backend: the answers, each one checked when solved (from the
    path's start at ``t0`` to its goal, parked ``hold`` seconds)."""
    out = [fn(backend) for backend in ("reference", "compiled")]
    query = Query("q", tuple(path[0]), tuple(path[-1]), t0, hold=hold)
    for res in out:
        if res.status is Status.SOLVED:
            rep = check_trajectory(scene, res.trajectory.waypoints, query)
            assert rep.valid, rep.reason
    return out


CASES = [(seed, shape) for seed in range(4) for shape in ROBOTS]


@pytest.mark.parametrize("seed, shape", CASES)
def test_holonomic_retiming_same_on_both_backends(seed, shape):
    scene, path = random_case(seed, shape, unicycle=False)
    robot = scene.robot
    plain = both(scene, path, 0.5, 0.0, lambda b: retime_path(scene, path, 0.5, DT, 60.0, backend=b))
    assert same(*plain), (plain[0].status, plain[0].message, plain[1].status, plain[1].message)
    s_xy, v_xy = speed_limit(path[:, :2], robot.vmax, robot.amax, expert_rules(), FuzzyOptions())
    layer = both(scene, path, 0.5, 0.5, lambda b: retime_profile(scene, path, s_xy, v_xy, 0.5, DT, robot.amax, 60.0, hold=0.5,
                                                 backend=b))  # fmt: skip
    assert same(*layer), (layer[0].status, layer[0].message, layer[1].status, layer[1].message)


@pytest.mark.parametrize(  # seed 2's footprint costs 10 s (the reference's turns): `make slow`
    "seed, shape", [pytest.param(*c, marks=pytest.mark.slow) if c == (2, "footprint") else c for c in CASES]
)
def test_drive_retiming_same_on_both_backends(seed, shape):
    scene, path = random_case(seed, shape, unicycle=True)
    amax = scene.robot.amax
    plain = both(scene, path, 0.0, 0.0, lambda b: retime_path(scene, path, 0.0, DT, 60.0, backend=b))
    assert same(*plain), (plain[0].status, plain[0].message, plain[1].status, plain[1].message)
    drive = both(scene, path, 0.0, 0.5, lambda b: retime_drive(scene, path, 0.0, DT, amax, 60.0, hold=0.5, backend=b))
    assert same(*drive), (drive[0].status, drive[0].message, drive[1].status, drive[1].message)
    blend = both(scene, path, 0.0, 0.0, lambda b: retime_blend(scene, path, 0.0, DT, amax, 60.0, backend=b))
    assert same(*blend) and np.array_equal(blend[0].hasty, blend[1].hasty)


def test_the_random_cases_cover_waits_and_haste():
    """The cases above are not all trivial: some timings wait for a mover, some blends need haste."""
    waits = hasty = 0
    for seed, shape in CASES:
        scene, path = random_case(seed, shape, unicycle=True)
        b = retime_blend(scene, path, 0.0, DT, scene.robot.amax, 60.0)
        hasty += b.status is Status.SOLVED and bool(b.hasty.any())
        scene, path = random_case(seed, shape, unicycle=False)
        r = retime_path(scene, path, 0.5, DT, 60.0)
        waits += r.status is Status.SOLVED and r.trajectory.duration > math.dist(path[0, :2], path[1, :2]) + 1e-9 and bool(r.waits)
    assert waits > 0 and hasty > 0, (waits, hasty)


@pytest.mark.parametrize("unicycle, refine", [(False, False), (False, True), (True, False), (True, True)])
def test_the_stages_retime_with_the_querys_backend(monkeypatch, unicycle, refine):
    """The speed layer, the drive layer and the refinement's timing search with
    ``PlanOptions.backend`` (before, they always ran the pure-Python reference): every
    chain search asks for the query's backend, none for the default."""
    seen = []
    inner = retime_module.search_function

    def spy(backend):
        seen.append(backend)
        return inner(backend)

    monkeypatch.setattr(retime_module, "search_function", spy)
    robot = {"disc": 0.2, "vmax": 1.0, **({"kinematics": "unicycle"} if unicycle else {})}
    scene = parse_scene({"version": 1, "name": "s", "bounds": [0, 0, W, H], "robot": robot,
                         "movers": [{"name": "m", "disc": 0.2, "speed": 0.5, "path": [[4, 0.5], [4, 4.5]],
                                     "mode": "bounce"}]})  # fmt: skip
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    ends = ([0.6, 2.5, 0.0], [7.4, 2.5, 0.0]) if unicycle else ([0.6, 2.5], [7.4, 2.5])
    for backend in ("compiled", "reference"):
        seen.clear()
        opts = PlanOptions(speed_layer=True, refine=refine, backend=backend, seed=1)
        res = plan(scene, rm, *ends, options=opts)
        assert res.status is Status.SOLVED and res.speed_report.applied, res.speed_report
        assert seen and set(seen) == {backend}, seen


@pytest.mark.parametrize("unicycle", [False, True])
def test_horizon_rounds_answer_as_one_search_with_the_whole_horizon(monkeypatch, unicycle):
    """A chain's search starts with a short horizon and doubles its slack while the horizon
    cut it off (the safety kept): the same answers as one search over the whole horizon,
    which computed every point's safety over a window three times the path's duration."""
    horizons = []
    inner = retime_module.search_function

    def spy(backend):
        search = inner(backend)

        def run(graph, field_, *args, **kw):
            horizons.append(field_.steps)
            return search(graph, field_, *args, **kw)

        return run

    monkeypatch.setattr(retime_module, "search_function", spy)

    def answers():
        out = []
        for seed, shape in CASES:
            scene, path = random_case(seed, shape, unicycle)
            if unicycle:
                out.append(retime_blend(scene, path, 0.0, DT, scene.robot.amax, 60.0))
                out.append(retime_drive(scene, path, 0.0, DT, scene.robot.amax, 60.0, hold=0.5))
            else:
                s_xy, v_xy = speed_limit(path[:, :2], scene.robot.vmax, scene.robot.amax, expert_rules(), FuzzyOptions())
                out.append(retime_profile(scene, path, s_xy, v_xy, 0.5, DT, scene.robot.amax, 60.0, hold=0.5))
                out.append(retime_path(scene, path, 0.5, DT, 60.0))
        return out

    rounds = answers()
    whole = 60.0 / DT
    assert min(horizons) < whole / 2 and horizons.count(max(horizons)) < len(horizons) / 2  # mostly short rounds
    monkeypatch.setattr(retime_module, "CHAIN_SLACK_STEPS", 10**9)  # one round: the whole horizon
    horizons.clear()
    one = answers()
    assert min(horizons) >= whole
    for a, b in zip(rounds, one, strict=True):
        assert same(a, b), (a.status, a.message, b.status, b.message)
        if hasattr(a, "hasty"):
            assert np.array_equal(a.hasty, b.hasty)


def test_a_fields_prefix_is_the_field_of_the_shorter_horizon():
    """:meth:`MoverField.prefix` (the chain searches of one stage share the movers' samples)
    equals, to the last bit, the field built for the shorter horizon: path and trajectory
    movers, present or not, with a clearance."""
    doc = {"version": 1, "name": "p", "bounds": [0, 0, W, H], "robot": {"box": [0.5, 0.3], "vmax": 1.0,
           "mover_clearance": 0.1},
           "movers": [{"name": "t", "disc": 0.2, "trajectory": [[2.0, 1, 1], [3.5, 4, 1], [3.6, 4, 4], [9.0, 1, 4]]},
                      {"name": "b", "box": [0.4, 0.3], "speed": 0.7, "path": [[1, 1], [7, 4]], "mode": "bounce"},
                      {"name": "o", "disc": 0.3, "speed": 1.1, "path": [[7, 1], [1, 4], [4, 4]], "mode": "once",
                       "offset": 1.5}]}  # fmt: skip
    scene = parse_scene(doc)
    long = retime_module.MoverField(scene, 0.3, DT, 400, 1.0)
    for steps in (0, 7, 8, 9, 55, 400):
        short = retime_module.MoverField(scene, 0.3, DT, steps, 1.0)
        cut = long.prefix(steps)
        assert cut.steps == short.steps and cut.nc == short.nc
        for name in ("times", "xy", "present", "margin", "bbox"):
            assert np.array_equal(getattr(cut, name), getattr(short, name)), name
            # the precompiled kernels take C-contiguous arrays only (else numba runs them)
            assert getattr(cut, name).flags.c_contiguous, name
    with pytest.raises(ValueError):
        long.prefix(401)


def test_the_blend_stage_retimes_with_the_querys_backend(monkeypatch):
    """The drive layer's blend (a mover forces haste on one leg) searches with the query's
    backend too: a gate appears on the straight at 4.4 s and stays."""
    import time

    from gfuzzy.collision.geometry import StaticGeometry
    from gfuzzy.planner.stages import StageContext, apply_stages
    from gfuzzy.trajectory import Trajectory

    seen = []
    inner = retime_module.search_function
    monkeypatch.setattr(retime_module, "search_function", lambda b: seen.append(b) or inner(b))
    path = np.array([[0.5, 0.5, math.pi / 2], [0.5, 0.5, 0.0], [4.5, 0.5, 0.0], [4.5, 0.5, math.pi / 2]])
    scene = parse_scene({
        "version": 1, "name": "gate", "bounds": [0, 0, 5, 2],
        "robot": {"disc": 0.2, "vmax": 1.0, "amax": 1.0, "kinematics": "unicycle"},
        "movers": [{"name": "gate", "disc": 0.25, "trajectory": [[4.4, 3.0, 0.5], [1000.0, 3.0, 0.5]]}],
    })  # fmt: skip
    times = np.cumsum([0.0, (math.pi / 2) / 5.0, 4.0, (math.pi / 2) / 5.0])
    searched = Trajectory(np.column_stack([times, path]), 0.2)
    q = Query("q", tuple(path[0]), tuple(path[-1]), 0.0)
    for backend in ("compiled", "reference"):
        seen.clear()
        out = apply_stages(StageContext(scene, StaticGeometry(scene)), searched, q,
                           PlanOptions(speed_layer=True, backend=backend), time.perf_counter() + 60)  # fmt: skip
        assert out.speed_report.applied and not out.speed_report.whole  # the blend answered
        assert seen and set(seen) == {backend}, seen


def test_the_first_round_covers_the_first_motions_window():
    # a search whose first motions were cut by the horizon answers NO_FIRST_MOTION without
    # horizon_hit: the rounds would then stop early with another answer (the review's
    # latent case); the first round's slack covers the whole waiting window
    from gfuzzy.timespace.timespace import FIRST_WAIT_STEPS

    assert retime_module.CHAIN_SLACK_STEPS >= FIRST_WAIT_STEPS


@pytest.mark.parametrize("unicycle", [False, True])
def test_a_horizon_that_ends_at_the_arrival_still_holds_the_goal(unicycle):
    # the hold comes on top of the horizon (as the search before the rounds had it): an
    # answer arriving at the horizon's last step is found with its hold, the same answer as
    # with a long horizon (the review's mutant capping the rounds at the horizon alone
    # answered no_path here)
    hold = 1.0
    t0 = 0.0 if unicycle else 0.5

    def run(scene, path, horizon):
        if unicycle:
            return retime_drive(scene, path, t0, DT, scene.robot.amax, horizon, hold=hold)
        return retime_path(scene, path, t0, DT, horizon, hold=hold)

    for seed, shape in CASES[:6]:
        scene, path = random_case(seed, shape, unicycle)
        free = run(scene, path, 60.0)
        if free.status is not Status.SOLVED:
            continue
        tight = run(scene, path, free.trajectory.waypoints[-1, 0] - t0)  # ends at the arrival
        assert same(tight, free), (seed, shape, tight.status, tight.message)


def test_chain_fields_grow_when_a_later_search_asks_for_more():
    # a stage's later search may ask past the longest horizon sampled so far (a larger hold):
    # the samples are then taken again over the longer horizon, and every prefix is still
    # the field built for it (the branch no caller reached in the review's runs)
    scene, _ = random_case(1, "box", False)
    fields = retime_module.ChainFields(scene, 0.3, DT)
    first = fields(40, 60)
    assert first.steps == 40
    later = fields(50, 200)  # more than the 60 sampled: sampled again
    fresh = retime_module.MoverField(scene, 0.3, DT, 50, scene.robot.vmax)
    assert later.steps == 50
    for name in ("times", "xy", "present", "margin", "bbox"):
        assert np.array_equal(getattr(later, name), getattr(fresh, name)), name
    assert fields(200, 200).steps == 200
