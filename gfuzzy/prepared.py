"""Replanning to a fixed goal: the roadmap graph built once, the start spliced in per call.

A navigator replans every fraction of a second from the robot's current pose to the same
goal among newly predicted movers. What does not change between two calls is kept in a
:class:`PreparedGoal` (:meth:`gfuzzy.planner.Planner.prepare`):

* the roadmap's spanner with the goal connected, every edge split into one-step points
  (the spanner's cut comes from the roadmap's cache, :mod:`gfuzzy.roadgraph`);
* the static distances to the goal: in steps (the search's heuristic) and in metres (the
  roadmap distance of the answer), by Dijkstra, once;
* the goal's static clearance (its certified connections need it).

Per call (:meth:`gfuzzy.planner.Planner.plan_from`) only the start is spliced in: its
certified straight connections to the nearest vertices (the vertices' clearances come from
the roadmap's cache) and to the goal directly, split into steps and appended after the
kept points; the kept adjacency lists get the start's moves appended (one ``np.insert``,
no sort). No shortest-path search runs per call, so two bounds replace the fresh plan's
exact ones, and both stay admissible (never above the truth):

* the heuristic of a kept point x becomes ``min(h(x), |x - start| / step + h(start))``:
  the start may offer a shortcut the kept distances do not know of;
* the earliest step a point can be reached (the lower end of its safety window) becomes
  ``max(|x - start| / step, h(start) - h(x))``. The first term: no step is longer than
  ``step``. The second is the triangle inequality with the goal as the landmark: the
  spliced graph's distance to the goal from x is at most the kept one, h(x), and from the
  start it is exactly h(start) (a shortest route leaves the start once, through one of its
  connections, into the kept graph), so reaching x takes at least h(start) - h(x) steps.
  It replaces a Dijkstra over the roadmap per call (issue 11); points beyond the start,
  away from the goal, only get the metric term, so their windows open earlier and a
  little more safety may be computed there, never a different answer.

So the answer arrives at the same step as a fresh :meth:`Planner.plan` from the same pose
(the search is exact for any admissible heuristic: it reopens states), though arrival-equal
answers may take other routes; safety is still only computed where movers come near a
point inside its window (the broad phase), so a call's cost follows the movers near the
robot's reachable space-time. The graph part of a call is a handful of vectorised passes
over the kept arrays (the search needs whole arrays: the heuristic and the windows change
with the start), plus the start's certified connections.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .geometry import metric_distance
from .roadgraph import spanner_split
from .settings import SPEED_SAFETY
from .spacetime import SpaceTimeGraph, split_edges
from .typing import FloatArray, IntArray

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

    def splice(self, planner, start: FloatArray):
        """The kept graph with ``start`` connected: (graph, s_id, g_id, roadmap distance)."""
        opts = self.options
        robot = planner.robot
        c_s = planner.geometry.clearance1(start)
        conn = planner._connect(start, opts.connect_k, c_s)
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
        # admissible on the spliced graph: a route may use the start as a shortcut
        near = metric_distance(poses, start[None, :], robot.circumradius) / self.step_len
        heur = np.minimum(kept_h, near + h_s)
        # earliest steps: see the module docstring (no Dijkstra per call)
        from_start = near
        if np.isfinite(h_s):
            from_start = np.maximum(near, np.where(np.isfinite(kept_h), h_s - kept_h, 0.0))
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


def _split_from(start, ends, edges, lengths, step_len, first_id):
    """:func:`split_edges` of the start's edges, given the poses at their far ends."""
    m = len(edges)
    verts = np.vstack([start[None], ends]) if m else start[None]
    local = np.stack([np.zeros(m, dtype=np.int64), np.arange(1, m + 1)], axis=1)
    k, offs, inner, a, b, j, src, dst = split_edges(verts, local, lengths, step_len, first_id)
    ids = np.concatenate([edges[:, 1], [edges[0, 0]] if m else []]).astype(np.int64)

    def back(x):  # local ids (0: the start, 1..m: the ends) to graph ids; interior unchanged
        x = np.asarray(x, dtype=np.int64)
        out = x.copy()
        small = x < first_id
        out[small] = np.where(x[small] == 0, ids[-1] if m else 0, ids[np.maximum(x[small] - 1, 0)])
        return out

    return k, offs, inner, back(a), back(b), j, back(src), back(dst)


def prepare_goal(planner, goal: FloatArray, options) -> PreparedGoal:
    """Build a :class:`PreparedGoal` (see :meth:`gfuzzy.planner.Planner.prepare`)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import dijkstra

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

    def sp(edges_, weights):
        w = np.maximum(weights, 1e-300)  # csgraph drops explicit zeros
        rows = np.r_[edges_[:, 0], edges_[:, 1]]
        cols = np.r_[edges_[:, 1], edges_[:, 0]]
        mat = coo_matrix((np.r_[w, w], (rows, cols)), shape=(n, n)).tocsr()
        out = dijkstra(mat, directed=True, indices=g_id)
        return np.where(out < 1e-200, 0.0, out)

    dist = sp(np.vstack([rm.edges, extra_e]), np.concatenate([rm.lengths, extra_w]))
    hop_g = np.rint(sp(np.vstack([base.edges, extra_e]), np.concatenate([base.k, kept.k]).astype(float)))
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
    )
