"""Planner.prepare / plan_from (replanning to a fixed goal) against fresh plans."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

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


@pytest.mark.parametrize("name", SCENES)
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
        graph, s_id, g_id, _ = prepared.splice(planner, start)
        n = len(graph.poses)
        rows = np.repeat(np.arange(n), np.diff(graph.indptr))
        adj = csr_matrix((np.ones(len(rows)), (rows, graph.neighbors)), shape=(n, n))
        exact = shortest_path(adj, unweighted=True, indices=[s_id, g_id])
        np.testing.assert_array_equal(graph.from_start, exact[0])
        np.testing.assert_array_equal(graph.heuristic, exact[1])
        spliced += 1
    assert spliced == 3
