"""Roadmap-time search: A*-ordered safe-interval search over a graph and discretized time.

After van den Berg & Overmars, "Roadmap-based motion planning in dynamic environments"
(IROS 2004; IEEE T-RO 21(5), 2005): time is discretized at ``dt``; every roadmap edge is
split into ``k = ceil(length / (vmax * dt))`` equal steps, so that one step of the search
moves the robot to the next point of an edge at a speed of at most vmax; the robot may
wait at any of these points (on vertices and on edges). Consecutive waiting steps are
merged into *safe intervals* (Phillips & Likhachev, "SIPP", ICRA 2011), so a long wait is
one state, not one per step. States are expanded in A* order of arrival step plus the
admissible heuristic (static distance to the goal) / (vmax * dt).

Continuous-time safety (docs/formats.md section 3). A point of the graph is *safe at step n*
when, for every mover present at some time in ``[t_n - dt/2, t_n + dt/2]``, the distance
between the robot at that point and the mover at ``clamp(t_n)`` is at least
``(vmax + v_mover) * dt / 2``. During the first half of a step the robot stays within
``vmax * dt / 2`` of the point it left (every point of its body does, in the contract's
metric), during the second half within that of the point it reaches, and the mover within
``v_mover * dt / 2`` of its sampled position; so a sequence of safe (point, step) pairs is
collision-free at every instant, not only at the steps.

Clearance. With the robot's ``mover_clearance`` c the margin is
``(vmax + v_mover) * dt / 2 + c``: the distance shrinks by at most the first term within the
half step, so it stays at least c at every instant. The margin is data
(:attr:`MoverField.margin`, one value per mover and step), never a special case.

The first step. The margin at the start's step also covers the half step *before* the
departure, which the robot never lives through, and assumes nothing about where the robot
goes; near a mover it refuses starts that are clear. When the start is not safe at its
step, :func:`sipp` decides each first motion (waiting, or one step to a neighbour) exactly
instead: :meth:`MoverField.motion_safe` bounds the distance over ``[t_s, t_s + dt]`` by the
same Lipschitz argument as the independent check, bisecting until every sub-interval is
proven clear. The arrival point is then safe at the next step as usual, so the whole
answer keeps the guarantee.

Parking. With ``goal_hold`` K the goal is accepted only in a safe interval that lasts at
least K steps after the arrival: the robot stands still there, each of those steps covers
half a step on either side, so the goal pose is safe from the arrival until at least
``K * dt`` after it.
"""

from __future__ import annotations

import heapq
import logging
import math
import time
from bisect import bisect_left
from collections.abc import Callable

import numpy as np

from ..status import Status
from .movers import MoverField
from .spacetime import IntervalStore, SearchResult, SpaceTimeGraph

__all__ = ["MoverField", "SpaceTimeGraph", "SearchResult", "IntervalStore", "sipp", "timed_rows", "first_motions", "exhausted"]

log = logging.getLogger(__name__)

#: Why a search from a start the margin refuses found nothing (both backends).
NO_FIRST_MOTION = (
    "no first motion from the start keeps clear of the movers (the start is too close to a mover at t0)"
)


