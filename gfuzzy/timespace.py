"""Roadmap-time search: A*-ordered safe-interval search over a graph and discretized time.

After van den Berg & Overmars, "Roadmap-based motion planning in dynamic environments"
(IROS 2004; IEEE T-RO 21(5), 2005): time is discretized at ``dt``; every roadmap edge is
split into ``k = ceil(length / (vmax * dt))`` equal steps, so that one step of the search
moves the robot to the next point of an edge at a speed of at most vmax; the robot may
wait at any of these points (on vertices and on edges). Consecutive waiting steps are
merged into *safe intervals* (Phillips & Likhachev, "SIPP", ICRA 2011), so a long wait is
one state, not one per step. States are expanded in A* order of arrival step plus the
admissible heuristic (static distance to the goal) / (vmax * dt).

Continuous-time safety (CONTRACT.md section 3). A point of the graph is *safe at step n*
when, for every mover present at some time in ``[t_n - dt/2, t_n + dt/2]``, the distance
between the robot at that point and the mover at ``clamp(t_n)`` is at least
``(vmax + v_mover) * dt / 2``. During the first half of a step the robot stays within
``vmax * dt / 2`` of the point it left (every point of its body does, in the contract's
metric), during the second half within that of the point it reaches, and the mover within
``v_mover * dt / 2`` of its sampled position; so a sequence of safe (point, step) pairs is
collision-free at every instant, not only at the steps.
"""

from __future__ import annotations

import heapq
import logging
import math
import time
from bisect import bisect_left
from dataclasses import dataclass, field

import numpy as np

from .geometry import mover_distance
from .scene import Robot, Scene
from .typing import BoolArray, FloatArray, IntArray

__all__ = ["MoverField", "SpaceTimeGraph", "SearchResult", "sipp"]

log = logging.getLogger(__name__)

#: Steps per chunk of the movers' broad phase.
CHUNK = 8


class MoverField:
    """The movers sampled on the time grid ``t_n = t0 + n * dt``, ``n = 0..steps``.

    Parameters
    ----------
    scene : Scene
    t0, dt : float
    steps : int
        Horizon in steps.
    vrobot : float
        Bound on the speed of any point of the robot (vmax).

    Notes
    -----
    Memory is about ``32 * movers * steps`` bytes.
    """

    def __init__(self, scene: Scene, t0: float, dt: float, steps: int, vrobot: float):
        self.robot: Robot = scene.robot
        self.movers = scene.movers
        self.t0, self.dt, self.steps = float(t0), float(dt), int(steps)
        n = self.steps + 1
        m = len(self.movers)
        times = self.t0 + self.dt * np.arange(n)
        self.times = times
        self.xy = np.empty((m, n, 2))
        self.present = np.zeros((m, n), dtype=bool)
        self.margin = np.empty((m, n))
        half = 0.5 * self.dt
        for i, mv in enumerate(self.movers):
            ta, tb = mv.time_range
            tc = np.clip(times, ta, tb)
            self.xy[i], _ = mv.state(tc)
            self.present[i] = (times + half >= ta) & (times - half <= tb)
            self.margin[i] = (vrobot + _local_speed(mv, times, half)) * half
        # broad phase: per mover and chunk, the box of reference points inflated by reach
        nc = (n + CHUNK - 1) // CHUNK
        pad = nc * CHUNK - n
        reach = (
            np.array([mv.extent for mv in self.movers]).reshape(m, 1)
            + self.robot.circumradius
            + self.margin.max(axis=1, initial=0.0, keepdims=True)
        )
        x = np.pad(self.xy[..., 0], ((0, 0), (0, pad)), mode="edge").reshape(m, nc, CHUNK)
        y = np.pad(self.xy[..., 1], ((0, 0), (0, pad)), mode="edge").reshape(m, nc, CHUNK)
        pres = np.pad(self.present, ((0, 0), (0, pad))).reshape(m, nc, CHUNK)
        big = np.inf
        self.bbox = np.stack(
            [
                np.where(pres, x, big).min(-1) - reach,
                np.where(pres, y, big).min(-1) - reach,
                np.where(pres, x, -big).max(-1) + reach,
                np.where(pres, y, -big).max(-1) + reach,
            ],
            axis=-1,
        )  # (m, nc, 4); empty (inf/-inf) where absent
        self.nc = nc
        self.evaluations = 0

    def unsafe(self, poses: FloatArray, lo: int = 0, hi: int | None = None) -> BoolArray:
        """Steps at which the robot at each of ``poses`` is not safe.

        Parameters
        ----------
        poses : (k, d) float
            Usually the points of one roadmap edge: they share the broad phase.
        lo, hi : int
            Only steps ``lo..hi`` are examined; the others are reported unsafe.

        Returns
        -------
        (k, steps + 1) bool
        """
        poses = np.atleast_2d(np.asarray(poses, dtype=float))
        hi = self.steps if hi is None else min(hi, self.steps)
        out = np.ones((len(poses), self.steps + 1), dtype=bool)
        if lo > hi:
            return out
        out[:, lo : hi + 1] = False
        if not self.movers:
            return out
        pmin = poses[:, :2].min(axis=0)
        pmax = poses[:, :2].max(axis=0)
        bb = self.bbox
        c0, c1 = lo // CHUNK, hi // CHUNK + 1
        bb = bb[:, c0:c1]
        near = (bb[..., 0] <= pmax[0]) & (pmin[0] <= bb[..., 2]) & (bb[..., 1] <= pmax[1]) & (pmin[1] <= bb[..., 3])
        ms, cs = np.nonzero(near)
        cs = cs + c0
        if ms.size == 0:
            return out
        grid = np.arange(CHUNK)
        for m in np.unique(ms):
            chunks = cs[ms == m]
            steps = (chunks[:, None] * CHUNK + grid).ravel()
            steps = steps[(steps >= lo) & (steps <= hi)]
            steps = steps[self.present[m, steps]]
            if steps.size == 0:
                continue
            mv = self.movers[m]
            d = mover_distance(
                self.robot, poses[:, None, :], mv.shape, mv.radius, mv.size, self.xy[m, steps][None]
            )
            self.evaluations += d.size
            bad = d < self.margin[m, steps]
            out[:, steps] |= bad
        return out

    def collides_at(self, pose: FloatArray, step: int) -> str | None:
        """Name of a mover overlapping the robot at ``pose`` exactly at step ``step``, if any."""
        t = self.t0 + step * self.dt
        for mv in self.movers:
            xy, present = mv.state(np.array([t]))
            if present[0] and mover_distance(self.robot, np.asarray(pose, float), mv.shape, mv.radius, mv.size, xy[0]) < 0:
                return mv.name
        return None


