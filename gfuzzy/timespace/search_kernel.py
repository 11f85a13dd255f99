"""The compiled search loop: :func:`gfuzzy.timespace.timespace.sipp` in numba.

The reference search (:func:`gfuzzy.timespace.timespace.sipp`) stays the definition; this module
runs the same A* loop over safe intervals in machine code and must give the same answers
(tests/test_search_kernel.py cross-checks them). What stays in Python:

* the driver of the movers' safety (:class:`gfuzzy.timespace.spacetime.IntervalStore`), asked for
  lazily, node by node, exactly as the reference asks for it; its kernels are compiled too
  (:mod:`gfuzzy.timespace.movers_kernel`) and the loop reads the store's pool of intervals directly;
* the first motions from a start that the margin refuses (:meth:`MoverField.motion_safe`),
  decided before the loop starts;
* the deadline: the loop hands control back every :data:`YIELD_EVERY` expansions.

The loop is a resumable kernel. Before expanding a state it checks that every neighbour's
safe intervals are loaded; if not, it returns the missing nodes *without popping*, the
driver loads them from the store and calls it again, and the kernel re-examines the same
top of the open list. Its state (a binary heap on arrays, an open-addressing table of
``best`` and ``parent``) lives in arrays that survive between calls.

Same order as the reference. The reference's heap holds tuples ``(f, -g, node, interval)``,
all distinct (a state is pushed again only with a strictly earlier arrival, so never twice
with the same ``g``), so its pop order is the lexicographic order of the tuples whatever
the heap's layout; this kernel's heap compares the same four keys in the same order, so
both search in the same order, break ties the same way and return the same answer.

The kernels are decorated with :func:`gfuzzy.timespace.jit.njit`: when ``make warm`` (``python -m
gfuzzy.timespace.precompile``) built them ahead of time they are the precompiled extension's and numba
is never imported; otherwise numba is imported when this module is (the reference path and
``import gfuzzy`` do not need it) and ``cache=True`` keeps its machine code on disk. Where
the package folder is read-only numba falls back to a per-user cache folder;
``NUMBA_CACHE_DIR`` overrides both.
"""

from __future__ import annotations

import math
import time
from bisect import bisect_left

import numpy as np

from ..status import Status
from .jit import njit
from .movers import MoverField
from .spacetime import IntervalStore, SearchResult, SpaceTimeGraph
from .timespace import NO_FIRST_MOTION, exhausted, first_motions, too_short

__all__ = ["sipp_compiled", "warm"]

#: Expansions between two returns to Python (deadline check).
YIELD_EVERY = 4096

# return codes of the kernel
_SOLVED, _EXHAUSTED, _NEED, _YIELD, _ROOM = 0, 1, 2, 3, 4
# counters (ctr)
_HSIZE, _TCOUNT, _EXP, _HIT, _NNEED, _RESULT, _SINCE = range(7)


@njit(cache=True)
def _slot(tk, key):
    """Slot of ``key`` in the open-addressing table (its own, or the empty one to use)."""
    mask = len(tk) - 1
    i = ((key * -7046029254386353131) >> 17) & mask
    while tk[i] != -1 and tk[i] != key:
        i = (i + 1) & mask
    return i


@njit(cache=True)
def _grow_table(tk, tb, tp):
    n = len(tk) * 2
    nk = np.full(n, -1, np.int64)
    nb = np.empty(n, np.int64)
    np_ = np.empty(n, np.int64)
    for i in range(len(tk)):
        if tk[i] != -1:
            s = _slot(nk, tk[i])
            nk[s] = tk[i]
            nb[s] = tb[i]
            np_[s] = tp[i]
    return nk, nb, np_


@njit(cache=True)
def _less(hf, hq, a, b):
    if hf[a] != hf[b]:
        return hf[a] < hf[b]
    if hq[a, 0] != hq[b, 0]:
        return hq[a, 0] < hq[b, 0]
    if hq[a, 1] != hq[b, 1]:
        return hq[a, 1] < hq[b, 1]
    return hq[a, 2] < hq[b, 2]


@njit(cache=True)
def _swap(hf, hq, a, b):
    f = hf[a]
    hf[a] = hf[b]
    hf[b] = f
    for c in range(3):
        x = hq[a, c]
        hq[a, c] = hq[b, c]
        hq[b, c] = x