def sipp(
    graph: SpaceTimeGraph,
    field_: MoverField,
    start: int,
    goal: int,
    deadline: float = math.inf,
    start_step: int = 0,
    weight: float = 1.0,
    store: IntervalStore | None = None,
    goal_hold: int = 0,
    clock: Callable[[], float] = time.perf_counter,
) -> SearchResult:
    """Earliest-arrival search from ``start`` (at ``start_step``) to ``goal``.

    With ``weight`` w > 1 the order is arrival + w * heuristic (weighted A*): far fewer
    expansions, and the arrival is at most w times the earliest. ``store`` keeps the
    safety computed by an earlier search on the same graph with a shorter horizon.
    With ``goal_hold`` K > 0 the goal counts as reached only where it stays safe for K
    steps after the arrival (the robot parks there); the search arrives later if it must.
    When the start is not safe at ``start_step`` its first motions are decided exactly
    (:meth:`MoverField.motion_safe`). The search gives up at ``deadline`` on ``clock``
    (wall-clock by default; the navigator may pass a CPU-time clock).

    Returns the arrival-optimal sequence of (node, arrival step) on the time grid: the
    robot waits at a node from its arrival until one step before the next arrival.
    """
    H = field_.steps
    h = graph.heuristic
    store = store or IntervalStore(graph)
    store.set_horizon(field_)
    ivals = store.get
    intervals = store._served

    # plain Python containers in the hot loop: numpy scalar indexing costs ~10x more
    indptr = graph.indptr.tolist()
    nbrs = graph.neighbors.tolist()
    hl = h.tolist()
    wait_ok = None if graph.can_wait is None else graph.can_wait.tolist()
    inf = math.inf
    if not math.isfinite(hl[start]):
        return SearchResult(Status.NO_PATH, message="the goal is not reachable on the roadmap")
    if start_step + hl[start] > H:
        return too_short()
    # a state (node, interval index) is the integer node * stride + index
    stride = H + 2
    heappop, heappush = heapq.heappop, heapq.heappush
    best, parent, openq = _open(graph, field_, start, start_step, ivals, nbrs[indptr[start] : indptr[start + 1]],
                                wait_ok is None or wait_ok[start], stride, weight)  # fmt: skip
    if not openq:
        return SearchResult(Status.NO_PATH, message=NO_FIRST_MOTION)
    expansions = 0
    horizon_hit = False
    while openq:
        _, neg_g, u, ju = heappop(openq)
        g = -neg_g
        ukey = u * stride + ju
        if best.get(ukey, inf) < g:
            continue
        parked = True
        if u == goal and goal_hold > 0:
            _, g_ends, g_cap = intervals[u]
            parked = g_ends[ju] >= g + goal_hold
            if not parked and g_ends[ju] >= g_cap:  # cut by the horizon, not by a mover
                horizon_hit = True
        if u == goal and parked:
            nodes, steps = _walk_back(ukey, best, parent, stride)
            return SearchResult(Status.SOLVED, nodes, steps, expansions=expansions, states=len(best))
        expansions += 1
        if expansions % 512 == 0 and clock() > deadline:
            return SearchResult(
                Status.TIMEOUT, message="planning time budget exhausted", expansions=expansions, states=len(best)
            )
        _, u_ends, u_cap = intervals[u]
        end_u = u_ends[ju]
        if end_u >= u_cap:  # the interval was cut by the horizon, not by a mover
            horizon_hit = True
        lo = g + 1
        hi = end_u + 1 if (wait_ok is None or wait_ok[u]) else lo
        if hi > H:
            hi = H
        if lo > hi:
            continue
        for v in nbrs[indptr[u] : indptr[u + 1]]:
            hv = hl[v]
            if hv == inf:
                continue
            iv = intervals.get(v)
            starts, ends, _ = iv if iv is not None else ivals(v)
            j = bisect_left(ends, lo)
            n_iv = len(starts)
            while j < n_iv and starts[j] <= hi:
                arr = lo if starts[j] < lo else starts[j]
                key = v * stride + j
                if arr < best.get(key, inf):
                    best[key] = arr
                    parent[key] = ukey
                    heappush(openq, (arr + weight * hv, -arr, v, j))
                j += 1
    return exhausted(expansions, len(best), horizon_hit)


def _open(graph, field_, start, start_step, ivals, neighbours, can_wait, stride, weight):
    """(best, parent, open list) of :func:`sipp` before its first expansion.

    The start's own state when it is safe at ``start_step``; otherwise the first motions
    decided exactly (an empty open list: none is clear).
    """
    hl = graph.heuristic
    s_starts, s_ends, _ = ivals(start)
    j0 = bisect_left(s_ends, start_step)
    if j0 < len(s_starts) and s_starts[j0] <= start_step:
        key0 = start * stride + j0
        return {key0: start_step}, {key0: -1}, [(start_step + weight * float(hl[start]), -start_step, start, j0)]
    # the margin refuses the start: decide each first motion exactly instead (the
    # robot only lives from the start's step on, and only along the motion it takes)
    key0 = start * stride + stride - 1  # an index no interval has (at most H / 2 + 1)
    best = {key0: start_step}
    parent = {key0: -1}
    openq: list = []
    for v, j, arrive in first_motions(graph, field_, start, start_step, ivals, neighbours, can_wait):
        key = v * stride + j
        if arrive < best.get(key, math.inf):
            best[key] = arrive
            parent[key] = key0
            heapq.heappush(openq, (arrive + weight * float(hl[v]), -arrive, v, j))
    return best, parent, openq


def too_short() -> SearchResult:
    """The NO_PATH answer when the horizon is shorter than the static distance to the goal
    (both backends): the horizon, not the movers, cut the search."""
    return SearchResult(Status.NO_PATH, message="no safe trajectory within the planning horizon", horizon_hit=True)


def exhausted(expansions: int, states: int, horizon_hit: bool) -> SearchResult:
    """The NO_PATH answer of a search whose open list ran empty (both backends)."""
    msg = (
        "no safe trajectory within the planning horizon"
        if horizon_hit
        else "the reachable space-time is exhausted: no safe trajectory exists on this graph"
    )
    return SearchResult(Status.NO_PATH, message=msg, expansions=expansions, states=states, horizon_hit=horizon_hit)


