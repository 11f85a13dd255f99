"""The compiled search (gfuzzy.timespace.search_kernel) against the reference (timespace.sipp).

Both must search in the same order and so return the same answer: same status, same
(node, step) rows, same expansions. Cross-checked on every bundled scene's queries (as
given, with a hold, with a mover clearance), on seeded random graphs among random movers,
and (in test_planner) against the brute-force time-expanded search of tests/reference.py.
"""

from __future__ import annotations

import dataclasses
import math
import os
import subprocess
import sys
from collections import deque
from pathlib import Path

import numpy as np
import pytest
from helpers import bundled_params

from gfuzzy.check.check import check_trajectory
from gfuzzy.planner.planner import Planner, PlanOptions, Status
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import Query, load_scene
from gfuzzy.timespace.search_kernel import sipp_compiled
from gfuzzy.timespace.timespace import IntervalStore, MoverField, SpaceTimeGraph, sipp, timed_rows

ROOT = Path(__file__).resolve().parent.parent
SCENES = sorted((ROOT / "scenes").glob("*.yaml"))


def _same(a, b):
    assert a.status == b.status
    assert a.message == b.message
    assert a.stats.expansions == b.stats.expansions
    if a.trajectory is None:
        assert b.trajectory is None
    else:
        assert a.duration == b.duration
        np.testing.assert_array_equal(a.trajectory.waypoints, b.trajectory.waypoints)


# the costly scenes (5-30 s each with the reference search) run in `make slow`: the box, drive,
# map and mover scenes left keep both searches' answers the same in `make test`
@pytest.mark.parametrize(
    "path", bundled_params(slow=("depot", "tb3-arena-unicycle", "warehouse-mesh", "building-floor-unicycle", "footprint-office"))
)
def test_bundled_queries_same_answer(path):
    scene = load_scene(path)
    rm = load_roadmap(ROOT / "roadmaps" / f"{scene.name}.json", scene)
    planner = Planner(scene, rm)
    for q in scene.queries:
        for hold in {q.hold, 2.0}:
            ref = planner.plan(q.start, q.goal, q.t0, PlanOptions(backend="reference"), hold=hold)
            comp = planner.plan(q.start, q.goal, q.t0, PlanOptions(backend="compiled"), hold=hold)
            _same(ref, comp)


@pytest.mark.parametrize("name", ["sim-5s2m", "zara-crowd", "wait-corridor"])
def test_bundled_queries_same_answer_with_mover_clearance(name):
    scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
    rm = load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene)
    scene = dataclasses.replace(scene, robot=dataclasses.replace(scene.robot, mover_clearance=0.25))
    planner = Planner(scene, rm)
    solved = 0
    for q in scene.queries:
        ref = planner.plan(q.start, q.goal, q.t0, PlanOptions(backend="reference"), hold=q.hold)
        comp = planner.plan(q.start, q.goal, q.t0, PlanOptions(backend="compiled"), hold=q.hold)
        _same(ref, comp)
        solved += ref.solved
    assert solved >= 1  # the comparison covered a search, not only refusals


def test_backend_is_validated():
    with pytest.raises(ValueError, match="backend"):
        PlanOptions(backend="fortran")


SCENE = """
version: 1
name: random
bounds: [0, 0, 6, 6]
robot: ROBOT
obstacles: []
movers:
"""


