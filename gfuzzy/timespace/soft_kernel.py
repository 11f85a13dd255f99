"""A time-space search whose cost counts the steps spent in soft zones (issue 19).

:func:`gfuzzy.timespace.timespace.sipp` forbids every (point, step) its field makes unsafe.
:func:`soft_search` keeps that for a *hard* field (people's discs plus the buffer) and only
prices a second, *soft* one (their personal space, the ghosts of their ways): it
minimises ``arrival step + penalty * (steps in a soft zone)`` (one or two soft fields, each
with its own penalty, added where both are unsafe) in A* order over the
time-expanded graph, one state per (node, step), each keeping its least cost. Waiting is
a move to the same node (where the node may wait), so a wait inside someone's way costs
as much per step as walking through it. The heuristic (static steps to the goal) stays
admissible: a soft step costs at least as much as a free one.

Both fields' safe intervals come from their own :class:`~gfuzzy.timespace.spacetime.IntervalStore`
(pool storage, lazily, as the compiled search asks them); the soft field must be at least
as cautious as the hard one (every soft-safe (point, step) hard-safe), as the navigator's
are (the same people, more inflation, plus ghosts). The loop is a resumable kernel with
the protocol of :mod:`gfuzzy.timespace.search_kernel` (it returns the nodes it needs,
the driver loads them, it resumes on the same top of the open list).

Its open-addressing table and heap are its own, on purpose, though they follow the
search kernel's: the heap orders other entries (a cost and a g column; the later step
first at equal cost), the table holds a float cost, and the search kernel's functions
cannot be called from here. When the precompiled extension is loaded (:mod:`.jit`) they are
Python stand-ins, not numba dispatchers, so nopython code here cannot call them ("Untyped
global name '_slot'"); and numba's cache does not see a change in another file, so this
module's cached machine code would keep an edited function's old body while the search
kernel's own code took the new one.
"""

from __future__ import annotations

import math
import time

import numpy as np

from ..status import Status
from .jit import njit
from .movers import MoverField
from .spacetime import IntervalStore, SearchResult
from .timespace import NO_FIRST_MOTION, exhausted, first_motions, too_short

__all__ = ["soft_search"]

_SOLVED, _EXHAUSTED, _NEED, _YIELD, _ROOM = 0, 1, 2, 3, 4
_HSIZE, _TCOUNT, _EXP, _HIT, _NNEED, _RESULT, _SINCE = range(7)
#: Expansions between two returns to Python (deadline check), as the search kernel's.
YIELD_EVERY = 4096


@njit(lazy=True, cache=True)
def _slot(tk, key):
    mask = len(tk) - 1
    i = ((key * -7046029254386353131) >> 17) & mask
    while tk[i] != -1 and tk[i] != key:
        i = (i + 1) & mask
    return i


@njit(lazy=True, cache=True)
def _grow_table(tk, tb, tp):
    """The table doubled and rehashed."""
    n = len(tk) * 2
    nk = np.full(n, -1, np.int64)
    nb = np.empty(n, np.float64)
    np_ = np.empty(n, np.int64)
    for i in range(len(tk)):
        if tk[i] != -1:
            s = _slot(nk, tk[i])
            nk[s] = tk[i]
            nb[s] = tb[i]
            np_[s] = tp[i]
    return nk, nb, np_


@njit(lazy=True, cache=True)
def _inside(s, e, off, cnt, k):
    """Whether step ``k`` lies in one of the intervals ``s[off:off+cnt]``/``e[...]``."""
    a, b = 0, cnt
    while a < b:
        mid = (a + b) >> 1
        if e[off + mid] < k:
            a = mid + 1
        else:
            b = mid
    return a < cnt and s[off + a] <= k


@njit(lazy=True, cache=True)
def _less(hf, hq, a, b):
    if hf[a] != hf[b]:
        return hf[a] < hf[b]
    if hq[a, 0] != hq[b, 0]:  # the later step first (deeper), as the safe-interval search
        return hq[a, 0] > hq[b, 0]
    return hq[a, 1] < hq[b, 1]


@njit(lazy=True, cache=True)
def _swap(hf, hg, hq, a, b):
    hf[a], hf[b] = hf[b], hf[a]
    hg[a], hg[b] = hg[b], hg[a]
    for c in range(2):
        x = hq[a, c]
        hq[a, c] = hq[b, c]
        hq[b, c] = x