def _local_speed(mv, times: FloatArray, half: float) -> FloatArray:
    """Largest speed of a mover within ``[t - half, t + half]`` for each t."""
    if mv.trajectory is None:
        return np.full(times.shape, mv.speed)
    tr = mv.trajectory
    if len(tr) < 2:
        return np.zeros(times.shape)
    seg_v = np.hypot(*np.diff(tr[:, 1:], axis=0).T) / np.diff(tr[:, 0])
    last = len(seg_v) - 1
    i0 = np.clip(np.searchsorted(tr[:, 0], times - half, side="right") - 1, 0, last)
    i1 = np.clip(np.searchsorted(tr[:, 0], times + half, side="left") - 1, 0, last)
    i1 = np.maximum(i1, i0)
    span = int((i1 - i0).max(initial=0))
    v = seg_v[i0]
    for k in range(1, span + 1):
        v = np.maximum(v, seg_v[np.minimum(i0 + k, i1)])
    return v


@dataclass
class SpaceTimeGraph:
    """A graph whose every edge takes exactly one time step.

    Attributes
    ----------
    poses : (N, d) float
    indptr : (N+1,) int
    neighbors : (M,) int
        CSR adjacency: the successors of node i are ``neighbors[indptr[i]:indptr[i+1]]``.
    heuristic : (N,) float
        Lower bound on the number of steps to the goal (inf: goal unreachable).
    can_wait : (N,) bool or None
        Where the robot may wait (None: everywhere).
    groups : (G+1,) int or None
        Nodes ``groups[j] .. groups[j+1]-1`` lie on one roadmap edge; their safe intervals
        are computed together. Nodes below ``groups[0]`` are computed one by one.
    from_start : (N,) float or None
        Lower bound on the steps from the start to each node. With the heuristic it
        bounds the useful times of a node to ``[from_start, horizon - heuristic]``: the
        robot cannot be there earlier, nor reach the goal in time from there later, so
        safety is only computed inside that window.
    """

    poses: FloatArray
    indptr: IntArray
    neighbors: IntArray
    heuristic: FloatArray
    can_wait: BoolArray | None = None
    groups: IntArray | None = None
    from_start: FloatArray | None = None


@dataclass
class SearchResult:
    """Outcome of :func:`sipp`: ``status`` in {"solved", "no_path", "timeout"}."""

    status: str
    nodes: list = field(default_factory=list)  # node ids, one per arrival
    steps: list = field(default_factory=list)  # arrival steps
    message: str = ""
    expansions: int = 0
    states: int = 0
    horizon_hit: bool = False


