"""The one builder of a holonomic query's graph: the goal's part kept, the start spliced in.

Every holonomic query's space-time graph is built here, in two steps: :func:`prepare_goal`
(the goal's certified connections, and the static distances to the goal on the vertices),
then :meth:`PreparedGoal.splice` (the start's connections; both ends' connections cut into
steps and spliced into the roadmap's kept spanner cut; the figures that depend on the
start). A fresh :meth:`Planner.plan <gfuzzy.planner.planner.Planner.plan>` runs both;
:meth:`~gfuzzy.planner.planner.Planner.plan_from` and the navigator keep the first
(:meth:`~gfuzzy.planner.planner.Planner.prepare`) and run the second per call. So the three
search the same graph for the same start and goal, under the same point-count limit
(``settings.MAX_POINTS``, checked before anything is cut).

A navigator replans every fraction of a second from the robot's current pose to the same
goal among newly predicted movers. What does not change between two calls is kept in a
:class:`PreparedGoal`:

* the goal's certified connections (and its static clearance);
* the static distances to the goal: in steps (the search's heuristic; per vertex, and per
  point of the spanner's edges) and in metres (the roadmap distance of the answer), by
  Dijkstra, once.

The spanner cut into one-step points is the roadmap's (:mod:`gfuzzy.timespace.roadgraph`,
cached per step length and stretch). Per call only the start's connections are certified
(the vertices' clearances come from the roadmap's cache); the goal's and the start's
connections are cut and spliced into the spanner's cut in one pass
(:meth:`~gfuzzy.timespace.roadgraph.SplitSpanner.splice`: one ``np.insert``, no sort of the
whole graph). One Dijkstra runs per call, from the start over the kept *vertex* graph (the
spanner's edges and the goal's connections, weighted in steps, the start's row spliced in),
then along each edge's points: the steps from the start to every point, exact. It gives
both figures the search needs, exactly:

* the earliest step a point can be reached (the lower end of its safety window);
* the steps to the goal, ``min(h(x), from_start(x) + h(start))``: a shortest route from x
  either avoids the start (the kept distance h(x)) or passes through it.

Its cost grows with the roadmap's vertices, not with its points (0.1 ms at 1000 vertices,
0.8 ms at 5000 on building floor). Bounds without it were measured and dropped: the metric
distance and the triangle inequality with the goal as the landmark,
``max(|x - start| / step, h(start) - h(x))``, are admissible but loose behind the start,
where safety windows then open earlier: the search computed about 14 % more mover
distances and lost more time than the Dijkstra costs; and the metric term alone cost more
per call (1.4 ms at 5000 vertices, a pass over every point) than the Dijkstra.

So the answer is a fresh :meth:`Planner.plan`'s from the same pose (the same graph,
heuristic and windows: a fresh plan is this module's two steps; only a fresh plan joins
ends the roadmap does not join through the free space or bridges its start; a prepared goal
with no certified connection is bridged here, :mod:`gfuzzy.planner.bridge`).
Safety is still only computed where movers come near a point inside its window (the broad
phase), so a call's cost follows the movers near the robot's reachable space-time. The
graph part of a call is a handful of vectorised passes over the points (the search needs
whole arrays: the heuristic and the windows change with the start), plus the start's
certified connections.
"""

from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..collision.geometry import metric_distance
from ..poses import split_counts, wrap_angle
from ..settings import SPEED_SAFETY
from ..timespace.roadgraph import (
    SplitSpanner,
    VertexGraph,
    check_points,
    roadmap_metres,
    spanner_split,
    split_points,
)
from ..timespace.spacetime import QueryGraph, SpaceTimeGraph, split_edges
from ..typed import FloatArray, IntArray

__all__ = ["PreparedGoal", "QueryGraph", "check_time_step", "prepare_goal", "split_edges"]


def check_time_step(robot, roadmap, options) -> None:
    """Refuse ``options.dt`` as too fine for ``roadmap`` whatever the query, before any graph is
    built: the count a plan refuses first (a holonomic robot's spanner cut, a differential
    drive's turning ring; a finer dt past the other bounds still fails the query itself).

    Raises
    ------
    TimeStepError
        When the count exceeds ``settings.MAX_POINTS``.
    """
    step_len = robot.vmax * SPEED_SAFETY * options.dt
    if robot.unicycle:
        from ..timespace.unicycle import ring_points

        ring_points(robot.vmax, robot.turn_rate, step_len)
    else:
        check_points(split_points(roadmap, step_len, options.stretch))