@njit(lazy=True, cache=True)
def _push(hf, hg, hq, ctr, f, g, k, v):
    n = ctr[_HSIZE]
    hf[n] = f
    hg[n] = g
    hq[n, 0] = k
    hq[n, 1] = v
    ctr[_HSIZE] = n + 1
    while n > 0:
        p = (n - 1) >> 1
        if _less(hf, hq, n, p):
            _swap(hf, hg, hq, n, p)
            n = p
        else:
            break


@njit(lazy=True, cache=True)
def _pop(hf, hg, hq, ctr):
    n = ctr[_HSIZE] - 1
    ctr[_HSIZE] = n
    if n == 0:
        return
    _swap(hf, hg, hq, 0, n)
    i = 0
    while True:
        a = 2 * i + 1
        if a >= n:
            break
        b = a + 1
        c = b if (b < n and _less(hf, hq, b, a)) else a
        if _less(hf, hq, c, i):
            _swap(hf, hg, hq, c, i)
            i = c
        else:
            break


@njit(lazy=True, cache=True)
def _set(tk, tb, tp, ctr, key, best, parent):
    s = _slot(tk, key)
    if tk[s] == -1:
        tk[s] = key
        ctr[_TCOUNT] += 1
    tb[s] = best
    tp[s] = parent


@njit(lazy=True, cache=True)
def _get(tk, tb, key):
    s = _slot(tk, key)
    return tb[s] if tk[s] == key else np.inf


@njit(lazy=True, cache=True)
def _run(indptr, nbrs, h, wait_ok, goal, H, penalty, penalty2, stride, ho, hc, hcap, hs, he, so, sc, ss, se,
         so2, sc2, ss2, se2, hf, hg, hq, tk, tb, tp, ctr, need):  # fmt: skip
    """The A* loop over (node, step) states until it ends or needs something (as
    :func:`gfuzzy.timespace.search_kernel._run`: ``_NEED``, ``_ROOM``, ``_YIELD``)."""
    while ctr[_HSIZE] > 0:
        g = hg[0]
        k = hq[0, 0]
        u = hq[0, 1]
        ukey = u * stride + k
        if _get(tk, tb, ukey) < g:
            _pop(hf, hg, hq, ctr)
            continue
        if u == goal:
            ctr[_RESULT] = ukey
            return _SOLVED
        if k + 1 <= H:
            nn = 0
            pushes = 1
            for e in range(indptr[u], indptr[u + 1]):
                v = nbrs[e]
                if math.isinf(h[v]):
                    continue
                if hc[v] < 0 or sc[v] < 0 or sc2[v] < 0:
                    need[nn] = v
                    nn += 1
                pushes += 1
            if nn > 0:
                ctr[_NNEED] = nn
                return _NEED
            if ctr[_HSIZE] + pushes > len(hf) or 2 * (ctr[_TCOUNT] + pushes) > len(tk):
                ctr[_NNEED] = pushes
                return _ROOM
        if ctr[_SINCE] >= YIELD_EVERY:
            ctr[_SINCE] = 0
            return _YIELD
        _pop(hf, hg, hq, ctr)
        ctr[_EXP] += 1
        ctr[_SINCE] += 1
        if k >= hcap[u]:
            ctr[_HIT] = 1
        if k + 1 > H:
            continue
        n1 = k + 1
        for e in range(indptr[u], indptr[u + 1] + 1):
            if e < indptr[u + 1]:
                v = nbrs[e]
            elif wait_ok[u]:
                v = u
            else:
                break
            hv = h[v]
            if math.isinf(hv):
                continue
            if not _inside(hs, he, ho[v], hc[v], n1):
                continue
            ng = g + 1.0
            if not _inside(ss, se, so[v], sc[v], n1):
                ng += penalty
            if not _inside(ss2, se2, so2[v], sc2[v], n1):
                ng += penalty2
            key = v * stride + n1
            if ng < _get(tk, tb, key):
                _set(tk, tb, tp, ctr, key, ng, ukey)
                _push(hf, hg, hq, ctr, ng + hv, ng, n1, v)
    return _EXHAUSTED


