"""What queries share, kept on the roadmap (gfuzzy.timespace.roadgraph): the spanner's cut
spliced as one cut of the whole graph lists it, the same answers from cold and warm caches,
the vertex clearances per static clearance, the caches' bounds."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

from gfuzzy.collision.geometry import StaticGeometry, metric_distance
from gfuzzy.planner.planner import Planner, PlanOptions
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, load_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene
from gfuzzy.settings import SPEED_SAFETY
from gfuzzy.timespace.roadgraph import MAX_SPLITS, spanner_split, vertex_clearances
from gfuzzy.timespace.spacetime import split_edges

ROOT = Path(__file__).resolve().parent.parent


def _setup(name):
    scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
    return scene, load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene)


def _scratch_connect(planner, pose, k):
    """The planner's connections as they were made before any cache (every clearance anew)."""
    V = planner.roadmap.vertices
    d = metric_distance(V, pose[None, :], planner.robot.circumradius)
    out, tried = [], 0
    for i in np.argsort(d, kind="stable"):
        if (tried >= max(k, 1) and out) or tried >= 4 * max(k, 1):
            break
        tried += 1
        if planner.geometry.motion_free(pose, V[i]):
            out.append((int(i), float(d[i])))
    return out


def _batch_cut(planner, start, goal, dt, stretch):
    """The whole graph of a query cut in one go (the spanner's edges, the goal's connections,
    the start's) and its moves sorted by source, stably: (poses, indptr, neighbors)."""
    rm = planner.roadmap
    nv = len(rm.vertices)
    s_id, g_id = nv, nv + 1
    extra_e, extra_w = [], []
    for pose, node in ((goal, g_id), (start, s_id)):
        for v, w in _scratch_connect(planner, pose, 10):
            extra_e.append((node, v))
            extra_w.append(w)
    if planner.geometry.motion_free(start, goal):
        extra_e.append((s_id, g_id))
        extra_w.append(float(metric_distance(start, goal, planner.robot.circumradius)))
    verts = np.vstack([rm.vertices, start[None], goal[None]])
    keep = rm.spanner(stretch)
    edges = np.vstack([rm.edges[keep], np.array(extra_e, dtype=np.int64).reshape(-1, 2)])
    lengths = np.concatenate([rm.lengths[keep], extra_w])
    cut = split_edges(verts, edges, lengths, planner.robot.vmax * SPEED_SAFETY * dt, len(verts))
    s2, d2 = np.concatenate([cut.src, cut.dst]), np.concatenate([cut.dst, cut.src])
    order = np.argsort(s2, kind="stable")
    total = len(verts) + int(cut.offs[-1])
    indptr = np.zeros(total + 1, dtype=np.int64)
    np.add.at(indptr, s2 + 1, 1)
    return np.vstack([verts, cut.inner]), np.cumsum(indptr), d2[order]


def test_the_kept_cut_spliced_lists_moves_as_one_cut_of_the_whole_graph_does():
    """The spanner's cut is kept and the connections are spliced into it
    (SplitSpanner.splice); the search expands moves in list order, so the lists are those of
    one cut of the whole graph sorted by source: same ids, poses and move order. With dt
    large most spanner edges are one step: a connection onto such edges goes between the
    vertex's own moves. (The graph itself is checked against an independent build in
    tests/test_prepared.py.)"""
    scene, rm = _setup("building-floor")
    planner = Planner(scene, rm)
    vplan = scene.robot.vmax * SPEED_SAFETY
    split = spanner_split(rm, vplan * 3.0, 1.05)
    assert (split.k == 1).sum() > 0.8 * len(split.k) and (split.k > 1).any()
    goal = np.asarray(scene.queries[0].goal, float)
    tried = 0
    for v in (5, 40, 77, 120):
        start = rm.vertices[v].copy()
        start[0] += 0.01
        if planner.geometry.clearance1(start) < 0:
            continue
        tried += 1
        for dt in (3.0, 0.5, 0.07):
            qg = planner.prepare(goal, PlanOptions(dt=dt)).splice(planner, start)
            poses, indptr, nbrs = _batch_cut(planner, start, goal, dt, 1.05)
            np.testing.assert_array_equal(qg.graph.poses, poses)
            np.testing.assert_array_equal(qg.graph.indptr, indptr)
            np.testing.assert_array_equal(qg.graph.neighbors, nbrs)
    assert tried >= 2