@njit(cache=True)
def _push(hf, hq, ctr, f, ng, v, j):
    """Push onto the heap, which has room (the loop asks for it before an expansion)."""
    n = ctr[_HSIZE]
    hf[n] = f
    hq[n, 0] = ng
    hq[n, 1] = v
    hq[n, 2] = j
    ctr[_HSIZE] = n + 1
    while n > 0:
        p = (n - 1) >> 1
        if _less(hf, hq, n, p):
            _swap(hf, hq, n, p)
            n = p
        else:
            break


@njit(cache=True)
def _pop(hf, hq, ctr):
    n = ctr[_HSIZE] - 1
    ctr[_HSIZE] = n
    if n == 0:
        return
    _swap(hf, hq, 0, n)
    i = 0
    while True:
        a = 2 * i + 1
        if a >= n:
            break
        b = a + 1
        c = b if (b < n and _less(hf, hq, b, a)) else a
        if _less(hf, hq, c, i):
            _swap(hf, hq, c, i)
            i = c
        else:
            break


@njit(cache=True)
def _set(tk, tb, tp, ctr, key, best, parent):
    """Set a state's arrival and parent; the table has room (at most half full)."""
    s = _slot(tk, key)
    if tk[s] == -1:
        tk[s] = key
        ctr[_TCOUNT] += 1
    tb[s] = best
    tp[s] = parent


@njit(cache=True)
def _get(tk, tb, key, default):
    s = _slot(tk, key)
    return tb[s] if tk[s] == key else default


@njit(cache=True)
def _run(indptr, nbrs, h, wait_ok, goal, goal_hold, H, weight, stride,
         iv_off, iv_cnt, iv_cap, pool_s, pool_e, hf, hq, tk, tb, tp, ctr, need):  # fmt: skip
    """The A* loop of :func:`gfuzzy.timespace.timespace.sipp` until it ends or needs something:
    intervals not loaded yet (``_NEED``), room in the heap or the table (``_ROOM``: at
    most ``ctr[_NNEED]`` states are pushed by the next expansion), a deadline check
    (``_YIELD``). The arrays are never reallocated here (no array returned per push).

    Returns the code.
    """
    big = np.iinfo(np.int64).max
    while ctr[_HSIZE] > 0:
        g = -hq[0, 0]
        u = hq[0, 1]
        ju = hq[0, 2]
        ukey = u * stride + ju
        if _get(tk, tb, ukey, big) < g:
            _pop(hf, hq, ctr)
            continue
        o = iv_off[u] + ju
        end_u = pool_e[o]
        cap_u = iv_cap[u]
        parked = True
        if u == goal and goal_hold > 0:
            parked = end_u >= g + goal_hold
            if not parked and end_u >= cap_u:
                ctr[_HIT] = 1
        if u == goal and parked:
            ctr[_RESULT] = ukey
            return _SOLVED
        lo = g + 1
        hi = end_u + 1 if wait_ok[u] else lo
        if hi > H:
            hi = H
        if lo <= hi:
            # every neighbour's intervals must be loaded before the expansion starts
            nn = 0
            pushes = 0  # at most one push per neighbour's interval
            for e in range(indptr[u], indptr[u + 1]):
                v = nbrs[e]
                if math.isinf(h[v]):
                    continue
                if iv_cnt[v] < 0:
                    need[nn] = v
                    nn += 1
                pushes += iv_cnt[v]
            if nn > 0:
                ctr[_NNEED] = nn
                return _NEED
            if ctr[_HSIZE] + pushes > len(hf) or 2 * (ctr[_TCOUNT] + pushes) > len(tk):
                ctr[_NNEED] = pushes
                return _ROOM
        if ctr[_SINCE] >= YIELD_EVERY:
            ctr[_SINCE] = 0
            return _YIELD
        _pop(hf, hq, ctr)
        ctr[_EXP] += 1
        ctr[_SINCE] += 1
        if end_u >= cap_u:  # the interval was cut by the horizon, not by a mover
            ctr[_HIT] = 1
        if lo > hi:
            continue
        for e in range(indptr[u], indptr[u + 1]):
            v = nbrs[e]
            hv = h[v]
            if math.isinf(hv):
                continue
            off = iv_off[v]
            n_iv = iv_cnt[v]
            # bisect_left(ends, lo)
            a, b = 0, n_iv
            while a < b:
                mid = (a + b) >> 1
                if pool_e[off + mid] < lo:
                    a = mid + 1
                else:
                    b = mid
            j = a
            while j < n_iv and pool_s[off + j] <= hi:
                s = pool_s[off + j]
                arr = lo if s < lo else s
                key = v * stride + j
                if arr < _get(tk, tb, key, big):
                    _set(tk, tb, tp, ctr, key, arr, ukey)
                    _push(hf, hq, ctr, arr + weight * hv, -arr, v, j)
                j += 1
    return _EXHAUSTED


