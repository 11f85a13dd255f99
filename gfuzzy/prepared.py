"""Replanning to a fixed goal: the roadmap graph built once, the start spliced in per call.

A navigator replans every fraction of a second from the robot's current pose to the same
goal among newly predicted movers. What does not change between two calls is kept in a
:class:`PreparedGoal` (:meth:`gfuzzy.planner.Planner.prepare`):

* the roadmap's spanner with the goal connected, every edge split into one-step points;
* the static distances to the goal: in steps (the search's heuristic) and in metres (the
  roadmap distance of the answer), by Dijkstra, once.

Per call (:meth:`gfuzzy.planner.Planner.plan_from`) only the start is spliced in: its
certified straight connections to the nearest vertices (and to the goal directly), split
into steps and appended after the kept points; the adjacency is rebuilt by a vectorised
merge (no sort). No Dijkstra runs per call, so two bounds replace the fresh plan's exact
ones, and both stay admissible (never above the truth):

* the heuristic of a kept point x becomes ``min(h(x), |x - start| / step + h(start))``:
  the start may offer a shortcut the kept distances do not know of;
* the earliest step a point can be reached (the lower end of its safety window) becomes
  ``|x - start| / step`` (the metric distance, in steps) instead of the graph distance.

So the answer arrives at the same step as a fresh :meth:`Planner.plan` from the same pose
(the search is exact for any admissible heuristic: it reopens states), though arrival-equal
answers may take other routes; safety is still only computed where movers come near a
point inside its window (the broad phase), so a call's cost follows the movers near the
robot's reachable space-time, not the roadmap's size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import LimitError
from .geometry import metric_distance
from .settings import MAX_POINTS, SPEED_SAFETY
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
    vgraph: object  # scipy CSR of the kept vertex graph, weights in steps
    pa: IntArray  # per kept interior point: its edge's ends, its index along it, the edge's steps
    pb: IntArray
    pj: IntArray
    pk: IntArray

    def splice(self, planner, start: FloatArray):
        """The kept graph with ``start`` connected: (graph, s_id, g_id, roadmap distance)."""
        opts = self.options
        robot = planner.robot
        conn = planner._connect(start, opts.connect_k)
        e = [(self.s_id, v) for v, _ in conn]
        w = [d for _, d in conn]
        if planner.geometry.motion_free(start, self.goal):
            e.append((self.s_id, self.g_id))
            w.append(float(metric_distance(start, self.goal, robot.circumradius)))
        edges = np.array(e, dtype=np.int64).reshape(-1, 2)
        lengths = np.array(w, dtype=float)
        N = len(self.poses)
        poses = self.poses.copy()
        poses[self.s_id] = start
        k, offs, inner, a, b, j, src, dst = split_edges(poses, edges, lengths, self.step_len, N)
        total = N + int(offs[-1])
        # roadmap distance and heuristic of the start: through one of its connections
        dist_v = np.append(self.dist, [np.inf, 0.0])  # start (unknown yet), goal
        rd = float(np.min(lengths + dist_v[edges[:, 1]], initial=np.inf))
        h_s = float(np.min(k + self.heuristic[edges[:, 1]], initial=np.inf))
        heur = np.empty(total)
        heur[:N] = self.heuristic
        heur[self.s_id] = h_s
        ke = np.repeat(k, offs[1:] - offs[:-1])
        heur[N:] = np.minimum(h_s + j, self.heuristic[b] + ke - j)
        all_poses = np.vstack([poses, inner])
        # admissible on the spliced graph: a route may use the start as a shortcut
        near = metric_distance(all_poses, start[None, :], robot.circumradius) / self.step_len
        heur = np.minimum(heur, near + h_s)
        # earliest steps: one multi-source Dijkstra on the kept vertex graph from the
        # start's neighbours (each reached after at least the shortest connection)
        from_start = near
        if len(edges):
            from scipy.sparse.csgraph import dijkstra

            fs_v = dijkstra(self.vgraph, directed=True, indices=edges[:, 1], min_only=True) + k.min()
            fs_v[self.s_id] = 0.0
            fs = np.empty(total)
            fs[: len(fs_v)] = fs_v
            fs[len(fs_v) : N] = np.minimum(fs_v[self.pa] + self.pj, fs_v[self.pb] + self.pk - self.pj)
            fs[N:] = np.minimum(j, fs_v[b] + ke - j)
            from_start = np.maximum(near, np.where(np.isfinite(fs), fs, np.inf))
        # CSR: the kept lists, then each node's new moves after them (no sort)
        s2 = np.concatenate([src, dst])
        d2 = np.concatenate([dst, src])
        order = np.argsort(s2, kind="stable")  # few: the start's edges only
        s2, d2 = s2[order], d2[order]
        old_cnt = np.zeros(total, dtype=np.int64)
        old_cnt[:N] = np.diff(self.indptr)
        add_cnt = np.bincount(s2, minlength=total)
        indptr = np.zeros(total + 1, dtype=np.int64)
        np.cumsum(old_cnt + add_cnt, out=indptr[1:])
        nbrs = np.empty(indptr[-1], dtype=np.int64)
        src_old = np.repeat(np.arange(N), old_cnt[:N])
        nbrs[indptr[src_old] + (np.arange(len(self.neighbors)) - self.indptr[src_old])] = self.neighbors
        add_ptr = np.concatenate([[0], np.cumsum(add_cnt)])
        rank = np.arange(len(s2)) - add_ptr[s2]
        nbrs[indptr[s2] + old_cnt[s2] + rank] = d2
        groups = np.concatenate([self.groups, N + offs[1:]]) if offs[-1] > 0 else self.groups
        graph = SpaceTimeGraph(all_poses, indptr, nbrs, heur, groups=groups, from_start=from_start)
        return graph, self.s_id, self.g_id, rd


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
    conn = planner._connect(goal, options.connect_k)
    extra_e = np.array([(g_id, v) for v, _ in conn], dtype=np.int64).reshape(-1, 2)
    extra_w = np.array([d for _, d in conn], dtype=float)
    verts = np.vstack([rm.vertices, goal[None], goal[None]])  # the start's row: filled per call
    n = len(verts)
    keep = rm.spanner(options.stretch)
    edges = np.vstack([rm.edges[keep], extra_e])
    lengths = np.concatenate([rm.lengths[keep], extra_w])
    step_len = robot.vmax * SPEED_SAFETY * options.dt
    k, offs, inner, a, b, j, src, dst = split_edges(verts, edges, lengths, step_len, n)
    total = n + int(offs[-1])
    if total > MAX_POINTS:
        raise LimitError(
            f"the time step is too fine for this roadmap: its edges would be cut into "
            f"{total:,} points (at most {MAX_POINTS:,}); use a larger dt"
        )

    def matrix(edges_, weights):
        w = np.maximum(weights, 1e-300)  # csgraph drops explicit zeros
        rows = np.r_[edges_[:, 0], edges_[:, 1]]
        cols = np.r_[edges_[:, 1], edges_[:, 0]]
        return coo_matrix((np.r_[w, w], (rows, cols)), shape=(n, n)).tocsr()

    def sp(mat):
        out = dijkstra(mat, directed=True, indices=g_id)
        return np.where(out < 1e-200, 0.0, out)

    dist = sp(matrix(np.vstack([rm.edges, extra_e]), np.concatenate([rm.lengths, extra_w])))
    vgraph = matrix(edges, k.astype(float))
    hop_g = np.rint(sp(vgraph))
    heur = np.empty(total)
    heur[:n] = hop_g
    ke = np.repeat(k, offs[1:] - offs[:-1])
    heur[n:] = np.minimum(hop_g[a] + j, hop_g[b] + ke - j)
    s2 = np.concatenate([src, dst])
    d2 = np.concatenate([dst, src])
    order = np.argsort(s2, kind="stable")
    indptr = np.zeros(total + 1, dtype=np.int64)
    np.add.at(indptr, s2 + 1, 1)
    return PreparedGoal(
        goal=goal,
        goal_raw=goal_raw,
        options=options,
        s_id=s_id,
        g_id=g_id,
        poses=np.vstack([verts, inner]),
        indptr=np.cumsum(indptr),
        neighbors=d2[order],
        heuristic=heur,
        dist=dist[:nv],
        groups=n + offs,
        step_len=step_len,
        vgraph=vgraph,
        pa=a,
        pb=b,
        pj=j,
        pk=ke,
    )