def _random_case(rng, tmp_path):
    """A grid graph with random diagonals among 1-6 random movers (discs and boxes)."""
    box_robot = rng.random() < 0.4
    lines = [SCENE.replace("ROBOT", "{box: [0.4, 0.25], vmax: 1.0}" if box_robot else "{disc: 0.15, vmax: 1.0}")]
    for i in range(int(rng.integers(1, 7))):
        path = rng.uniform(0.5, 5.5, size=(int(rng.integers(2, 4)), 2)).round(2).tolist()
        shape = f"disc: {rng.uniform(0.1, 0.5):.2f}" if rng.random() < 0.6 else "box: [0.5, 0.3]"
        mode = ["loop", "bounce", "once"][int(rng.integers(3))]
        lines.append(f"  - {{name: m{i}, {shape}, speed: {rng.uniform(0.2, 1.5):.2f}, path: {path}, mode: {mode}}}")
    p = tmp_path / "random.yaml"
    p.write_text("\n".join(lines) + "\n")
    scene = load_scene(p)
    side = int(rng.integers(5, 10))
    xs = np.linspace(0.5, 5.5, side)
    poses = np.array([[x, y] for y in xs for x in xs])
    if box_robot:
        poses = np.column_stack([poses, rng.uniform(-math.pi, math.pi, len(poses))])
    n = len(poses)
    adj = [[] for _ in range(n)]
    for r in range(side):
        for c in range(side):
            i = r * side + c
            for dr, dc in ((0, 1), (1, 0), (1, 1)):
                if r + dr < side and c + dc < side and (dr + dc == 1 or rng.random() < 0.3):
                    j = (r + dr) * side + c + dc
                    adj[i].append(j)
                    adj[j].append(i)
    indptr = np.concatenate([[0], np.cumsum([len(a) for a in adj])])
    nbrs = np.array([v for a in adj for v in a], dtype=np.int64)
    start, goal = (int(v) for v in rng.choice(n, 2, replace=False))
    hops = np.full(n, np.inf)  # exact static steps to the goal: BFS
    hops[goal] = 0
    queue = deque([goal])
    while queue:
        u = queue.popleft()
        for v in adj[u]:
            if hops[v] == np.inf:
                hops[v] = hops[u] + 1
                queue.append(v)
    graph = SpaceTimeGraph(poses, indptr, nbrs, hops)
    return scene, graph, start, goal


@pytest.mark.parametrize("seed", range(30))
def test_random_graphs_same_search(seed, tmp_path):
    rng = np.random.default_rng(seed)
    scene, graph, start, goal = _random_case(rng, tmp_path)
    t0 = float(rng.uniform(0, 5))
    steps = int(rng.integers(20, 80))
    hold = int(rng.integers(0, 10)) if rng.random() < 0.4 else 0
    weight = 1.0 if rng.random() < 0.7 else 1.5
    answers = []
    for search in (sipp, sipp_compiled):
        store = IntervalStore(graph)
        res = None
        for horizon in (steps, 2 * steps):  # a regrown horizon reuses the store
            field = MoverField(scene, t0, 0.2, horizon, scene.robot.vmax)
            field.compiled = search is sipp_compiled  # the compiled safety kernel too
            res = search(graph, field, start, goal, weight=weight, store=store, goal_hold=hold)
            if res.status == "solved":
                break
        answers.append(res)
    ref, comp = answers
    assert (ref.status, ref.message, ref.nodes, ref.steps) == (comp.status, comp.message, comp.nodes, comp.steps)
    assert (ref.expansions, ref.states, ref.horizon_hit) == (comp.expansions, comp.states, comp.horizon_hit)


def _random_groups(rng, scene):
    """40 groups of points along random segments (roadmap edges) and 20 single points."""
    n = int(rng.integers(3, 9))
    a, b = rng.uniform(0.3, 5.7, (2, 40, 2))
    groups = [a[i] + np.linspace(0, 1, n)[:, None] * (b[i] - a[i]) for i in range(40)]
    groups += [rng.uniform(0.3, 5.7, (1, 2)) for _ in range(20)]
    poses = np.vstack(groups)
    if scene.robot.dof == 3:
        poses = np.column_stack([poses, rng.uniform(-math.pi, math.pi, len(poses))])
    ptr = np.concatenate([[0], np.cumsum([len(g) for g in groups])])
    return poses, ptr