@njit(lazy=True, cache=True)
def _path(tk, tp, key, stride):
    nodes = []
    steps = []
    while key >= 0:
        s = _slot(tk, key)
        nodes.append(key // stride)
        steps.append(key % stride)
        key = tp[s]
    return np.array(nodes[::-1], dtype=np.int64), np.array(steps[::-1], dtype=np.int64)


def _room(hf, hg, hq, tk, tb, tp, ctr, pushes: int):
    """The heap and the table grown until ``pushes`` more states fit (the table at most half full)."""
    size = len(hf)
    while ctr[_HSIZE] + pushes > size:
        size *= 2
    if size > len(hf):
        n = int(ctr[_HSIZE])
        nf, ng, nq = np.empty(size), np.empty(size), np.empty((size, 2), np.int64)
        nf[:n], ng[:n], nq[:n] = hf[:n], hg[:n], hq[:n]
        hf, hg, hq = nf, ng, nq
    while 2 * (ctr[_TCOUNT] + pushes) > len(tk):
        tk, tb, tp = _grow_table(tk, tb, tp)
    return hf, hg, hq, tk, tb, tp


def _merged(nodes, steps) -> tuple[list, list]:
    """(nodes, arrival steps) with the waits folded in, as the safe-interval search answers:
    the robot waits at a node from its arrival until one step before the next arrival."""
    out_n, out_s = [int(nodes[0])], [int(steps[0])]
    for nd, st in zip(nodes[1:].tolist(), steps[1:].tolist(), strict=True):
        if nd != out_n[-1]:
            out_n.append(nd)
            out_s.append(st)
    return out_n, out_s


def soft_search(graph, hard, soft, start: int, goal: int, penalty, deadline: float = math.inf,
                stores: tuple | None = None, clock=time.perf_counter) -> SearchResult:  # fmt: skip
    """Least ``arrival + sum of penalty * soft steps`` from ``start`` (at step 0) to ``goal``.

    Parameters
    ----------
    graph : SpaceTimeGraph
    hard : MoverField
        The field whose unsafe (point, step) pairs are forbidden.
    soft : MoverField or (MoverField, MoverField)
        The priced fields (same horizon): a step in an unsafe pair of each costs its
        ``penalty`` more steps (a step unsafe in both, both).
    penalty : float or (float, float)
        Extra cost (in steps) of a step each soft field calls unsafe (>= 0).
    stores : tuple of IntervalStore, optional
        The hard field's store and the soft fields' (pool storage), kept across horizons.

    Returns
    -------
    SearchResult
        The nodes and arrival steps of the cheapest answer (waits folded in), or why none.
    """
    H = hard.steps
    softs = (soft,) if isinstance(soft, MoverField) else tuple(soft)
    prices = (float(penalty),) if np.ndim(penalty) == 0 else tuple(float(x) for x in penalty)
    stores = stores or tuple(IntervalStore(graph) for _ in range(1 + len(softs)))
    hstore, sstore = stores[0], stores[1]
    sstore2 = stores[2] if len(softs) > 1 else sstore  # one soft field: the second is the first, priced 0
    penalty, penalty2 = prices[0], (prices[1] if len(softs) > 1 else 0.0)
    hstore.set_horizon(hard, pool=True)
    for store, field_ in zip(stores[1:], softs, strict=True):
        store.set_horizon(field_, pool=True)
    h = np.ascontiguousarray(graph.heuristic, dtype=np.float64)
    if not math.isfinite(h[start]):
        return SearchResult(Status.NO_PATH, message="the goal is not reachable on the roadmap")
    if h[start] > H:
        return too_short()
    indptr = np.ascontiguousarray(graph.indptr, dtype=np.int64)
    nbrs = np.ascontiguousarray(graph.neighbors, dtype=np.int64)
    n = len(h)
    wait_ok = np.ones(n, np.bool_) if graph.can_wait is None else np.ascontiguousarray(graph.can_wait, np.bool_)
    stride = H + 2
    hf, hg = np.empty(8192), np.empty(8192)
    hq = np.empty((8192, 2), np.int64)
    tk = np.full(1 << 16, -1, np.int64)
    tb, tp = np.empty(1 << 16), np.empty(1 << 16, np.int64)
    ctr = np.zeros(7, np.int64)
    need = np.empty(max(1, int(np.diff(indptr).max(initial=0))), np.int64)

    def load(v):
        hstore.ensure(v)
        sstore.ensure(v)
        sstore2.ensure(v)

    load(start)
    if _inside(hstore.s, hstore.e, int(hstore.off[start]), int(hstore.ready[start]), 0):
        _set(tk, tb, tp, ctr, start * stride, 0.0, -1)
        _push(hf, hg, hq, ctr, float(h[start]), 0.0, 0, start)
    else:  # the margin refuses the start: the first motions decided exactly (hard field)
        key0 = start * stride + stride - 1
        _set(tk, tb, tp, ctr, key0, 0.0, -1)
        neighbours = nbrs[indptr[start] : indptr[start + 1]].tolist()
        for v, _, arrive in first_motions(graph, hard, start, 0, hstore.get, neighbours, bool(wait_ok[start])):
            load(v)
            cost = float(arrive)
            if not _inside(sstore.s, sstore.e, int(sstore.off[v]), int(sstore.ready[v]), arrive):
                cost += penalty
            if not _inside(sstore2.s, sstore2.e, int(sstore2.off[v]), int(sstore2.ready[v]), arrive):
                cost += penalty2
            key = v * stride + arrive
            if cost < _get(tk, tb, key):
                hf, hg, hq, tk, tb, tp = _room(hf, hg, hq, tk, tb, tp, ctr, 1)
                _set(tk, tb, tp, ctr, key, cost, key0)
                _push(hf, hg, hq, ctr, cost + h[v], cost, arrive, v)
        if ctr[_HSIZE] == 0:
            return SearchResult(Status.NO_PATH, message=NO_FIRST_MOTION)
    while True:
        code = _run(indptr, nbrs, h, wait_ok, goal, H, penalty, penalty2, stride,
                    hstore.off, hstore.ready, hstore.cap, hstore.s, hstore.e, sstore.off, sstore.ready, sstore.s,
                    sstore.e, sstore2.off, sstore2.ready, sstore2.s, sstore2.e, hf, hg, hq, tk, tb, tp, ctr, need)  # fmt: skip
        if code == _ROOM:
            hf, hg, hq, tk, tb, tp = _room(hf, hg, hq, tk, tb, tp, ctr, int(ctr[_NNEED]))
            continue
        if code == _NEED:
            for v in need[: ctr[_NNEED]].tolist():
                load(v)
        if code in (_NEED, _YIELD):
            if clock() > deadline:
                return SearchResult(Status.TIMEOUT, message="planning time budget exhausted",
                                    expansions=int(ctr[_EXP]), states=int(ctr[_TCOUNT]))  # fmt: skip
            continue
        break
    expansions, states = int(ctr[_EXP]), int(ctr[_TCOUNT])
    if code == _SOLVED:
        nodes, steps = _path(tk, tp, int(ctr[_RESULT]), stride)
        if nodes[0] == start and steps[0] == stride - 1:  # the first motions' virtual start
            steps[0] = 0
        nodes_l, steps_l = _merged(nodes, steps)
        return SearchResult(Status.SOLVED, nodes_l, steps_l, expansions=expansions, states=states)
    return exhausted(expansions, states, bool(ctr[_HIT]))


def warm() -> None:
    """Compile (or load from numba's cache) the loop: a priced search on a three-node line
    past a mover, with waits, so that a navigator's first call does not pay for it."""
    from ..scene.scene import parse_scene
    from .spacetime import SpaceTimeGraph

    scene = parse_scene({"version": 1, "name": "warm", "bounds": [0, 0, 2, 2], "robot": {"disc": 0.2, "vmax": 1.0},
                         "movers": [{"name": "a", "disc": 0.2, "speed": 1.0, "path": [[1, 1.8], [1, 0.2]],
                                     "mode": "bounce"}]})  # fmt: skip
    graph = SpaceTimeGraph(poses=np.array([[0.5, 1.0], [1.0, 1.0], [1.5, 1.0]]), indptr=np.array([0, 1, 3, 4]),
                           neighbors=np.array([1, 0, 2, 1]), heuristic=np.array([2.0, 1.0, 0.0]))  # fmt: skip
    hard = MoverField(scene, 0.0, 0.1, 40, 1.0)
    soft = MoverField(scene, 0.0, 0.1, 40, 1.0, clearance=0.3)
    hard.compiled = soft.compiled = True
    soft_search(graph, hard, soft, 0, 2, 2.0)
    soft_search(graph, hard, (soft, hard), 0, 2, (2.0, 1.0))
    _grow_table(np.full(2, -1, np.int64), np.empty(2), np.empty(2, np.int64))  # called only past 32,768 states