def test_answers_equal_with_a_cold_and_a_warm_roadmap():
    """Every query of a scene: a roadmap loaded anew (no cache) and one whose caches are
    warm from other queries give the same status, duration and expansions."""
    scene, rm = _setup("zara-crowd")
    warm = Planner(scene, rm)
    for q in scene.queries:
        warm.plan(q.goal, q.start, q.t0)  # another query's connections and the same cut
    for q in scene.queries:
        cold = Planner(scene, load_roadmap(ROOT / "roadmaps" / "zara-crowd.json", scene))
        a, b = cold.plan(q.start, q.goal, q.t0), warm.plan(q.start, q.goal, q.t0)
        assert (a.status, a.duration, a.roadmap_distance) == (b.status, b.duration, b.roadmap_distance)
        assert a.stats.expansions == b.stats.expansions
    assert rm._derived  # the warm roadmap did keep its cut and clearances


def test_vertex_clearances_are_kept_per_static_clearance():
    """The table is the geometry's own: another robot.clearance gets another table, whose
    values are that geometry's clearances (a shared table would give the first one's)."""
    scene, rm = _setup("building-floor")
    other = scene.with_clearances(0.1)
    g0, g1 = StaticGeometry(scene), StaticGeometry(other)
    t0 = vertex_clearances(rm, g0)
    assert vertex_clearances(rm, g0) is t0
    t1 = vertex_clearances(rm, g1)
    assert t1 is not t0
    planner = Planner(scene, rm)
    pose = np.asarray(scene.queries[0].start, float)
    conns = planner._connect(pose, 10)
    assert conns
    seen = [v for v, _ in conns]
    np.testing.assert_array_equal(t0[seen], [g0.clearance1(rm.vertices[v]) for v in seen])
    assert np.all(np.isnan(t1[seen]))  # nothing leaked into the other clearance's table
    t1[seen] = [g1.clearance1(rm.vertices[v]) for v in seen]
    assert np.all(t1[seen] <= t0[seen]) and np.any(t1[seen] < t0[seen] - 0.09)  # the bounds ignore it


def test_caches_are_bounded_and_not_pickled():
    scene, rm = _setup("sim-4s1m")
    planner = Planner(scene, rm)
    q = scene.queries[0]
    for dt in (0.05, 0.06, 0.07, 0.08, 0.09, 0.1):
        planner.plan(q.start, q.goal, q.t0, PlanOptions(dt=dt))
    splits = [key for key in rm._derived if key[0] == "split"]
    assert len(splits) == MAX_SPLITS
    assert ("split", scene.robot.vmax * SPEED_SAFETY * 0.1, 1.05) in splits  # the newest stays
    copy = pickle.loads(pickle.dumps(rm))
    assert not copy._derived and len(rm._derived) > MAX_SPLITS - 1
    np.testing.assert_array_equal(copy.vertices, rm.vertices)


def test_a_cut_too_fine_is_refused_before_it_is_made():
    import yaml

    from gfuzzy.errors import LimitError

    scene = parse_scene(yaml.safe_load(
        "version: 1\nname: open\nbounds: [0, 0, 6, 6]\nrobot: {disc: 0.2, vmax: 1.0}\n"
        "queries:\n  - {name: q, start: [1, 1], goal: [5, 5]}\n"
    ))
    rm = build_roadmap(scene, RoadmapOptions(vertices=30, seed=3))
    with pytest.raises(LimitError, match="too fine"):
        Planner(scene, rm).plan([1, 1], [5, 5], 0.0, PlanOptions(dt=1e-6))
    assert not [key for key in rm._derived if key[0] == "split"]


@pytest.mark.parametrize("seed", range(5))
def test_plain_timed_rows_equal_the_loop_to_the_bit(seed):
    """The vectorised rows of a search's answer against the loop that adds rows inside
    steps (asked for none): the same times and poses, bit for bit, and the same waits."""
    from gfuzzy.timespace.timespace import timed_rows

    rng = np.random.default_rng(seed)
    poses = rng.uniform(-5, 5, size=(40, 2 + seed % 2))
    n = int(rng.integers(1, 30))
    nodes = rng.integers(0, 40, size=n).tolist()
    steps = np.cumsum(rng.integers(1, 4, size=n)).tolist()  # some waits, some plain moves
    t0, dt = float(rng.uniform(0, 100)), float(rng.choice([0.07, 0.1, 0.033]))
    rows, waits = timed_rows(nodes, steps, poses, t0, dt)
    rows_loop, waits_loop = timed_rows(nodes, steps, poses, t0, dt, between=lambda a, b: [])
    np.testing.assert_array_equal(rows, rows_loop)
    assert waits == waits_loop
    assert len(rows) == n + len(waits)