def sipp(
    graph: SpaceTimeGraph,
    field_: MoverField,
    start: int,
    goal: int,
    deadline: float = math.inf,
    start_step: int = 0,
) -> SearchResult:
    """Earliest-arrival search from ``start`` (at ``start_step``) to ``goal``.

    Returns the arrival-optimal sequence of (node, arrival step) on the time grid: the
    robot waits at a node from its arrival until one step before the next arrival.
    """
    intervals: dict[int, tuple[list, list]] = {}
    H = field_.steps
    h = graph.heuristic
    groups = graph.groups
    first = int(groups[0]) if groups is not None else len(graph.poses)

    def ivals(node: int):
        iv = intervals.get(node)
        if iv is not None:
            return iv
        if node < first:
            ids = np.array([node])
        else:
            j = int(np.searchsorted(groups, node, side="right")) - 1
            ids = np.arange(groups[j], groups[j + 1])
        if graph.from_start is not None:
            lo = max(0, int(math.floor(graph.from_start[ids].min() + 1e-9)))
            hi = H - int(math.floor(h[ids].min() + 1e-9))
        else:
            lo, hi = 0, H
        safe = ~field_.unsafe(graph.poses[ids], lo, hi)
        pad = np.zeros((len(ids), 1), dtype=np.int8)
        d = np.diff(np.concatenate([pad, safe.view(np.int8), pad], axis=1), axis=1)
        rs, cs = np.nonzero(d == 1)
        re, ce = np.nonzero(d == -1)
        bounds_s = np.searchsorted(rs, np.arange(len(ids) + 1))
        bounds_e = np.searchsorted(re, np.arange(len(ids) + 1))
        for k, nid in enumerate(ids.tolist()):
            intervals[nid] = (
                cs[bounds_s[k] : bounds_s[k + 1]].tolist(),
                (ce[bounds_e[k] : bounds_e[k + 1]] - 1).tolist(),
            )
        return intervals[node]

    indptr, nbrs = graph.indptr, graph.neighbors
    can_wait = graph.can_wait
    s_starts, s_ends = ivals(start)
    j0 = bisect_left(s_ends, start_step)
    if j0 >= len(s_starts) or s_starts[j0] > start_step:
        return SearchResult("no_path", message="the start is not safe from the movers at t0")
    if not math.isfinite(h[start]):
        return SearchResult("no_path", message="the goal is not reachable on the roadmap")
    best = {(start, j0): start_step}
    parent: dict = {(start, j0): None}
    tie = 0
    openq = [(start_step + h[start], -start_step, tie, start, j0)]
    expansions = 0
    horizon_hit = False
    while openq:
        f, neg_g, _, u, ju = heapq.heappop(openq)
        g = -neg_g
        if best.get((u, ju), math.inf) < g:
            continue
        if u == goal:
            nodes, steps = [], []
            key = (u, ju)
            while key is not None:
                nodes.append(key[0])
                steps.append(best[key])
                key = parent[key]
            return SearchResult(
                "solved", nodes[::-1], steps[::-1], expansions=expansions, states=len(best)
            )
        expansions += 1
        if expansions % 512 == 0 and time.perf_counter() > deadline:
            return SearchResult(
                "timeout", message="planning time budget exhausted", expansions=expansions, states=len(best)
            )
        end_u = intervals[u][1][ju]
        lo = g + 1
        hi = end_u + 1 if (can_wait is None or can_wait[u]) else lo
        if hi > H:
            horizon_hit = True
            hi = H
        if lo > hi:
            continue
        for k in range(indptr[u], indptr[u + 1]):
            v = int(nbrs[k])
            hv = h[v]
            if hv == math.inf:
                continue
            starts, ends = ivals(v)
            j = bisect_left(ends, lo)
            while j < len(starts) and starts[j] <= hi:
                arr = lo if starts[j] < lo else starts[j]
                key = (v, j)
                if arr < best.get(key, math.inf):
                    best[key] = arr
                    parent[key] = (u, ju)
                    tie += 1
                    heapq.heappush(openq, (arr + hv, -arr, tie, v, j))
                j += 1
    msg = (
        "no safe trajectory within the planning horizon"
        if horizon_hit
        else "the reachable space-time is exhausted: no safe trajectory exists on this graph"
    )
    return SearchResult("no_path", message=msg, expansions=expansions, states=len(best), horizon_hit=horizon_hit)