@pytest.mark.parametrize("broad", ["dense", "grid"])
@pytest.mark.parametrize("seed", range(12))
def test_compiled_intervals_match_reference(seed, broad, tmp_path, monkeypatch):
    """The safe intervals read off the compiled kernel's table equal the numpy reference's
    (unsafe pairs, sorted between walls), with the kernel testing every box itself
    (dense) or taking the grid join's candidates; windows include empty ones and ones
    beyond the horizon (points that cannot matter in time)."""
    from gfuzzy.timespace import movers
    from gfuzzy.timespace.spacetime import _intervals_from_pairs

    if broad == "grid":
        monkeypatch.setattr(movers, "DENSE_BROAD_PHASE", 0)
    rng = np.random.default_rng(300 + seed)
    scene, _, _, _ = _random_case(rng, tmp_path)
    poses, ptr = _random_groups(rng, scene)
    H = 70
    lo = rng.integers(0, 80, len(ptr) - 1)
    hi = lo + rng.integers(-6, 60, len(ptr) - 1)
    t0 = float(rng.uniform(0, 3))
    out = []
    for compiled in (False, True):
        field = MoverField(scene, t0, 0.1, H, 1.0, clearance=0.1 * seed % 0.3)
        field.compiled = compiled
        if compiled:
            out.append(field.safe_intervals(poses, ptr, lo, np.minimum(hi, H)))
        else:
            out.append(_intervals_from_pairs(field, poses, ptr, lo, np.minimum(hi, H), H))
    for ref, comp in zip(*out, strict=True):
        np.testing.assert_array_equal(ref, comp)
    starts, ends, _ = out[1]
    assert len(starts) > len(poses) // 2  # most windows hold intervals: a real comparison
    window = np.repeat(np.maximum(np.minimum(hi, H) - lo + 1, 0), np.diff(ptr)).sum()
    assert (ends - starts + 1).sum() < window  # and movers made some steps unsafe


@pytest.mark.parametrize("broad", ["dense", "grid"])
@pytest.mark.parametrize("seed", range(12))
def test_compiled_safety_kernel_same_pairs(seed, broad, tmp_path, monkeypatch):
    """unsafe_pairs: the compiled kernel against numpy, on groups of points along segments
    (the roadmap's edges) and single points, disc and box robots, disc and box movers."""
    from gfuzzy.timespace import movers

    if broad == "grid":
        monkeypatch.setattr(movers, "DENSE_BROAD_PHASE", 0)
    rng = np.random.default_rng(100 + seed)
    scene, graph, _, _ = _random_case(rng, tmp_path)
    poses, ptr = _random_groups(rng, scene)
    lo = rng.integers(0, 20, len(ptr) - 1)
    hi = lo + rng.integers(0, 60, len(ptr) - 1)
    pairs = []
    t0 = float(rng.uniform(0, 3))
    for compiled in (False, True):
        field = MoverField(scene, t0, 0.1, 70, 1.0, clearance=0.1 * seed % 0.3)
        field.compiled = compiled
        node, step = field.unsafe_pairs(poses, ptr, lo, hi)
        pairs.append((set(zip(node.tolist(), step.tolist(), strict=True)), field.evaluations))
    assert pairs[0] == pairs[1]
    assert pairs[0][0]  # the movers come near some points: not a vacuous comparison


def test_random_graphs_cover_both_outcomes(tmp_path):
    """The random cases above include solved and unsolved searches (else they test little)."""
    statuses = set()
    for seed in range(30):
        rng = np.random.default_rng(seed)
        scene, graph, start, goal = _random_case(rng, tmp_path)
        field = MoverField(scene, float(rng.uniform(0, 5)), 0.2, int(rng.integers(20, 80)), 1.0)
        statuses.add(sipp_compiled(graph, field, start, goal).status)
    assert statuses == {"solved", "no_path"}


