"""Planner.prepare / plan_from (replanning to a fixed goal) against fresh plans."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from helpers import bundled_params

from gfuzzy.check.check import check_trajectory
from gfuzzy.planner.planner import Planner, PlanOptions
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def _setup(name):
    scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
    return scene, Planner(scene, load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene))


@pytest.mark.parametrize("name", ["building-floor", "zara-crowd", "wait-corridor", "sim-5s2m", "office-polygons"])
def test_plan_from_matches_fresh_plans_along_a_run(name):
    """From the start and from poses along the first answer (mid-edge, later t0): the same
    status and duration as a fresh plan, and a valid answer."""
    scene, planner = _setup(name)
    q = scene.queries[0]
    prepared = planner.prepare(q.goal)
    first = planner.plan(q.start, q.goal, q.t0)
    assert first.solved
    wps = first.trajectory.waypoints
    checked = 0
    for frac in (0.0, 0.17, 0.4, 0.63):
        t = q.t0 + frac * first.duration
        pose = first.trajectory.at(t) if frac else np.asarray(q.start, float)
        fresh = planner.plan(pose, q.goal, t)
        again = planner.plan_from(prepared, pose, t)
        assert again.status == fresh.status, (frac, fresh.message, again.message)
        assert again.roadmap_distance == pytest.approx(fresh.roadmap_distance)
        if fresh.solved:
            assert again.duration == pytest.approx(fresh.duration, abs=1e-9)
            np.testing.assert_allclose(again.trajectory.waypoints[-1, 1:], q.goal)
            ok = check_trajectory(scene, again.trajectory.waypoints)
            assert ok.valid, ok.reason
            checked += 1
    assert checked >= 2
    assert len(wps) > 2


def test_plan_from_with_other_movers_and_the_reference_backend():
    """Movers given per call (a navigator's prediction) replace the scene's; both backends
    agree with a fresh plan on a scene holding those movers."""
    scene, planner = _setup("wait-corridor")
    q = scene.queries[0]
    moved = [dataclasses.replace(m, offset=m.offset + 1.5) if m.trajectory is None else m for m in scene.movers]
    other = dataclasses.replace(scene, movers=tuple(moved))
    fresh = Planner(other, planner.roadmap).plan(q.start, q.goal, q.t0)
    for backend in ("compiled", "reference"):
        prepared = planner.prepare(q.goal, PlanOptions(backend=backend))
        again = planner.plan_from(prepared, q.start, q.t0, movers=moved)
        assert (again.status, again.duration) == (fresh.status, fresh.duration)
    base = planner.plan(q.start, q.goal, q.t0)
    assert base.duration != fresh.duration  # the movers given did change the problem


SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("*.yaml"))


# 4-11 s each on the drives and the depot map: `make slow`; tb3-arena-unicycle keeps a drive
@pytest.mark.parametrize(
    "name", bundled_params(slow=("drive-tight", "building-floor-unicycle", "depot", "footprint-office"), names=True)
)
def test_plan_from_matches_fresh_plans_on_every_bundled_query(name):
    """Every query of every bundled scene, from its start and from a pose in the middle of
    a roadmap edge near it: the same status, duration and roadmap distance as a fresh plan."""
    scene, planner = _setup(name)
    rm = planner.roadmap
    compared = 0
    for q in scene.queries:
        prepared = planner.prepare(q.goal)
        start = np.asarray(q.start, float)
        near = np.argmin(np.hypot(*(rm.vertices[:, :2] - start[:2]).T))
        e = rm.edges[np.nonzero((rm.edges == near).any(axis=1))[0][0]]
        mid = 0.5 * (rm.vertices[e[0]] + rm.vertices[e[1]])
        if rm.dof == 3:
            mid[2] = rm.vertices[e[0], 2]
        elif scene.robot.dof == 3:  # a unicycle disc: its poses carry a heading
            mid = np.append(mid, q.start[2])
        for pose in (start, mid):
            again = planner.plan_from(prepared, pose, q.t0, hold=q.hold)
            fresh = planner.plan(pose, q.goal, q.t0, hold=q.hold)
            assert again.status == fresh.status, (q.name, fresh.message, again.message)
            assert again.roadmap_distance == pytest.approx(fresh.roadmap_distance, rel=1e-12)
            if fresh.solved:
                assert again.duration == pytest.approx(fresh.duration, abs=1e-9)
            compared += 1
    assert compared == 2 * len(scene.queries)


@pytest.mark.parametrize("name", ["building-floor", "warehouse-mesh", "office-polygons"])
def test_spliced_bounds_never_exceed_the_spliced_graphs_distances(name):
    """The per-call figures against breadth-first distances on the spliced graph itself:
    the earliest step of every point and its steps to the goal are exact (one Dijkstra on
    the vertex graph per call, then along the edges; the kept distances to the goal)."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import shortest_path

    scene, planner = _setup(name)
    rm = planner.roadmap
    q = scene.queries[0]
    prepared = planner.prepare(q.goal)
    spliced = 0
    for i in (0, len(rm.edges) // 2, len(rm.edges) - 1):
        e = rm.edges[i]
        start = 0.7 * rm.vertices[e[0]] + 0.3 * rm.vertices[e[1]]
        if rm.dof == 3:
            start[2] = rm.vertices[e[0], 2]
        qg = prepared.splice(planner, start)
        graph, s_id, g_id = qg.graph, qg.s_id, qg.g_id
        n = len(graph.poses)
        rows = np.repeat(np.arange(n), np.diff(graph.indptr))
        adj = csr_matrix((np.ones(len(rows)), (rows, graph.neighbors)), shape=(n, n))
        exact = shortest_path(adj, unweighted=True, indices=[s_id, g_id])
        np.testing.assert_array_equal(graph.from_start, exact[0])
        np.testing.assert_array_equal(graph.heuristic, exact[1])
        spliced += 1
    assert spliced == 3


# ----------------------------------------------------------------------------- the one builder
# An independent construction of a query's graph, to test the builder against: plain Python
# and networkx, sharing no code with gfuzzy's graph code (no split_edges, split_counts,
# interpolate_segment, metric_distance, roadgraph caches, Dijkstra kernels). It takes from
# gfuzzy only its inputs: the roadmap (vertices, edges, the spanner's edge mask) and the
# collision model's verdict on a straight motion (which connections are certified). Points
# are matched by their place in the graph, not by pose: roadmap edges may overlap (collinear
# vertices), so two points may share a pose.


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def _metric(p, q, r):
    d = math.hypot(q[0] - p[0], q[1] - p[1])
    return d + abs(_wrap(q[2] - p[2])) * r if len(p) == 3 else d


def _pieces(length, step):
    """Fewest equal pieces of at most ``step`` (docs/formats.md section 3)."""
    k = max(1, math.ceil(length / step))
    while length / k > step:
        k += 1
    return k


def _oracle(planner, start, goal, dt, stretch, connect_k=10):
    """(networkx graph on point ids, poses by id, interior point ids by label, roadmap distance).

    Ids: vertices, start ``nv``, goal ``nv + 1``, then the interior points in any order;
    an interior point's label is ``(lower end, upper end, steps from the lower end)``."""
    import networkx as nx

    rm, robot = planner.roadmap, planner.robot
    r = robot.circumradius
    step = robot.vmax * dt * (1.0 - 1e-9)  # the planner's guard against rounding up the speed
    V = [tuple(float(c) for c in v) for v in rm.vertices]
    nv = len(V)
    s_id, g_id = nv, nv + 1
    poses = {i: v for i, v in enumerate(V)}
    poses[s_id], poses[g_id] = tuple(map(float, start)), tuple(map(float, goal))
    links = []
    for pose, node in ((goal, g_id), (start, s_id)):  # nearest first; the first connect_k tries
        order = sorted(range(nv), key=lambda i: (_metric(poses[node], V[i], r), i))
        tried = joined = 0
        for i in order[: 4 * connect_k]:
            if tried >= connect_k and joined:
                break
            tried += 1
            if planner.geometry.motion_free(pose, rm.vertices[i]):
                links.append((node, i))
                joined += 1
    if planner.geometry.motion_free(start, goal):
        links.append((s_id, g_id))
    spanner = [tuple(map(int, e)) for e in rm.edges[rm.spanner(stretch)]]
    G = nx.Graph()
    G.add_nodes_from(range(nv + 2))
    labels = {}
    for a, b in spanner + links:
        pa, pb = poses[a], poses[b]
        k = _pieces(_metric(pa, pb, r), step)
        chain = [a]
        for j in range(1, k):
            f = j / k
            p = [pa[0] + f * (pb[0] - pa[0]), pa[1] + f * (pb[1] - pa[1])]
            if len(pa) == 3:
                p.append(_wrap(pa[2] + f * _wrap(pb[2] - pa[2])))
            pid = len(poses)
            poses[pid] = tuple(p)
            labels[(min(a, b), max(a, b), j if a < b else k - j)] = pid
            chain.append(pid)
        chain.append(b)
        G.add_edges_from(zip(chain[:-1], chain[1:], strict=True))
    W = nx.Graph()  # the whole roadmap in metres, with the connections
    W.add_nodes_from(range(nv + 2))
    for a, b in [tuple(map(int, e)) for e in rm.edges] + links:
        W.add_edge(a, b, weight=_metric(poses[a], poses[b], r))
    try:
        rd = nx.dijkstra_path_length(W, s_id, g_id)
    except nx.NetworkXNoPath:
        rd = math.inf
    return G, poses, labels, rd


def _to_oracle(graph, nv, labels):
    """The oracle's id of every built point: the fixed ids as they are; an interior point by
    its label, read off its group (one edge's points in order) and the group's two ends."""
    N = len(graph.poses)
    groups = np.asarray(graph.groups)
    assert groups[0] == nv + 2 and groups[-1] == N and np.all(np.diff(groups) >= 0)
    out = np.arange(N)

    def ends(i):
        nb = graph.neighbors[graph.indptr[i] : graph.indptr[i + 1]]
        return sorted(int(v) for v in nb if v < nv + 2)

    for lo, hi in zip(groups[:-1].tolist(), groups[1:].tolist(), strict=True):
        m = hi - lo
        if m == 0:
            continue
        if m == 1:
            e1, e2 = ends(lo)
        else:
            (e1,), (e2,) = ends(lo), ends(hi - 1)
        for t in range(m):
            out[lo + t] = labels[(min(e1, e2), max(e1, e2), t + 1 if e1 < e2 else m - t)]
    return out


def _assert_same_graph(qg, planner, start, goal, dt, stretch):
    """The builder's graph equals the oracle's up to the interior points' numbering."""
    import networkx as nx

    G, poses, labels, rd = _oracle(planner, start, goal, dt, stretch)
    graph = qg.graph
    nv = len(planner.roadmap.vertices)
    N = len(graph.poses)
    assert (qg.s_id, qg.g_id) == (nv, nv + 1)
    assert N == len(poses)
    to_oracle = _to_oracle(graph, nv, labels)
    assert len(np.unique(to_oracle)) == N

    def embed(p):  # headings as points on a circle: no wrap at +-pi
        p = np.asarray(p, dtype=float)
        return p if p.shape[1] == 2 else np.column_stack([p[:, :2], np.cos(p[:, 2]), np.sin(p[:, 2])])

    np.testing.assert_allclose(embed(graph.poses), embed([poses[int(i)] for i in to_oracle]), rtol=0, atol=1e-9)
    # the one-step moves, both ways, as sets of (from, to) in the oracle's ids
    rows = np.repeat(np.arange(N), np.diff(graph.indptr))
    built = np.sort(to_oracle[rows] * N + to_oracle[graph.neighbors])
    expect = np.sort([a * N + b for a, b in G.edges] + [b * N + a for a, b in G.edges])
    np.testing.assert_array_equal(built, expect)
    # the figures the search's windows rest on: exact breadth-first step counts
    for source, got in ((nv + 1, graph.heuristic), (nv, graph.from_start)):
        hops = nx.single_source_shortest_path_length(G, source)
        np.testing.assert_array_equal(got, [hops.get(int(i), math.inf) for i in to_oracle])
    if math.isfinite(rd):
        assert qg.roadmap_distance == pytest.approx(rd, rel=1e-12)
    else:
        assert qg.roadmap_distance == math.inf


def _query_poses(scene, planner):
    """The first query's ends, a roadmap vertex, mid-edge poses (free ones only)."""
    rm = planner.roadmap
    q = scene.queries[0]
    V, e = rm.vertices, rm.edges
    mids = [0.5 * (V[e[i, 0]] + V[e[i, 1]]) for i in (0, len(e) // 3, len(e) // 2)]
    if rm.dof == 3:  # a heading between the ends' (never across the wrap)
        for m in mids:
            m[2] = 0.3
    goal = np.asarray(q.goal, float)
    pairs = [(np.asarray(q.start, float), goal), (V[3].copy(), goal), (mids[0], mids[1]), (mids[2], goal)]
    return [(s, g) for s, g in pairs if planner.geometry.clearance1(s) >= 0 and planner.geometry.clearance1(g) >= 0]


@pytest.mark.parametrize(
    "name, stretch, dt",
    [
        ("building-floor", 1.05, 0.07),  # a box robot: headings
        ("building-floor", 1.0, 3.0),  # most edges one step: connections onto single-step edges
        ("office-polygons", 1.05, 0.2),
        ("sealed-room", 1.0, 0.07),  # a part of the roadmap the goal cannot reach: inf
        pytest.param("warehouse-mesh", 1.05, 0.07, marks=pytest.mark.slow),  # 8 s: `make slow`
    ],
)
def test_the_query_graph_equals_an_independent_build(name, stretch, dt):
    """What every holonomic query searches (a fresh plan, plan_from, the navigator): the
    prepared goal with the start spliced in, against the plain-Python build above."""
    scene, planner = _setup(name)
    pairs = _query_poses(scene, planner)
    assert len(pairs) >= 3
    opts = PlanOptions(dt=dt, stretch=stretch)
    for start, goal in pairs:
        for _ in range(2):  # the second time from the roadmap's caches
            qg = planner.prepare(goal, opts).splice(planner, start)
            _assert_same_graph(qg, planner, start, goal, dt, stretch)


def test_plan_plan_from_and_the_navigator_get_their_graph_from_one_builder(monkeypatch):
    """A fresh plan, plan_from and the navigator all search the graph PreparedGoal.splice
    builds, and for the same start and goal it is the same graph, to the bit (the
    navigator's with its ends' connections cut leading, ``lead=True``)."""
    from gfuzzy.navigation.navigator import Navigator
    from gfuzzy.planner.prepared import PreparedGoal

    built = []
    splice = PreparedGoal.splice

    def spy(self, planner, start, ahead=(), lead=False):
        qg = splice(self, planner, start, ahead, lead)
        built.append((np.array(start), qg))
        return qg

    monkeypatch.setattr(PreparedGoal, "splice", spy)
    scene, planner = _setup("building-floor")
    q = scene.queries[0]
    fresh = planner.plan(q.start, q.goal, q.t0)
    assert fresh.solved and len(built) == 1
    prepared = planner.prepare(q.goal)
    again = planner.plan_from(prepared, q.start, q.t0)
    assert len(built) == 2
    assert again.trajectory == fresh.trajectory  # the same graph: the same search, the same route
    (s1, g1), (s2, g2) = built
    np.testing.assert_array_equal(s1, s2)
    for field in ("poses", "indptr", "neighbors", "heuristic", "from_start", "groups"):
        np.testing.assert_array_equal(getattr(g1.graph, field), getattr(g2.graph, field))
    assert (g1.s_id, g1.g_id, g1.roadmap_distance) == (g2.s_id, g2.g_id, g2.roadmap_distance)
    nav = Navigator(scene, planner.roadmap, q.goal)  # its own dt and stretch (NavOptions)
    nav.step(q.t0, np.asarray(q.start, float), np.zeros((0, 5)))
    assert len(built) >= 3
    np.testing.assert_array_equal(built[2][0], s1)
    ref = planner.prepare(q.goal, nav._kept.options).splice(planner, built[2][0], lead=True)  # the start as wrapped
    for field in ("poses", "indptr", "neighbors", "heuristic", "from_start"):
        np.testing.assert_array_equal(getattr(built[2][1].graph, field), getattr(ref.graph, field))


def test_the_point_limit_covers_the_starts_connections(monkeypatch):
    """settings.MAX_POINTS bounds the whole graph: a limit the spanner and the goal's
    connections fit under, but not the start's too, refuses a fresh plan and plan_from
    alike (a LimitError, before the start's connections are cut)."""
    import gfuzzy.timespace.roadgraph as roadgraph
    from gfuzzy.errors import LimitError

    scene, planner = _setup("building-floor")
    q = scene.queries[0]
    whole = planner.plan(q.start, q.goal, q.t0).stats.graph_nodes  # points of the whole graph
    monkeypatch.setattr(roadgraph, "MAX_POINTS", whole - 1)
    kept = planner.prepare(q.goal)  # the spanner and the goal's connections fit
    with pytest.raises(LimitError, match="too fine"):
        planner.plan_from(kept, q.start, q.t0)
    with pytest.raises(LimitError, match="too fine"):
        planner.plan(q.start, q.goal, q.t0)
    monkeypatch.setattr(roadgraph, "MAX_POINTS", whole)
    assert planner.plan_from(kept, q.start, q.t0).solved


def test_a_leading_splice_cuts_whole_steps_away_from_the_start_and_up_to_the_goal():
    """``splice(lead=True)``: on every connection of the start, interior points lie whole
    steps from the start; on every connection of the goal, whole steps from its roadmap
    vertex (the remainder at the goal). Flipping either direction moves them."""
    scene, planner = _setup("building-floor")
    q = scene.queries[0]
    prepared = planner.prepare(q.goal)
    start = np.asarray(q.start, float)
    qg = prepared.splice(planner, start, lead=True)
    poses, step = qg.graph.poses, prepared.step_len
    inner = poses[prepared.base.N0:]  # the connections' interior points
    edges, lengths = prepared._start_edges(planner, start, ())
    ends = [(start, planner.roadmap.vertices[v], d) for (_, v), d in zip(edges, lengths, strict=True)]
    ends += [(planner.roadmap.vertices[v], prepared.goal, d)
             for (_, v), d in zip(prepared.goal_edges, prepared.goal_lengths, strict=True)]  # fmt: skip
    checked = 0
    for a, b, d in ends:  # whole steps from a towards b
        k = math.ceil(d / step - 1e-9)
        if k < 2 or (k - 1) * step >= d - 1e-9:
            continue
        for m in range(1, k):
            want = a + (b - a) * (m * step / d)
            assert np.min(np.linalg.norm(inner[:, :2] - want[:2], axis=1)) < 1e-9
            checked += 1
    assert checked >= 4