@dataclass
class PreparedGoal:
    """The part of a query that does not depend on the start (see the module docstring).

    Ids, as in every query graph: the roadmap's vertices, the start ``s_id``, the goal
    ``g_id`` (``n = g_id + 1`` vertex ids), the spanner's interior points (``base``, up to
    ``base.N0``), then the goal's connections' points, then the start's.

    Attributes
    ----------
    goal : (d,) float
        Heading wrapped to [-pi, pi) for a box robot.
    goal_raw : (d,) float
        As given (the answer's last row repeats it).
    options : PlanOptions
    s_id, g_id : int
    base : gfuzzy.timespace.roadgraph.SplitSpanner
        The roadmap's spanner cut into steps (the roadmap's cache).
    goal_edges : (x, 2) int
        The goal's certified connections ``(g_id, vertex)``.
    goal_lengths : (x,) float
        Their metric lengths.
    hop : (n,) float
        Steps to the goal on the vertex graph without the start (inf at the start).
    base_heuristic : (base.N0 - n,) float
        The same at the spanner's interior points.
    dist : (n,) float
        Metres to the goal on the whole roadmap with the goal's connections (the roadmap
        distance; inf at the start).
    vgraph : VertexGraph
        The spanner and the goal's connections on the vertex ids, weighted in steps; the
        start's row is empty.
    step_len : float
        ``vmax * SPEED_SAFETY * dt``: the longest step.
    goal_clearance : float
        The goal's static clearance (``StaticGeometry.clearance1``).
    bridged : Planner or None
        The planner on the roadmap with the goal's bridge (:mod:`gfuzzy.planner.bridge`)
        when the goal was bridged: every start is then spliced on it (a start on the way
        along the bridge connects to its poses).
    """

    goal: FloatArray
    goal_raw: FloatArray
    options: object
    s_id: int
    g_id: int
    base: SplitSpanner
    goal_edges: IntArray
    goal_lengths: FloatArray
    hop: FloatArray
    base_heuristic: FloatArray
    dist: FloatArray
    vgraph: VertexGraph
    step_len: float
    goal_clearance: float
    bridged: object = None

    def splice(self, planner, start: FloatArray, ahead=(), lead: bool = False) -> QueryGraph:
        """The query's graph: the spanner's cut with the goal's and ``start``'s connections.

        Parameters
        ----------
        planner : gfuzzy.planner.planner.Planner
            The planner this goal was prepared on (its roadmap and collision model).
        start : (d,) float
            A free pose (heading wrapped to [-pi, pi) for a box robot).
        ahead : sequence of int
            Roadmap vertices to try too, after the nearest (the navigator's: those its
            last plan was heading for); the first two not connected already are tried.
        lead : bool
            Cut the start's connections into whole steps from the start (the remainder
            last) and the goal's into whole steps up to the goal (the remainder at the
            goal), instead of equal pieces (:func:`split_edges`): the same step counts, costs
            and heuristic (the interior points move, so among movers the safety checks and
            the answer may differ), but a plan run for a moment and replanned (the
            navigator's) then leaves at full speed and slows only in an edge's last step.

        Returns
        -------
        QueryGraph
            ``roadmap_distance`` inf when no connection of the start leads to the goal.

        Raises
        ------
        LimitError
            When the graph would exceed ``settings.MAX_POINTS`` points (checked before
            the connections are cut).
        """
        planner = planner if self.bridged is None else self.bridged
        edges, lengths = self._start_edges(planner, start, ahead)
        base, n, N0 = self.base, self.g_id + 1, self.base.N0
        x = len(self.goal_edges)
        both = np.vstack([self.goal_edges, edges])
        # the goal's edges run (goal, v): whole steps up to v leave the remainder at the goal
        lead_of = np.concatenate([np.full(x, -1), np.full(len(edges), 1)]) if lead else None
        cut = base.splice(both, np.concatenate([self.goal_lengths, lengths]), np.vstack([start, self.goal]), lead_of)
        k = cut.k[x:]  # the start's edges' steps
        ends = edges[:, 1]
        rd = float(np.min(lengths + self.dist[ends], initial=np.inf))
        h_s = float(np.min(k + self.hop[ends], initial=np.inf))
        fs_v = self._from_start(ends, k)
        # steps to the goal at the vertices: a shortest route avoids the start or passes it
        hop = np.minimum(self.hop, fs_v + h_s)
        total = len(cut.poses)
        rest = np.repeat(cut.k, cut.k - 1) - cut.j  # the connections' points' steps to b
        from_start = np.empty(total)
        from_start[:n] = fs_v
        _along(fs_v, base.a, base.j, base.b, base.rest, from_start[n:N0])
        _along(fs_v, cut.a, cut.j, cut.b, rest, from_start[N0:])
        heur = np.empty(total)
        heur[:n] = hop
        np.add(from_start[n:N0], h_s, out=heur[n:N0])
        np.minimum(heur[n:N0], self.base_heuristic, out=heur[n:N0])
        _along(hop, cut.a, cut.j, cut.b, rest, heur[N0:])
        groups = np.concatenate([n + base.offs, N0 + cut.offs[1:]])
        graph = SpaceTimeGraph(cut.poses, cut.indptr, cut.neighbors, heur, groups=groups, from_start=from_start)
        return QueryGraph(graph, self.s_id, self.g_id, rd)

    def bridged_from(self, planner, start: FloatArray, deadline: float = math.inf, clock=time.perf_counter):
        """This goal's graph again on a copy of its roadmap with a bridge from ``start`` to the
        vertices that lead to the goal (:func:`gfuzzy.planner.bridge.bridge`; for a disc robot
        that finds none, its link through the free space,
        :meth:`~gfuzzy.planner.planner.Planner._linked`), or None when none is found (the
        bridge by ``deadline`` on ``clock``).

        The navigator's, for a robot deep in a dead end. The copy is a superset of this graph
        (the same vertices and edges, the bridge's after them: vertex ids keep their meaning),
        so it answers every start this one does.
        """
        from .bridge import bridge, with_chains

        base = planner if self.bridged is None else self.bridged
        rm = base.roadmap
        targets = np.flatnonzero(np.isfinite(self.dist[: len(rm.vertices)]))
        found = bridge(base.geometry, rm, np.asarray(start, dtype=float), targets, deadline, clock) if len(targets) else None
        if found is not None:
            out = copy.copy(base)
            out.roadmap = with_chains(rm, [found])
        else:  # a disc's way out by the free space (a dead end along none of the rays)
            out = base._linked([start], self.options.connect_k, join=False)  # as the kept graph: not repaired
            if out is None:
                return None
        return replace(prepare_goal(out, self.goal_raw, self.options, bridge=False), bridged=out)

    def _start_edges(self, planner, start: FloatArray, ahead) -> tuple[IntArray, FloatArray]:
        """The start's certified connections: (x, 2) int edges from ``s_id``, (x,) metres."""
        robot = planner.robot
        c_s = planner.geometry.clearance1(start)
        conn = planner._connect(start, self.options.connect_k, c_s)
        seen = {v for v, _ in conn}
        for v in [v for v in ahead if v not in seen][:2]:
            target = planner.roadmap.vertices[v]
            if planner.geometry.motion_free(start, target, ca=c_s):
                conn.append((int(v), float(metric_distance(start, target, robot.circumradius))))
        e = [(self.s_id, v) for v, _ in conn]
        w = [d for _, d in conn]
        if planner.geometry.motion_free(start, self.goal, ca=c_s, cb=self.goal_clearance):
            e.append((self.s_id, self.g_id))
            w.append(float(metric_distance(start, self.goal, robot.circumradius)))
        return np.array(e, dtype=np.int64).reshape(-1, 2), np.array(w, dtype=float)

    def _from_start(self, ends: IntArray, k: IntArray) -> FloatArray:
        """Steps from the start to every vertex id (Dijkstra on the vertex graph with the
        start's row filled: a shortest route never comes back to the start)."""
        g = self.vgraph
        at = g.indptr[self.s_id]
        indptr = g.indptr.copy()
        indptr[self.s_id + 1 :] += len(ends)
        indices = np.concatenate([g.indices[:at], ends, g.indices[at:]])  # the start's row: empty before
        data = np.concatenate([g.data[:at], np.maximum(k, 1e-300), g.data[at:]])
        return np.rint(VertexGraph(g.n, indptr, indices, data).distances(self.s_id))


