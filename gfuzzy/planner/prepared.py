"""Replanning to a fixed goal: the roadmap graph built once, the start spliced in per call.

A navigator replans every fraction of a second from the robot's current pose to the same
goal among newly predicted movers. What does not change between two calls is kept in a
:class:`PreparedGoal` (:meth:`gfuzzy.planner.planner.Planner.prepare`):

* the roadmap's spanner with the goal connected, every edge split into one-step points
  (the spanner's cut comes from the roadmap's cache, :mod:`gfuzzy.timespace.roadgraph`);
* the static distances to the goal: in steps (the search's heuristic) and in metres (the
  roadmap distance of the answer), by Dijkstra, once;
* the goal's static clearance (its certified connections need it).

Per call (:meth:`gfuzzy.planner.planner.Planner.plan_from`) only the start is spliced in: its
certified straight connections to the nearest vertices (the vertices' clearances come from
the roadmap's cache) and to the goal directly, split into steps and appended after the
kept points; the kept adjacency lists get the start's moves appended (one ``np.insert``,
no sort). One Dijkstra runs per call, from the start over the kept *vertex* graph (the
spanner's edges and the goal's connections, weighted in steps, the start's row spliced
in), then along each edge's points: the steps from the start to every point, exact, as in
a fresh plan. It gives both figures the search needs, exactly:

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

So the answer arrives at the same step as a fresh :meth:`Planner.plan` from the same pose
(the heuristic and the windows are a fresh plan's; the points are numbered otherwise, so
arrival-equal answers may take other routes); safety is still only computed where movers come near a
point inside its window (the broad phase), so a call's cost follows the movers near the
robot's reachable space-time. The graph part of a call is a handful of vectorised passes
over the kept arrays (the search needs whole arrays: the heuristic and the windows change
with the start), plus the start's certified connections.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..collision.geometry import metric_distance
from ..settings import SPEED_SAFETY
from ..timespace.roadgraph import VertexGraph, spanner_split
from ..timespace.spacetime import SpaceTimeGraph, split_edges
from ..typed import FloatArray, IntArray

__all__ = ["PreparedGoal", "split_edges"]


@dataclass
class PreparedGoal:
    """The part of a query that does not depend on the start (see the module docstring).

    Attributes
    ----------
    goal : (d,) float
        Heading wrapped to [-pi, pi) for a box robot.
    goal_raw : (d,) float
        As given (the answer's last row repeats it).
    options : PlanOptions
    s_id, g_id : int
        Ids of the start (no edges until spliced) and of the goal.
    poses : (N, d) float
    indptr, neighbors : CSR adjacency of the kept graph.
    heuristic : (N,) float
        Steps to the goal on the kept graph.
    dist : (n,) float
        Metres to the goal on the whole roadmap, per vertex (the roadmap distance).
    groups : (G+1,) int
        Point groups (edges) of the kept graph.
    step_len : float
    goal_clearance : float
        The goal's static clearance (``StaticGeometry.clearance1``).
    vgraph : VertexGraph (n vertices)
        The kept vertex graph, weights in steps; the start's row is empty.
    pa, pb, pj, pk : (N - n,) int
        Per kept interior point: its edge's ends, its index along it, the edge's steps.
    """

    goal: FloatArray
    goal_raw: FloatArray
    options: object
    s_id: int
    g_id: int
    poses: FloatArray
    indptr: IntArray
    neighbors: IntArray
    heuristic: FloatArray
    dist: FloatArray
    groups: IntArray
    step_len: float
    goal_clearance: float
    vgraph: object
    pa: IntArray
    pb: IntArray
    pj: IntArray
    pk: IntArray

    def splice(self, planner, start: FloatArray, ahead=()):
        """The kept graph with ``start`` connected: (graph, s_id, g_id, roadmap distance).

        ``ahead``: roadmap vertices to try too, after the nearest (the navigator's: those
        its last plan was heading for); the first two not connected already are tried.
        """
        opts = self.options
        robot = planner.robot
        c_s = planner.geometry.clearance1(start)
        conn = planner._connect(start, opts.connect_k, c_s)
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
        edges = np.array(e, dtype=np.int64).reshape(-1, 2)
        lengths = np.array(w, dtype=float)
        N = len(self.poses)
        ends = self.poses[: self.g_id + 1][edges[:, 1]]  # the vertices' (and goal's) poses
        k, offs, inner, a, b, j, src, dst = _split_from(start, ends, edges, lengths, self.step_len, N)
        total = N + int(offs[-1])
        poses = np.concatenate([self.poses, inner])
        poses[self.s_id] = start
        # roadmap distance and heuristic of the start: through one of its connections
        dist_v = np.append(self.dist, [np.inf, 0.0])  # start (unknown yet), goal
        rd = float(np.min(lengths + dist_v[edges[:, 1]], initial=np.inf))
        h_s = float(np.min(k + self.heuristic[edges[:, 1]], initial=np.inf))
        kept_h = np.empty(total)
        kept_h[:N] = self.heuristic
        kept_h[self.s_id] = h_s
        ke = np.repeat(k, offs[1:] - offs[:-1])
        kept_h[N:] = np.minimum(h_s + j, self.heuristic[b] + ke - j)
        # steps from the start, exact (see the module docstring), then to the goal
        fs_v = self._from_start(edges[:, 1], k)
        from_start = np.empty(total)
        n = len(fs_v)
        from_start[:n] = fs_v
        from_start[n:N] = np.minimum(fs_v[self.pa] + self.pj, fs_v[self.pb] + self.pk - self.pj)
        from_start[N:] = np.minimum(j, fs_v[b] + ke - j)
        heur = np.minimum(kept_h, from_start + h_s)
        # adjacency: the start's moves after each kept list, the new points' lists appended
        s2 = np.concatenate([src, dst])
        d2 = np.concatenate([dst, src])
        order = np.argsort(s2, kind="stable")  # few: the start's edges only
        s2, d2 = s2[order], d2[order]
        at = np.where(s2 < N, self.indptr[np.minimum(s2, N - 1) + 1], len(self.neighbors))
        nbrs = np.insert(self.neighbors, at, d2)
        indptr = np.concatenate([self.indptr, np.full(total - N, self.indptr[-1])])
        indptr[1:] += np.cumsum(np.bincount(s2, minlength=total))
        groups = np.concatenate([self.groups, N + offs[1:]]) if offs[-1] > 0 else self.groups
        graph = SpaceTimeGraph(poses, indptr, nbrs, heur, groups=groups, from_start=from_start)
        return graph, self.s_id, self.g_id, rd


    def _from_start(self, ends: IntArray, k: IntArray) -> FloatArray:
        """Steps from the start to every vertex of the kept graph (Dijkstra)."""
        g = self.vgraph
        at = g.indptr[self.s_id]
        indptr = g.indptr.copy()
        indptr[self.s_id + 1 :] += len(ends)
        mat = VertexGraph(g.n, indptr, np.insert(g.indices, at, ends), np.insert(g.data, at, np.maximum(k, 1e-300)))
        return np.rint(mat.distances(self.s_id))


def _split_from(start, ends, edges, lengths, step_len, first_id):
    """:func:`split_edges` of the start's edges, given the poses at their far ends."""
    m = len(edges)
    verts = np.vstack([start[None], ends]) if m else start[None]
    local = np.stack([np.zeros(m, dtype=np.int64), np.arange(1, m + 1)], axis=1)
    cut = split_edges(verts, local, lengths, step_len, first_id)
    k, offs, inner, a, b, j, src, dst = cut.k, cut.offs, cut.inner, cut.a, cut.b, cut.j, cut.src, cut.dst
    ids = np.concatenate([edges[:, 1], [edges[0, 0]] if m else []]).astype(np.int64)

    def back(x):  # local ids (0: the start, 1..m: the ends) to graph ids; interior unchanged
        x = np.asarray(x, dtype=np.int64)
        out = x.copy()
        small = x < first_id
        out[small] = np.where(x[small] == 0, ids[-1] if m else 0, ids[np.maximum(x[small] - 1, 0)])
        return out

    return k, offs, inner, back(a), back(b), j, back(src), back(dst)


def prepare_goal(planner, goal: FloatArray, options) -> PreparedGoal:
    """Build a :class:`PreparedGoal` (see :meth:`gfuzzy.planner.planner.Planner.prepare`)."""
    robot = planner.robot
    rm = planner.roadmap
    goal_raw = np.asarray(goal, dtype=float).copy()
    goal = goal_raw.copy()
    if robot.dof == 3:
        goal[2] = (goal[2] + np.pi) % (2 * np.pi) - np.pi
    nv = len(rm.vertices)
    s_id, g_id = nv, nv + 1
    c_g = planner.geometry.clearance1(goal)
    conn = planner._connect(goal, options.connect_k, c_g)
    extra_e = np.array([(g_id, v) for v, _ in conn], dtype=np.int64).reshape(-1, 2)
    extra_w = np.array([d for _, d in conn], dtype=float)
    step_len = robot.vmax * SPEED_SAFETY * options.dt
    base = spanner_split(rm, step_len, options.stretch)
    kept = base.splice(extra_e, extra_w, np.vstack([goal, goal]))  # the start's row: filled per call
    n = base.n

    def matrix(edges_, weights):  # sorted CSR, weights at least 1e-300 (csgraph drops zeros)
        return VertexGraph.of(n, edges_, weights)

    def sp(mat):
        out = mat.distances(g_id)
        return np.where(out < 1e-200, 0.0, out)

    dist = sp(matrix(np.vstack([rm.edges, extra_e]), np.concatenate([rm.lengths, extra_w])))
    vgraph = matrix(np.vstack([base.edges, extra_e]), np.concatenate([base.k, kept.k]).astype(float))
    hop_g = np.rint(sp(vgraph))
    heur = np.empty(len(kept.poses))
    heur[:n] = hop_g
    heur[n : base.N0] = np.minimum(hop_g[base.a] + base.j, hop_g[base.b] + base.ke - base.j)
    ke = np.repeat(kept.k, kept.k - 1)
    heur[base.N0 :] = np.minimum(hop_g[kept.a] + kept.j, hop_g[kept.b] + ke - kept.j)
    return PreparedGoal(
        goal=goal,
        goal_raw=goal_raw,
        options=options,
        s_id=s_id,
        g_id=g_id,
        poses=kept.poses,
        indptr=kept.indptr,
        neighbors=kept.neighbors,
        heuristic=heur,
        dist=dist[:nv],
        groups=np.concatenate([n + base.offs, base.N0 + kept.offs[1:]]),
        step_len=step_len,
        goal_clearance=c_g,
        vgraph=vgraph,
        pa=np.concatenate([base.a, kept.a]),
        pb=np.concatenate([base.b, kept.b]),
        pj=np.concatenate([base.j, kept.j]),
        pk=np.concatenate([base.ke, ke]),
    )