@njit(cache=True)
def _path(tk, tb, tp, key, stride):
    nodes = []
    steps = []
    while key >= 0:
        s = _slot(tk, key)
        nodes.append(key // stride)
        steps.append(tb[s])
        key = tp[s]
    return np.array(nodes[::-1], dtype=np.int64), np.array(steps[::-1], dtype=np.int64)


def _room(hf, hq, tk, tb, tp, ctr, pushes: int):
    """The heap and the table grown (doubled, the table rehashed) until ``pushes`` more
    states fit: the heap holds them, the table stays at most half full."""
    size = len(hf)
    while ctr[_HSIZE] + pushes > size:
        size *= 2
    if size > len(hf):
        nf, nq = np.empty(size, np.float64), np.empty((size, 3), np.int64)
        n = int(ctr[_HSIZE])
        nf[:n], nq[:n] = hf[:n], hq[:n]
        hf, hq = nf, nq
    while 2 * (ctr[_TCOUNT] + pushes) > len(tk):
        tk, tb, tp = _grow_table(tk, tb, tp)
    return hf, hq, tk, tb, tp


def sipp_compiled(
    graph,
    field_,
    start: int,
    goal: int,
    deadline: float = math.inf,
    start_step: int = 0,
    weight: float = 1.0,
    store=None,
    goal_hold: int = 0,
    clock=time.perf_counter,
):
    """:func:`gfuzzy.timespace.timespace.sipp` with the loop compiled; same arguments, same answer."""
    H = field_.steps
    store = store or IntervalStore(graph)
    store.set_horizon(field_, pool=True)  # the kernel reads the store's pool of arrays
    ivals = store.get
    h = np.ascontiguousarray(graph.heuristic, dtype=np.float64)
    n = len(h)
    if not math.isfinite(h[start]):
        return SearchResult(Status.NO_PATH, message="the goal is not reachable on the roadmap")
    if start_step + h[start] > H:
        return too_short()
    indptr = np.ascontiguousarray(graph.indptr, dtype=np.int64)
    nbrs = np.ascontiguousarray(graph.neighbors, dtype=np.int64)
    wait_ok = np.ones(n, np.bool_) if graph.can_wait is None else np.ascontiguousarray(graph.can_wait, np.bool_)
    stride = H + 2
    load = store.ensure

    hf = np.empty(1024, np.float64)
    hq = np.empty((1024, 3), np.int64)
    tk = np.full(4096, -1, np.int64)
    tb = np.empty(4096, np.int64)
    tp = np.empty(4096, np.int64)
    ctr = np.zeros(7, np.int64)
    need = np.empty(max(1, int(np.diff(indptr).max(initial=0))), np.int64)

    load(start)
    s_starts, s_ends, _ = ivals(start)
    j0 = bisect_left(s_ends, start_step)
    if j0 < len(s_starts) and s_starts[j0] <= start_step:
        key0 = start * stride + j0
        _set(tk, tb, tp, ctr, key0, start_step, -1)
        _push(hf, hq, ctr, start_step + weight * h[start], -start_step, start, j0)
    else:
        # the reference's exact first motions, in Python (rare: a start beside a mover)
        key0 = start * stride + stride - 1
        _set(tk, tb, tp, ctr, key0, start_step, -1)
        pushed = False
        neighbours = nbrs[indptr[start] : indptr[start + 1]].tolist()
        for v, j, arrive in first_motions(graph, field_, start, start_step, ivals, neighbours, bool(wait_ok[start])):
            key = v * stride + j
            if arrive < _get(tk, tb, key, np.iinfo(np.int64).max):
                load(v)
                hf, hq, tk, tb, tp = _room(hf, hq, tk, tb, tp, ctr, 1)
                _set(tk, tb, tp, ctr, key, arrive, key0)
                _push(hf, hq, ctr, arrive + weight * h[v], -arrive, v, j)
                pushed = True
        if not pushed:
            return SearchResult(Status.NO_PATH, message=NO_FIRST_MOTION)
    while True:
        code = _run(
            indptr, nbrs, h, wait_ok, goal, goal_hold, H, float(weight), stride,
            store.off, store.ready, store.cap, store.s, store.e, hf, hq, tk, tb, tp, ctr, need,
        )  # fmt: skip
        if code == _ROOM:
            hf, hq, tk, tb, tp = _room(hf, hq, tk, tb, tp, ctr, int(ctr[_NNEED]))
            continue
        if code == _NEED:  # the safety of a batch can take long among many movers: the clock too
            for v in need[: ctr[_NNEED]].tolist():
                load(v)
        if code in (_NEED, _YIELD):
            if clock() > deadline:
                return SearchResult(
                    Status.TIMEOUT,
                    message="planning time budget exhausted",
                    expansions=int(ctr[_EXP]),
                    states=int(ctr[_TCOUNT]),
                )
            continue
        break
    expansions, states, hit = int(ctr[_EXP]), int(ctr[_TCOUNT]), bool(ctr[_HIT])
    if code == _SOLVED:
        nodes, steps = _path(tk, tb, tp, int(ctr[_RESULT]), stride)
        return SearchResult(Status.SOLVED, nodes.tolist(), steps.tolist(), expansions=expansions, states=states)
    return exhausted(expansions, states, hit)


def warm() -> None:
    """Compile (or load from the cache) every kernel: a search among movers on a small
    graph, for a disc and a box robot, with a horizon that grows once (the pool's merge)."""
    from ..scene.scene import (
        parse_scene,  # only for warming: the scene parser is not needed otherwise
    )

    for robot, poses in (({"disc": 0.2, "vmax": 1.0}, [[0.5, 1.0], [1.0, 1.0], [1.5, 1.0]]),
                         ({"box": [0.4, 0.2], "vmax": 1.0}, [[0.5, 1.0, 0.0], [1.0, 1.0, 0.2], [1.5, 1.0, 0.3]])):  # fmt: skip
        scene = parse_scene(
            {
                "version": 1,
                "name": "warm",
                "bounds": [0, 0, 2, 2],
                "robot": robot,
                "movers": [  # a crosses the middle node, b passes by: the start is free at t0
                    {"name": "a", "disc": 0.2, "speed": 1.0, "path": [[1, 1.8], [1, 0.2]], "mode": "bounce"},
                    {"name": "b", "box": [0.3, 0.3], "speed": 1.0, "path": [[0.2, 1.8], [1.8, 1.8]], "mode": "loop"},
                ],
            }
        )
        graph = SpaceTimeGraph(
            poses=np.array(poses, dtype=float),
            indptr=np.array([0, 1, 3, 4]),
            neighbors=np.array([1, 0, 2, 1]),
            heuristic=np.array([2.0, 1.0, 0.0]),
        )
        store = IntervalStore(graph)
        for steps in (10, 40):  # the search itself, then on the same store a longer horizon
            field_ = MoverField(scene, 0.0, 0.1, steps, 1.0)
            field_.compiled = True
            res = sipp_compiled(graph, field_, 0, 2, store=store)
        if res.status != Status.SOLVED:  # the kernels would not all have run
            raise RuntimeError(f"warm-up search: {res.status.value} {res.message}")
        field_.unsafe_pairs(graph.poses, np.array([0, 3]), np.array([0]), np.array([20]))
    # what the driver calls itself only on rarer paths: a growing table, a start beside a mover
    tk, tb, tp = np.full(4, -1, np.int64), np.empty(4, np.int64), np.empty(4, np.int64)
    ctr = np.zeros(7, np.int64)
    _room(np.empty(1), np.empty((1, 3), np.int64), tk, tb, tp, ctr, 4)
    _get(tk, tb, 0, np.iinfo(np.int64).max)


if __name__ == "__main__":
    warm()