#: Steps a start the margin refuses may be waited at, each decided exactly, before the
#: robot must have left it or the margin must accept it.
FIRST_WAIT_STEPS = 40


def first_motions(graph: SpaceTimeGraph, field_: MoverField, start: int, start_step: int, ivals, neighbours,
                  can_wait: bool):  # fmt: skip
    """The first motions from a start the margin refuses, decided exactly (both backends).

    Yields ``(node, interval index, arrival step)`` for each motion that waits at the start
    for ``k`` steps (0 <= k < :data:`FIRST_WAIT_STEPS`, each waiting step proven clear
    by :meth:`MoverField.motion_safe`, only when ``can_wait``) and then moves in one step to
    a neighbour (in ``neighbours`` order) proven clear over that step, arriving in a safe
    interval; and the start itself at the first step the margin accepts it, if waiting
    there stays clear until then. A mover touching the start and walking away is so left
    behind by waiting, which one exact step alone could not prove. A generator, so that a
    caller may act between two motions as the loop it replaces did.
    """
    h = graph.heuristic
    p0 = graph.poses[start]
    last = min(field_.steps, start_step + (FIRST_WAIT_STEPS if can_wait else 1))
    for depart in range(start_step, last):
        arrive = depart + 1
        for v in neighbours:
            if h[v] == math.inf:
                continue
            starts, ends, _ = ivals(v)
            j = bisect_left(ends, arrive)
            if j >= len(starts) or starts[j] > arrive:
                continue
            if not field_.motion_safe(p0, graph.poses[v], depart):
                continue
            yield v, j, arrive
        if not can_wait or not field_.motion_safe(p0, p0, depart):
            return  # the robot cannot stay at the start over this step
        starts, ends, _ = ivals(start)
        j = bisect_left(ends, arrive)
        if j < len(starts) and starts[j] <= arrive:  # the margin accepts the start again
            yield start, j, arrive
            return


def _walk_back(key: int, best: dict, parent: dict, stride: int) -> tuple[list, list]:
    """(nodes, arrival steps) from the start to the state ``key``, following ``parent``."""
    nodes, steps = [], []
    while key >= 0:
        nodes.append(key // stride)
        steps.append(best[key])
        key = parent[key]
    return nodes[::-1], steps[::-1]


def timed_rows(nodes, steps, poses, t0: float, dt: float, between=None):
    """Trajectory rows of a search's answer.

    The robot waits at a node from its arrival until one step before the next arrival,
    then moves in one step; ``between(a, b)`` may add rows inside the step from a to b as
    (fraction of the step, pose).

    Returns
    -------
    rows : (r, d + 1) float
        ``[t, pose...]``; t strictly increasing.
    waits : list of int
        The nodes where the answer waits.
    """
    if between is None:
        return _timed_rows_plain(nodes, steps, poses, t0, dt)
    rows = [(t0 + steps[0] * dt, poses[nodes[0]])]
    waits = []
    for k in range(1, len(nodes)):
        a, b = nodes[k - 1], nodes[k]
        depart = steps[k] - 1
        if depart > steps[k - 1]:
            rows.append((t0 + depart * dt, poses[a]))
            waits.append(a)
        if between is not None:
            for frac, pose in between(a, b):
                rows.append((t0 + (depart + frac) * dt, pose))
        rows.append((t0 + steps[k] * dt, poses[b]))
    return np.array([[t, *p] for t, p in rows], dtype=float), waits


def _timed_rows_plain(nodes, steps, poses, t0: float, dt: float):
    """:func:`timed_rows` without rows inside the steps, vectorised (the same numbers:
    each time is ``t0 + step * dt`` in float64, as the loop computes it)."""
    nodes = np.asarray(nodes, dtype=np.int64)
    steps = np.asarray(steps, dtype=np.int64)
    depart = steps[1:] - 1
    wait = depart > steps[:-1]
    times = np.empty(2 * len(steps) - 1)
    ids = np.empty(len(times), dtype=np.int64)
    keep = np.ones(len(times), dtype=bool)
    times[0], ids[0] = t0 + steps[0] * dt, nodes[0]
    times[1::2], ids[1::2], keep[1::2] = t0 + depart * dt, nodes[:-1], wait  # waiting rows
    times[2::2], ids[2::2] = t0 + steps[1:] * dt, nodes[1:]  # arrivals
    rows = np.column_stack([times[keep], np.asarray(poses)[ids[keep]]])
    return rows, nodes[:-1][wait].tolist()