def test_reference_path_never_imports_numba():
    """`import gfuzzy` and a reference-backend query run without numba (cold start), and
    the compiled backend loads it when no precompiled kernels serve it
    (``GFUZZY_PRECOMPILED=0``; with them: tests/test_jit.py)."""
    from conftest import run_python

    code = (
        "import os, sys\n"
        "os.environ['GFUZZY_PRECOMPILED'] = '0'\n"
        "import gfuzzy\n"
        "from gfuzzy.scene.scene import load_scene\n"
        "from gfuzzy.roadmap.roadmap import load_roadmap\n"
        "s = load_scene('scenes/sim-4s1m.yaml')\n"
        "p = gfuzzy.Planner(s, load_roadmap('roadmaps/sim-4s1m.json', s))\n"
        "q = s.queries[0]\n"
        "r = p.plan(q.start, q.goal, q.t0, gfuzzy.PlanOptions(backend='reference'))\n"
        "print(r.status, 'numba' in sys.modules)\n"
        "r = p.plan(q.start, q.goal, q.t0)\n"
        "print(r.status, 'numba' in sys.modules)\n"
    )
    out = run_python(code, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["solved", "False", "solved", "True"]


def test_cli_backend_flag(tmp_path, capsys, monkeypatch):
    """`gfuzzy plan --backend reference` and the default write the same trajectory. The
    default in a real process; the reference and a bad backend in process (a real process
    costs a second of imports: the flag is the subject, not the process)."""
    import json

    from conftest import run_cli_process
    from helpers import main_completed

    monkeypatch.chdir(ROOT)
    rows = {}
    for backend in ("compiled", "reference"):
        out = tmp_path / f"{backend}.json"
        argv = ("plan", "scenes/wait-corridor.yaml", "--backend", backend, "-o", out)
        res = run_cli_process(*argv, cwd=ROOT) if backend == "compiled" else main_completed(capsys, *argv)
        assert res.returncode == 0, res.stderr
        doc = json.loads(out.read_text())
        rows[backend] = (doc["status"], doc["duration"], doc["waypoints"])
    assert rows["compiled"] == rows["reference"]
    bad = main_completed(capsys, "plan", "scenes/wait-corridor.yaml", "--backend", "fortran")
    assert bad.returncode == 2 and "backend" in bad.stderr


def test_compiled_search_times_out_like_the_reference():
    """A deadline already past: both searches stop with `timeout` (the kernel hands control
    back every few thousand expansions), and without a deadline both solve."""
    from gfuzzy.scene.scene import parse_scene

    scene = parse_scene(
        {"version": 1, "name": "empty", "bounds": [0, 0, 90, 90], "robot": {"disc": 0.1, "vmax": 1.0}}
    )
    side = 80
    idx = np.arange(side * side).reshape(side, side)
    pairs = np.vstack([np.c_[idx[:, :-1].ravel(), idx[:, 1:].ravel()], np.c_[idx[:-1].ravel(), idx[1:].ravel()]])
    both = np.vstack([pairs, pairs[:, ::-1]])
    both = both[np.argsort(both[:, 0], kind="stable")]
    indptr = np.searchsorted(both[:, 0], np.arange(side * side + 1))
    poses = np.c_[idx.ravel() % side, idx.ravel() // side].astype(float) + 1.0
    graph = SpaceTimeGraph(poses, indptr, both[:, 1].copy(), np.zeros(side * side))  # h = 0: Dijkstra
    for search in (sipp, sipp_compiled):
        field = MoverField(scene, 0.0, 1.0, 400, 1.0)
        assert search(graph, field, 0, side * side - 1, deadline=0.0).status == "timeout"
        done = search(graph, MoverField(scene, 0.0, 1.0, 400, 1.0), 0, side * side - 1)
        assert done.status == "solved" and done.steps[-1] == 2 * (side - 1)


def test_compiled_box_box_gap_is_the_reference_bit_for_bit():
    """The kernel's box robot against box mover distance equals geometry.mover_distance
    (exact=False) exactly, near (separating-axis gap, overlaps included) and far (the
    circumscribed circles' bound beyond QUAD_EXACT)."""
    from gfuzzy.collision.geometry import QUAD_EXACT, mover_distance
    from gfuzzy.scene.scene import parse_scene
    from gfuzzy.timespace.movers_kernel import QUAD_EXACT as KERNEL_QUAD_EXACT
    from gfuzzy.timespace.movers_kernel import _box_box_gap

    assert KERNEL_QUAD_EXACT == QUAD_EXACT
    robot = parse_scene({"version": 1, "name": "b", "bounds": [0, 0, 9, 9], "robot": {"box": [0.9, 0.436], "vmax": 1}}).robot
    rng = np.random.default_rng(5)
    n = 3000
    poses = np.column_stack([rng.uniform(0, 5, (n, 2)), rng.uniform(-math.pi, math.pi, n)])
    xy, size = rng.uniform(0, 5, (n, 2)), rng.uniform(0.05, 1.2, (n, 2))
    ref = mover_distance(robot, poses, "box", np.zeros(n), size, xy, exact=False)
    scratch = np.empty((2, 4, 2))
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    hl, hw = 0.5 * np.asarray(robot.size)
    got = [_box_box_gap(scratch, *poses[i, :2], c[i], s[i], hl, hw, *xy[i], *(0.5 * size[i])) for i in range(n)]
    np.testing.assert_array_equal(np.array(got), ref)
    assert (ref < 0).sum() > 50 and (ref >= QUAD_EXACT).sum() > 50 and ((ref > 0) & (ref < QUAD_EXACT)).sum() > 50


@pytest.mark.parametrize("seed", range(6))
def test_grid_candidates_are_every_overlapping_triple(seed):
    """The compiled grid broad phase finds exactly the (group, mover, chunk) triples whose
    boxes overlap within the group's steps (all pairs tested), sorted by group; absent
    movers (empty boxes), empty windows and windows beyond the movers' chunks included."""
    from gfuzzy.timespace.movers_kernel import grid_candidates

    rng = np.random.default_rng(seed)
    G, M, nc, chunk = 150, 25, 12, 8
    lo_xy = rng.uniform(0, 20, (G, 2))
    box = np.column_stack([lo_xy, lo_xy + rng.uniform(0, 3, (G, 2))])
    m_xy = rng.uniform(-2, 22, (M, nc, 2))
    bbox = np.concatenate([m_xy, m_xy + rng.uniform(0.2, 4, (M, nc, 2))], axis=-1)
    bbox[rng.random((M, nc)) < 0.2] = [np.inf, np.inf, -np.inf, -np.inf]  # absent in that chunk
    lo = rng.integers(0, nc * chunk + 10, G)
    hi = lo + rng.integers(-5, 40, G)
    want = set()
    for g in range(G):
        for c in range(max(lo[g] // chunk, 0), min(hi[g] // chunk, nc - 1) + 1):
            if lo[g] > hi[g]:
                continue
            for m in range(M):
                b = bbox[m, c]
                if b[0] <= box[g, 2] and box[g, 0] <= b[2] and b[1] <= box[g, 3] and box[g, 1] <= b[3]:
                    want.add((g, m, c))
    got = grid_candidates(box, lo, hi, bbox, chunk)
    assert len(want) > 100  # a real comparison
    assert len(got) == len(want) and set(map(tuple, got.tolist())) == want
    assert np.all(np.diff(got[:, 0]) >= 0)


WARM_PROBE = """
import sys
from pathlib import Path
from numba.core.registry import CPUDispatcher
from gfuzzy.timespace import movers_kernel
from gfuzzy.timespace import search_kernel
from gfuzzy.planner.planner import plan
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, load_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene

search_kernel.warm()
kernels = [o for m in (movers_kernel, search_kernel) for o in vars(m).values() if isinstance(o, CPUDispatcher)]
before = {f: set(f.overloads) for f in kernels}
root = Path(sys.argv[1])
for name in ("warehouse-mesh", "eth-crossing", "building-floor"):  # box-box, a crowd, a box robot
    scene = load_scene(root / "scenes" / f"{name}.yaml")
    rm = load_roadmap(root / "roadmaps" / f"{name}.json", scene)
    for q in scene.queries:
        plan(scene, rm, q.start, q.goal, q.t0, hold=q.hold)
person = parse_scene({"version": 1, "name": "p", "bounds": [0, 0, 6, 6], "robot": {"disc": 0.25, "vmax": 1.0},
                      "movers": [{"name": "ped", "disc": 0.3, "trajectory": [[0, 0.0, 1.0], [4.6, 5.98, 1.0]]}]})
rm = build_roadmap(person, RoadmapOptions(vertices=40, seed=1))
assert plan(person, rm, [2.6, 1.586], [2.6, 5.0], 2.0).solved  # a start the margin refuses: first motions
assert len(kernels) >= 5, kernels  # numba's dispatchers watched (not the extension's functions)
print(sorted(f.py_func.__name__ for f in kernels if set(f.overloads) != before[f]))
"""


def test_warm_leaves_nothing_to_compile():
    """After `make warm` (search_kernel.warm) a process compiles no kernel in the user's way:
    plans among box movers, a crowd, a box robot and a start beside a walking person add no
    compiled signature to any kernel (a fresh process: the kernels load only by warm). On
    numba's kernels (``GFUZZY_PRECOMPILED=0``, the path of a machine without a C compiler):
    with the precompiled extension loaded the kernels are no dispatchers, and the probe
    watched none (it printed ``[]`` whatever happened)."""
    env = {**os.environ, "GFUZZY_PRECOMPILED": "0"}
    out = subprocess.run(
        [sys.executable, "-c", WARM_PROBE, str(ROOT)], capture_output=True, text=True, cwd=ROOT, timeout=300, env=env
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_make_warm_warms_every_kernel_module_the_extension_leaves_to_numba():
    """`make warm` compiles (into numba's on-disk cache) every module of ``@njit`` kernels
    that the precompiled extension leaves out (``jit.KERNEL_MODULES``): the GA's and the
    priced search's. Before, ``soft_kernel`` was left out, and the first ``--soft-search``
    run (or the first test worker) of a fresh checkout compiled it, ~10 s."""
    from gfuzzy.timespace.jit import KERNEL_MODULES

    make = (ROOT / "Makefile").read_text(encoding="utf-8")
    recipe = make.split("\nwarm:", 1)[1].split("\n\n", 1)[0]
    numba_only = sorted(
        p.relative_to(ROOT).with_suffix("").as_posix().replace("/", ".")
        for p in (ROOT / "gfuzzy").rglob("*.py")
        if "@njit" in p.read_text(encoding="utf-8") and p.stem not in KERNEL_MODULES
    )
    assert numba_only == ["gfuzzy.ga.kernels", "gfuzzy.timespace.soft_kernel"]
    assert "import gfuzzy.ga.refine as r; r.warm()" in recipe  # refine.warm runs the GA's kernels
    assert "import gfuzzy.timespace.soft_kernel as s; s.warm()" in recipe
    # the GA's compile runs beside the precompile (another core); warm fails if it fails
    assert "r.warm()' & ga=$$!" in recipe and "wait $$ga" in recipe
    # soft_kernel runs the search's kernels: beside the precompile's ahead-of-time compile, once
    # numba has compiled them (--beside), and after it (loading that cache, or compiling)
    assert "gfuzzy.timespace.precompile --beside gfuzzy.timespace.soft_kernel " in recipe
    assert recipe.rindex("soft_kernel") > recipe.index("gfuzzy.timespace.precompile")


@pytest.mark.parametrize("pool", [False, True])
def test_interval_store_unchanged_when_the_field_raises(pool, tmp_path):
    """A field that raises inside a batch (a navigator's deadline) leaves the store as it
    was: asked again with a working field, it serves what a fresh store serves."""
    rng = np.random.default_rng(4)
    scene, graph, _, _ = _random_case(rng, tmp_path)

    class Failing(MoverField):
        def unsafe_pairs(self, *a):
            raise TimeoutError

        def safe_intervals(self, *a):
            raise TimeoutError

    def field(cls):
        f = cls(scene, 0.5, 0.1, 40, 1.0)
        f.compiled = True
        return f

    store, fresh = IntervalStore(graph), IntervalStore(graph)
    store.set_horizon(field(Failing), pool=pool)
    with pytest.raises(TimeoutError):
        store.get(0)
    store.set_horizon(field(MoverField), pool=pool)
    fresh.set_horizon(field(MoverField), pool=pool)
    for node in range(len(graph.poses)):
        a, b = store.get(node), fresh.get(node)
        assert (list(a[0]), list(a[1]), a[2]) == (list(b[0]), list(b[1]), b[2])


@pytest.mark.parametrize("search", [sipp, sipp_compiled])
def test_a_start_beside_a_person_walking_away_waits_until_clear(search, tmp_path):
    """A start 1 cm from a person walking away (the margin refuses it for two steps): the
    robot may wait there, each step proven clear exactly, until a move or the start itself is
    accepted (one exact step alone found nothing, and the query was answered no_path)."""
    p = tmp_path / "away.yaml"
    p.write_text(
        "version: 1\nname: away\nbounds: [0, 0, 4, 3]\nrobot: {disc: 0.25, vmax: 1.0}\n"
        "movers:\n  - {name: p, disc: 0.3, trajectory: [[0, 1.0, 1.56], [5, 1.0, 3.06]]}\n"
    )
    scene = load_scene(p)
    xs = np.arange(1.0, 3.0 + 1e-9, 0.07)  # a chain of one-step points along +x
    n = len(xs)
    nbrs = [[i + 1] if i == 0 else ([i - 1, i + 1] if i < n - 1 else [i - 1]) for i in range(n)]
    graph = SpaceTimeGraph(
        np.column_stack([xs, np.ones(n)]),
        np.concatenate([[0], np.cumsum([len(a) for a in nbrs])]),
        np.array([v for a in nbrs for v in a]),
        np.arange(n)[::-1].astype(float),
    )
    field = MoverField(scene, 0.0, 0.07, 80, 1.0)
    field.compiled = True
    assert field.margin[0, 1] > 0.031  # waiting or stepping once is refused by the margin
    res = search(graph, field, 0, n - 1)
    assert res.status == "solved", res.message
    assert res.steps[-1] <= n - 1 + 3  # about two steps of waiting
    rows, _ = timed_rows(res.nodes, res.steps, graph.poses, 0.0, 0.07)
    report = check_trajectory(scene, rows, Query("away", (1.0, 1.0), (float(xs[-1]), 1.0), 0.0))
    assert report.valid, report.message


@pytest.mark.parametrize("backend", ["reference", "compiled"])
def test_a_horizon_shorter_than_the_route_names_the_horizon(backend):
    """A horizon below the static distance to the goal is the horizon's fault, not a mover's
    (it was reported as a start too close to a mover)."""
    scene = load_scene(ROOT / "scenes" / "building-floor.yaml")
    rm = load_roadmap(ROOT / "roadmaps" / "building-floor.json", scene)
    q = scene.queries[0]
    res = Planner(scene, rm).plan(q.start, q.goal, q.t0, PlanOptions(horizon=15.0, backend=backend))
    assert res.status is Status.NO_PATH
    assert "horizon" in res.message and "mover" not in res.message, res.message


@pytest.mark.parametrize("seed", range(3))
def test_a_field_without_movers_serves_every_window_whole_without_safety_batches(seed, tmp_path, monkeypatch):
    """Nobody predicted (a navigator among no one near): the pool serves each point's whole
    window as its one interval, filled in one go and grown with the horizon, without the
    batches of safety work (a differential drive's 214,000 points over 800 steps cost 76 ms
    of CPU a call on a house map); the same intervals as the lists' store computes."""
    from gfuzzy.timespace import movers_kernel, spacetime

    rng = np.random.default_rng(seed)
    scene, graph, _, _ = _random_case(rng, tmp_path)
    nobody = dataclasses.replace(scene, movers=())
    graph = dataclasses.replace(graph, from_start=rng.integers(0, 8, len(graph.poses)).astype(float))

    def field(steps):
        f = MoverField(nobody, 0.5, 0.1, steps, 1.0)
        f.compiled = True
        return f

    want = {}
    for steps in (30, 60):
        lists = IntervalStore(graph)
        lists.set_horizon(field(steps), pool=False)
        want[steps] = [lists.get(v) for v in range(len(graph.poses))]

    def boom(*a, **k):
        raise AssertionError("safety work for a field without movers")

    monkeypatch.setattr(spacetime, "_safe_intervals_shared", boom)
    monkeypatch.setattr(movers_kernel, "safe_runs", boom)
    pool = IntervalStore(graph)
    for steps in (30, 60):  # the fill, then a horizon grown by a batch
        pool.set_horizon(field(steps), pool=True)
        for v in range(len(graph.poses)):
            a, b = pool.get(v), want[steps][v]
            assert (list(a[0]), list(a[1]), a[2]) == (list(b[0]), list(b[1]), b[2])
    assert any(len(w[0]) for w in want[60])
    # the field's own answer for groups of points: each point's window (clipped), by hand
    ptr, lo, hi = np.array([0, 2, 2, 5]), np.array([-3, 4, 7]), np.array([9, 50, 6])
    starts, ends, sp = field(30).safe_intervals(graph.poses[:5], ptr, lo, hi)
    by_hand = [[(0, 9)], [(0, 9)], [], [], []]  # the empty group adds no point; 7..6 is empty
    assert [list(zip(starts[sp[i] : sp[i + 1]], ends[sp[i] : sp[i + 1]], strict=True)) for i in range(5)] == by_hand