def _along(at_vertices: FloatArray, a: IntArray, j: IntArray, b: IntArray, rest: IntArray, out: FloatArray) -> None:
    """Steps at interior points from steps at their edges' ends: ``out = min(at_vertices[a]
    + j, at_vertices[b] + rest)`` (a point leaves its edge through one end), in place."""
    np.take(at_vertices, a, out=out)
    out += j
    other = np.take(at_vertices, b)
    other += rest
    np.minimum(out, other, out=out)


def prepare_goal(planner, goal: FloatArray, options, bridge: bool = True, deadline: float = math.inf) -> PreparedGoal:
    """The goal's part of every query graph to ``goal`` (the module docstring's first step).

    Parameters
    ----------
    planner : gfuzzy.planner.planner.Planner
    goal : (d,) float
        As given: a box robot's heading is wrapped here (the answer's last row repeats
        ``goal`` as given).
    options : PlanOptions
        Its ``dt``, ``stretch`` and ``connect_k`` shape the graph.
    bridge : bool
        A goal with no certified connection is bridged to the roadmap
        (:mod:`gfuzzy.planner.bridge`; a disc robot's that finds no bridge is linked
        through the free space, :meth:`~gfuzzy.planner.planner.Planner._linked`): the result is then prepared on a copy of the roadmap
        with the bridge's poses appended (its ``base`` and ids are the copy's; ``splice``
        still takes the planner on the roadmap, whose vertices keep their ids).

    Returns
    -------
    PreparedGoal

    Raises
    ------
    LimitError
        When the spanner's and the goal's points would exceed ``settings.MAX_POINTS``.
    """
    robot = planner.robot
    rm = planner.roadmap
    goal_raw = np.asarray(goal, dtype=float).copy()
    goal = goal_raw.copy()
    if robot.dof == 3:
        goal[2] = wrap_angle(goal[2])
    nv = len(rm.vertices)
    s_id, g_id = nv, nv + 1
    c_g = planner.geometry.clearance1(goal)
    conn = planner._connect(goal, options.connect_k, c_g)
    if not conn and bridge:  # deep in a dead end: only the goal's graph gets the bridge
        from .bridge import bridged_planner

        bridged = bridged_planner(planner, [goal], options.connect_k, deadline) or planner._linked([goal], options.connect_k)
        if bridged is not None:
            return replace(prepare_goal(bridged, goal_raw, options, bridge=False), bridged=bridged)
    edges = np.array([(g_id, v) for v, _ in conn], dtype=np.int64).reshape(-1, 2)
    lengths = np.array([d for _, d in conn], dtype=float)
    step_len = robot.vmax * SPEED_SAFETY * options.dt
    base = spanner_split(rm, step_len, options.stretch)
    k = split_counts(lengths, step_len)
    check_points(base.N0 + int((k - 1).sum()))

    # static shortest distances to the goal (the vertex graphs are kept on the roadmap, the
    # goal's connections added): in metres on the whole roadmap for the roadmap distance,
    # in steps on the spanner for the heuristic (exact on the static graph: the tightest
    # admissible one)
    def sp(graph: VertexGraph):
        out = graph.distances(g_id)
        return np.where(out < 1e-200, 0.0, out)

    vgraph = base.steps.with_edges(edges, k.astype(float))
    hop = np.rint(sp(vgraph))
    base_heuristic = np.empty(base.N0 - base.n)
    _along(hop, base.a, base.j, base.b, base.rest, base_heuristic)
    return PreparedGoal(
        goal=goal,
        goal_raw=goal_raw,
        options=options,
        s_id=s_id,
        g_id=g_id,
        base=base,
        goal_edges=edges,
        goal_lengths=lengths,
        hop=hop,
        base_heuristic=base_heuristic,
        dist=sp(roadmap_metres(rm).with_edges(edges, lengths)),
        vgraph=vgraph,
        step_len=step_len,
        goal_clearance=c_g,
    )
