"""The space-time graph the safe-interval search runs on, its safe intervals, its result.

A roadmap (plus start and goal) becomes a :class:`SpaceTimeGraph` by cutting every edge
into ``k`` equal one-step pieces (:func:`split_edges`, with the rule of
:func:`gfuzzy.poses.split_counts`); :class:`IntervalStore` computes the safe intervals of
its points from a :class:`gfuzzy.timespace.movers.MoverField`, in batches, on demand; both searches
(:func:`gfuzzy.timespace.timespace.sipp` and the compiled :func:`gfuzzy.timespace.search_kernel.sipp_compiled`)
return a :class:`SearchResult`.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from ..poses import interpolate_segment, split_counts
from ..settings import INTERVAL_BATCH_CELLS
from ..status import Status
from ..typed import BoolArray, FloatArray, IntArray

if TYPE_CHECKING:
    from .movers import MoverField

__all__ = ["SpaceTimeGraph", "QueryGraph", "SearchResult", "IntervalStore", "StoreLayout", "store_layout", "SplitEdges",
           "split_edges", "leading_fractions", "BAND"]

#: Safety is computed for every group whose static lower bound on f lies within this many
#: steps of the group the search asks for: the A* order will want them soon.
BAND = 6


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
    #: A graph whose first nodes this one's are (their poses, heuristic and groups the same:
    #: a goal's kept graph spliced with a start), or None; its groups' static set-up for an
    #: :class:`IntervalStore` is then computed once and kept with it (:func:`store_layout`).
    kept: object = field(default=None, compare=False, repr=False)


@dataclass(frozen=True)
class QueryGraph:
    """A query's graph as the search gets it: the graph, its ends, the roadmap distance.

    Built by one splice per query: :meth:`gfuzzy.planner.prepared.PreparedGoal.splice`
    (a holonomic robot) or :meth:`gfuzzy.timespace.unicycle.UnicycleGoal.splice` (a
    differential drive, whose :class:`~gfuzzy.timespace.unicycle.UnicycleGraph` has the
    same fields).

    Attributes
    ----------
    graph : SpaceTimeGraph
    s_id, g_id : int
        The start's and the goal's points.
    roadmap_distance : float
        Shortest static start-to-goal distance on the roadmap (the contract's; inf when
        the roadmap does not join them).
    """

    graph: SpaceTimeGraph
    s_id: int
    g_id: int
    roadmap_distance: float


@dataclass
class SearchResult:
    """Outcome of :func:`gfuzzy.timespace.timespace.sipp` (and the compiled search): ``status`` is
    :attr:`Status.SOLVED`, :attr:`Status.NO_PATH` or :attr:`Status.TIMEOUT`."""

    status: Status
    nodes: list = field(default_factory=list)  # node ids, one per arrival
    steps: list = field(default_factory=list)  # arrival steps
    message: str = ""
    expansions: int = 0
    states: int = 0
    horizon_hit: bool = False


class IntervalStore:
    """Safe intervals of a graph's points, computed in batches on demand.

    A point's safety is only computed inside its time window ``[from_start, H - h]`` (see
    :class:`SpaceTimeGraph`); when the search's horizon H grows, the windows grow and only
    the new steps are computed, so a search restarted with a longer horizon redoes no
    safety work.

    Two storages, chosen by the search at :meth:`set_horizon`: lists per batch, read node
    by node (the reference search, :func:`gfuzzy.timespace.timespace.sipp`), or one pool of arrays
    the compiled search reads directly (``pool=True``, :func:`gfuzzy.timespace.search_kernel.sipp_compiled`):
    its batches come from the compiled kernel (:meth:`MoverField.safe_intervals`) and a
    window grown with the horizon is merged with what was computed before in machine code.

    Parameters
    ----------
    graph : SpaceTimeGraph

    Attributes
    ----------
    off, ready, cap : (N,) int
        Pool storage only: node i's intervals are ``s[off[i]:off[i] + ready[i]]`` and
        ``e[...]`` once computed up to the current horizon (``ready[i] >= 0``; -1: not
        yet), and ``cap[i]`` is the last step examined for it.
    s, e : (P,) int
        The pool (reallocated as it grows: read the attributes again after a compute).
    """

    def __init__(self, graph: SpaceTimeGraph):
        self.graph = graph
        lay = store_layout(graph)
        self.ptr, self._finite, self._hfloor, self._same = lay.ptr, lay.finite, lay.hfloor, lay.same
        self._layout = lay
        self.g_lo, self.f_lb = _windows_of(graph, lay)
        self.done_hi = np.full(len(self.ptr) - 1, -1, dtype=np.int64)  # last step computed
        self.pool: bool | None = None  # the storage, fixed by the first set_horizon
        self.field = None
        self.H = -1
        #: A pool store of the same graph whose field is at least as cautious as this one's
        #: (every step safe there is safe here: the same people, each kept at least as far),
        #: or None; a group whose points it found safe all through this batch's window is
        #: not computed again (a navigator's search without the personal space after the one
        #: with it). The caller vouches for the fields; set it per field (it may change).
        self.prior: IntervalStore | None = None

    def set_horizon(self, field_: MoverField, pool: bool = False) -> None:
        """Serve intervals for ``field_``'s horizon (never shorter than before), from the
        pool of arrays (``pool``) or from lists; a store keeps the storage it started with."""
        if field_.steps < self.H:
            raise ValueError("the horizon of an IntervalStore only grows")
        if self.pool and pool and field_ is self.field and field_.steps == self.H:
            # the same field again (a navigator's goal test, then its search): the pool's
            # ready counts are kept up to date batch by batch (_pool_merge), nothing changed
            self._served = {}
            return
        if self.pool is None:
            self.pool = bool(pool)
            self._init_storage()
        elif self.pool != bool(pool):
            raise ValueError("an IntervalStore serves one kind of search (reference or compiled)")
        self.field = field_
        self.H = field_.steps
        self.g_hi = np.where(self._finite, self.H - self._hfloor, -1).astype(np.int64)
        self._served: dict = {}
        if self.pool:
            grp = self._node_group
            fresh = not (self.done_hi >= 0).any()  # nothing computed yet
            if fresh and not field_.movers:
                self._fill_whole()
                fresh = False
            self.cap = self.g_hi[grp]
            if fresh:  # every done_hi -1 and every count -1: ready (0 intervals) only where the window is empty
                self.ready = np.where(self.cap <= -1, 0, -1).astype(np.int64)
            else:
                self.ready = np.where(self.done_hi[grp] >= self.cap, np.maximum(self.cnt, 0), -1)

    def _fill_whole(self) -> None:
        """A fresh pool for a field without movers, in one go: each point's one interval, its
        group's whole window clipped to the horizon (what :meth:`_compute`'s batches find)."""
        grp = self._node_group
        self.s = np.maximum(self.g_lo, 0)[grp]
        self.e = np.minimum(self.g_hi, self.H)[grp]
        self.cnt = (self.s <= self.e).astype(np.int64)
        self.off = np.arange(len(grp), dtype=np.int64)
        self.used = len(grp)
        np.maximum(self.done_hi, self.g_hi, out=self.done_hi)

    def _init_storage(self) -> None:
        n = len(self.graph.poses)
        if self.pool:
            self._node_group = self._layout.node_group
            self.off = np.zeros(n, dtype=np.int64)
            self.cnt = np.full(n, -1, dtype=np.int64)  # -1: never computed
            self.s = np.empty(4096, dtype=np.int64)
            self.e = np.empty(4096, dtype=np.int64)
            self.used = 0
        else:  # intervals stay in their batch's lists until a search asks for them
            self._batches: list = []  # (starts, row pointers, ends, first step examined per row)
            self._where = np.full(n, -1, dtype=np.int64)  # batch of a node's latest computation
            self._local = np.zeros(n, dtype=np.int64)  # its row there
            self._older: dict = {}  # node -> (starts, ends) from computations before the latest

    def group_of(self, node: int) -> int:
        return int(self._layout.node_group[node])

    def ensure(self, node: int) -> None:
        """Compute ``node``'s intervals up to the current horizon (with a batch of others)."""
        g = self.group_of(node)
        if self.done_hi[g] < self.g_hi[g]:
            self._compute(g)

    def get(self, node: int) -> tuple:
        """(interval starts, interval ends, last step examined) of a node: lists, or array
        slices from the pool."""
        iv = self._served.get(node)
        if iv is not None:
            return iv
        g = self.group_of(node)
        cap = int(self.g_hi[g])
        if self.done_hi[g] < cap:
            self._compute(g)
        if self.pool:
            a, c = int(self.off[node]), max(int(self.cnt[node]), 0)
            iv = (self.s[a : a + c], self.e[a : a + c], cap)
        else:
            starts, ends = self._intervals(node)
            iv = (starts, ends, cap)
        self._served[node] = iv
        return iv

    def _intervals(self, node: int) -> tuple[list, list]:
        b = int(self._where[node])
        if b < 0:
            return [], []
        cs, sp, ce, first = self._batches[b]
        k = int(self._local[node])
        a, z = sp[k], sp[k + 1]
        old = self._older.get(node)
        if old is None or not old[0]:
            return cs[a:z], ce[a:z]
        starts, ends = list(old[0]), list(old[1])
        if a < z:
            if ends[-1] == first[k] - 1 and cs[a] == first[k]:  # the last interval goes on
                ends[-1] = ce[a]
                a += 1
            starts.extend(cs[a:z])
            ends.extend(ce[a:z])
        return starts, ends

    def _compute(self, g: int) -> None:
        ptr, field_ = self.ptr, self.field
        need = self.done_hi < self.g_hi
        if not field_.movers:  # nobody: every window is one interval, no table: all in one batch
            pending = np.nonzero(need)[0]
        else:
            pending = np.nonzero(need & (self.f_lb <= self.f_lb[g] + BAND))[0]
            pending = pending[np.argsort(self.f_lb[pending], kind="stable")]
            budget = max(1, INTERVAL_BATCH_CELLS // (self.H + 1))  # points per batch (points x steps bools)
            sizes = ptr[pending + 1] - ptr[pending]
            pending = pending[np.cumsum(sizes) <= budget]
        if not (pending == g).any():
            pending = np.append(pending, g)
        lo = np.maximum(self.g_lo[pending], self.done_hi[pending] + 1)
        hi = self.g_hi[pending]
        sizes = ptr[pending + 1] - ptr[pending]
        sub_ptr = np.concatenate([[0], np.cumsum(sizes)])
        nodes = np.repeat(ptr[pending], sizes) + (np.arange(sub_ptr[-1]) - np.repeat(sub_ptr[:-1], sizes))
        lo_n = np.repeat(lo, sizes)
        # the safety first, the bookkeeping after: a field that raises (a deadline inside
        # the batch) leaves the store as it was
        if self.pool:
            compute = _pool_intervals
        else:
            H = self.H

            def compute(f, p, pt, a, b):
                return _intervals_from_pairs(f, p, pt, a, b, H)

        if self.pool and not field_.movers:  # nobody: each point's whole window (clipped as safe_intervals does)
            from .movers import whole_windows

            gs, ge, sp = whole_windows(sub_ptr, np.maximum(lo, 0), np.minimum(hi, field_.steps))
        elif self.pool and self.prior is not None:
            gs, ge, sp, nodes, lo_n = self._after_prior(pending, nodes, sizes, lo, hi, compute)
        else:
            gs, ge, sp = _safe_intervals_shared(field_, self.graph.poses[nodes], sub_ptr, lo, hi, self._same[pending],
                                                compute)  # fmt: skip
        self.done_hi[pending] = hi
        if self.pool:
            self._pool_merge(nodes, gs, ge, sp, lo_n)
            return
        for nid in nodes[self._where[nodes] >= 0].tolist():  # extended windows: keep what was computed before
            self._older[nid] = self._intervals(nid)
        self._batches.append((gs.tolist(), sp.tolist(), ge.tolist(), lo_n.tolist()))
        self._where[nodes] = len(self._batches) - 1
        self._local[nodes] = np.arange(len(nodes))

    def _after_prior(self, pending, nodes, sizes, lo, hi, compute):
        """A batch's (starts, ends, sp, nodes, first steps) with :attr:`prior`: the groups
        whose every point it found safe all through the window (clipped as
        :meth:`MoverField.safe_intervals` clips) get that window as their one interval; the
        others are computed. The computed groups' points come first."""
        from .movers import whole_windows

        prior, steps = self.prior, self.field.steps
        lo_c, hi_c = np.maximum(lo, 0), np.minimum(hi, steps)
        gid = np.repeat(np.arange(len(pending)), sizes)
        cnt = prior.cnt[nodes]
        at = np.where(cnt == 1, prior.off[nodes], 0)
        whole = (cnt == 1) & (prior.s[at] <= lo_c[gid]) & (prior.e[at] >= hi_c[gid])
        known = (np.bincount(gid, weights=~whole, minlength=len(pending)) == 0) | (lo_c > hi_c)
        if not known.any():
            sub_ptr = np.concatenate([[0], np.cumsum(sizes)])
            gs, ge, sp = _safe_intervals_shared(self.field, self.graph.poses[nodes], sub_ptr, lo, hi,
                                                self._same[pending], compute)  # fmt: skip
            return gs, ge, sp, nodes, np.repeat(lo, sizes)
        todo = ~known
        pts = todo[gid]
        ga, ea, spa = _safe_intervals_shared(self.field, self.graph.poses[nodes[pts]],
                                             np.concatenate([[0], np.cumsum(sizes[todo])]), lo[todo], hi[todo],
                                             self._same[pending[todo]], compute)  # fmt: skip
        gb, eb, spb = whole_windows(np.concatenate([[0], np.cumsum(sizes[known])]), lo_c[known], hi_c[known])
        sp = np.concatenate([spa, spb[1:] + spa[-1]])
        first = np.concatenate([np.repeat(lo[todo], sizes[todo]), np.repeat(lo[known], sizes[known])])
        return np.concatenate([ga, gb]), np.concatenate([ea, eb]), sp, np.concatenate([nodes[pts], nodes[~pts]]), first

    def _pool_merge(self, nodes, gs, ge, sp, lo_n) -> None:
        """Append a batch to the pool; a node computed before (a window grown with the
        horizon) gets its older intervals first, the last one joined to the new first
        when they meet (:func:`gfuzzy.timespace.movers_kernel.merge_runs`)."""
        from .movers_kernel import merge_runs

        room = self.used + len(gs) + int(np.maximum(self.cnt[nodes], 0).sum())
        if room > len(self.s):
            size = max(2 * len(self.s), room)
            for name in ("s", "e"):
                grown = np.empty(size, dtype=np.int64)
                grown[: self.used] = getattr(self, name)[: self.used]
                setattr(self, name, grown)
        self.used = merge_runs(self.s, self.e, self.off, self.cnt, self.used, nodes, gs, ge, sp, lo_n)
        self.ready[nodes] = self.cnt[nodes]


@dataclass(frozen=True)
class StoreLayout:
    """A graph's groups for an :class:`IntervalStore` (what does not change with the search):
    the group pointers ``ptr`` (each edge's points, every other node alone), each point's
    group, each group's smallest heuristic (``finite``; its floor ``hfloor`` in steps) and
    whether its points share one position (:func:`_same_position_groups`)."""

    ptr: IntArray
    node_group: IntArray
    finite: BoolArray
    hfloor: IntArray
    same: BoolArray


def _group_pointers(groups, first: int, n: int, start: int = 0) -> IntArray:
    """Sorted distinct ``arange(start, first + 1)`` and ``groups`` from ``start`` up to
    ``n``, ending with ``n``."""
    ptr = np.arange(start, first + 1, dtype=np.int64)
    if groups is not None:
        groups = np.asarray(groups, dtype=np.int64)
        ptr = np.sort(np.concatenate([ptr, groups[groups >= start] if start else groups]))
        ptr = ptr[np.r_[True, ptr[1:] != ptr[:-1]]]  # np.unique, which imports numpy.ma (~20 ms)
    ptr = ptr[ptr <= n]
    if ptr[-1] != n:
        ptr = np.append(ptr, n)
    return ptr


def _layout_of(poses, heuristic, ptr, g0: int = 0) -> tuple:
    """(node_group, finite, hfloor, same) of the groups ``ptr`` (numbered from ``g0``)."""
    node_group = np.repeat(np.arange(g0, g0 + len(ptr) - 1, dtype=np.int64), np.diff(ptr))
    hmin = np.minimum.reduceat(heuristic, ptr[:-1] - ptr[0]) if len(ptr) > 1 else np.zeros(0)
    finite = np.isfinite(hmin)
    hfloor = np.floor(np.where(finite, hmin, 0) + 1e-9).astype(np.int64)
    return node_group, finite, hfloor, _same_position_groups(poses, ptr - ptr[0])


def store_layout(graph) -> StoreLayout:
    """The :class:`StoreLayout` of ``graph`` (anything with ``poses``, ``heuristic`` and
    ``groups``), kept with it while those stay the same arrays. A graph spliced from a kept
    one (``graph.kept``) computes only its own nodes' groups: the kept graph's are the
    same and kept with it (a differential drive's navigator splices its pose into a goal's
    graph of 95,000 points every call, and searches it once or twice)."""
    src = (graph.poses, graph.heuristic, graph.groups)
    hit = getattr(graph, "_store_layout", None)
    if hit is not None and all(a is b for a, b in zip(hit[0], src, strict=True)):
        return hit[1]
    n = len(graph.poses)
    first = int(graph.groups[0]) if graph.groups is not None else n
    kept = getattr(graph, "kept", None)
    m = 0 if kept is None else len(kept.poses)
    own = 0 if kept is None or kept.groups is None else len(kept.groups)  # the kept graph's groups come first
    if own and first < m < n and own < len(graph.groups) and int(graph.groups[own]) == m:
        head = store_layout(kept)
        tail = _group_pointers(graph.groups[own:], m, n, start=m)  # the groups from m on, m first
        ptr = np.concatenate([head.ptr, tail[1:]])
        parts = _layout_of(graph.poses[m:], graph.heuristic[m:], tail, len(head.ptr) - 1)
        lay = StoreLayout(ptr, *(np.concatenate([a, b]) for a, b in
                                 zip((head.node_group, head.finite, head.hfloor, head.same), parts, strict=True)))  # fmt: skip
    else:
        ptr = _group_pointers(graph.groups, first, n)
        lay = StoreLayout(ptr, *_layout_of(graph.poses, graph.heuristic, ptr))
    object.__setattr__(graph, "_store_layout", (src, lay))
    return lay


def _windows_of(graph, lay: StoreLayout) -> tuple[IntArray, FloatArray]:
    """(g_lo, f_lb) per group: the first step a group's points can be reached (from
    ``graph.from_start``, 0 without it) and the static lower bound on f; kept with the graph
    while its ``from_start`` and heuristic stay the same arrays (a navigator's second search)."""
    hit = getattr(graph, "_store_windows", None)
    if hit is not None and hit[0] is graph.from_start and hit[1] is graph.heuristic and hit[2] is lay:
        return hit[3]
    ptr, h = lay.ptr, graph.heuristic
    fs = graph.from_start if graph.from_start is not None else np.zeros(len(graph.poses))
    fs = np.where(np.isfinite(fs), fs, 0.0)
    g_lo = np.maximum(0, np.floor(np.minimum.reduceat(fs, ptr[:-1]) + 1e-9)).astype(np.int64)
    out = (g_lo, np.minimum.reduceat(fs + h, ptr[:-1]))
    object.__setattr__(graph, "_store_windows", (graph.from_start, graph.heuristic, lay, out))
    return out


def _same_position_groups(poses, ptr) -> BoolArray:
    """(G,) bool: groups of more than one point, all at one position (a unicycle's turning
    ring, a turn in place). A group is the points of one straight motion, so its first and
    last points share a position only when all do."""
    sizes = np.diff(ptr)
    multi = np.nonzero(sizes > 1)[0]
    out = np.zeros(len(sizes), dtype=bool)
    out[multi] = np.all(poses[ptr[multi], :2] == poses[ptr[multi + 1] - 1, :2], axis=1)
    return out


def _pool_intervals(field_, poses, ptr, lo, hi):
    return field_.safe_intervals(poses, ptr, lo, hi)


def _turn_field(field_: MoverField) -> MoverField:
    """``field_`` for a robot turning in place: its circumscribed disc, which holds the body
    at every heading (the same field for a disc robot)."""
    robot = field_.robot
    if robot.shape == "disc":
        return field_
    from dataclasses import replace as _replace

    body = copy.copy(field_)
    body.robot = _replace(robot, shape="disc", radius=robot.circumradius, size=(0.0, 0.0))
    return body


def _whole(starts, ends, sp, lo, hi) -> BoolArray:
    """Per point of intervals ``(starts, ends, sp)``: safe all through its window ``lo..hi``
    (one interval covering it, or an empty window)."""
    one = np.diff(sp) == 1
    k = np.where(one, sp[:-1], 0)
    if not len(starts):
        return hi < lo
    return (one & (starts[k] <= lo) & (ends[k] >= hi)) | (hi < lo)


def _refined(field_, poses, ptr, lo, hi, collapse, refine, compute):
    """(points, intervals) of the same-position groups ``refine`` (indices among the
    collapsed ones) judged point by point with the body, for :func:`_safe_intervals_shared`."""
    sizes = np.diff(ptr)
    rg = np.nonzero(collapse)[0][refine]  # the refined groups, as indices of all groups
    rpts = np.concatenate([np.arange(ptr[g], ptr[g + 1]) for g in rg.tolist()])
    return rpts, compute(field_, poses[rpts], np.concatenate([[0], np.cumsum(sizes[rg])]).astype(np.int64), lo[rg], hi[rg])


def _safe_intervals_shared(field_: MoverField, poses, ptr, lo, hi, same, compute):
    """Safe intervals of groups of points (``compute(field, poses, ptr, lo, hi)``, e.g.
    :meth:`MoverField.safe_intervals`), computed once for a group whose points all share one
    position (``same``, per group: a unicycle's turn in place) and handed to each of its
    points. Such a group is judged with the robot's circumscribed disc (:func:`_turn_field`):
    the body at any heading lies inside it, so every point's safety is sound, and for a disc
    robot exact.

    Returns (starts, ends, sp) as :meth:`gfuzzy.timespace.movers.MoverField.safe_intervals`.
    """
    sizes = np.diff(ptr)
    n = len(poses)
    collapse = same & (sizes > 1)
    if n == 0 or not collapse.any():
        return compute(field_, poses, ptr, lo, hi)
    norm = ~collapse
    pn = np.repeat(norm, sizes)
    ga, ea, spa = compute(field_, poses[pn], np.concatenate([[0], np.cumsum(sizes[norm])]).astype(np.int64),
                          lo[norm], hi[norm])  # fmt: skip
    body = _turn_field(field_)
    before = body.evaluations
    firsts = ptr[:-1][collapse]
    gb, eb, spb = compute(body, poses[firsts], np.arange(len(firsts) + 1, dtype=np.int64), lo[collapse], hi[collapse])
    if body is not field_:
        field_.evaluations += body.evaluations - before
        # where the disc is not safe all through a group's window, its points are judged
        # one by one with the body at their headings (sound as any point's judgement: the
        # turning rate is capped at vmax / circumradius (Robot.turn_rate), so a turn's step
        # moves no point of the body farther than vmax dt, the margin's bound)
        refine = np.nonzero(~_whole(gb, eb, spb, np.clip(lo[collapse], 0, None), np.minimum(hi[collapse], field_.steps)))[0]
    else:
        refine = np.zeros(0, dtype=np.int64)
    start = np.empty(n, dtype=np.int64)
    count = np.empty(n, dtype=np.int64)
    start[pn], count[pn] = spa[:-1], np.diff(spa)
    cidx = np.repeat(np.cumsum(collapse) - 1, sizes)[~pn]  # each point's collapsed group
    start[~pn], count[~pn] = spb[:-1][cidx] + len(ga), np.diff(spb)[cidx]
    starts, ends = [ga, gb], [ea, eb]
    if len(refine):
        rpts, (gr, er, spr) = _refined(field_, poses, ptr, lo, hi, collapse, refine, compute)
        start[rpts], count[rpts] = spr[:-1] + len(ga) + len(gb), np.diff(spr)
        starts.append(gr)
        ends.append(er)
    sp = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    idx = np.repeat(start, count) + (np.arange(sp[-1]) - np.repeat(sp[:-1], count))
    return np.concatenate(starts)[idx], np.concatenate(ends)[idx], sp


def _intervals_from_pairs(field_: MoverField, poses, ptr, lo, hi, H: int):
    """Safe intervals of groups of points from the field's unsafe pairs (the numpy
    reference): the gaps between unsafe steps, with each window's ends as walls.

    Returns (starts, ends, sp) as :meth:`gfuzzy.timespace.movers.MoverField.safe_intervals`.
    """
    sizes = np.diff(ptr)
    # walls at lo - 1 and hi + 1, kept inside the row's keys; an empty window (lo > hi: a
    # point that cannot matter before the horizon) gets its walls side by side, no gap
    lo_n = np.minimum(np.repeat(lo, sizes), H + 1)
    hi_n = np.maximum(np.repeat(hi, sizes), lo_n - 1)
    un, us = field_.unsafe_pairs(poses, ptr, lo, hi)
    k = len(poses)
    span = H + 3  # steps -1 .. H + 1 fit in [0, span) once shifted by one
    rows = np.arange(k) * span
    keys = np.sort(np.concatenate([un * span + us + 1, rows + lo_n, rows + hi_n + 2]))
    wn, ws = keys // span, keys % span - 1  # repeated walls leave empty gaps, dropped below
    same = wn[1:] == wn[:-1]
    gs, ge = ws[:-1] + 1, ws[1:] - 1
    ok = same & (gs <= ge)
    rn = wn[:-1][ok]
    return gs[ok], ge[ok], np.searchsorted(rn, np.arange(k + 1))


@dataclass(frozen=True)
class SplitEdges:
    """Edges cut into one-step pieces (:func:`split_edges`).

    Attributes
    ----------
    k : (e,) int
        Steps per edge.
    offs : (e+1,) int
        Interior points of edge i are ``first_id + offs[i] .. first_id + offs[i+1] - 1``.
    inner : (offs[-1], d) float
        Their poses.
    a, b, j : (offs[-1],) int
        Each interior point's edge ends and its index 1..k-1 along the edge.
    src, dst : (c,) int
        The one-step moves along the chains a -> interior... -> b (one direction).
    """

    k: IntArray
    offs: IntArray
    inner: FloatArray
    a: IntArray
    b: IntArray
    j: IntArray
    src: IntArray
    dst: IntArray


def leading_fractions(frac: FloatArray, j: IntArray, k: IntArray, length: FloatArray, step_len: float,
                      lead: IntArray) -> FloatArray:  # fmt: skip
    """Fractions along their edges of interior points ``j`` (of ``k`` pieces, of edges of
    ``length``) cut into whole steps of ``step_len`` from the first end (``lead`` 1) or
    up to the second (-1), the remainder (at most a step) at the other end; ``frac`` (the
    equal pieces' ``j / k``) where ``lead`` is 0 or whole steps would not leave a
    remainder (the extra piece of :func:`gfuzzy.poses.split_counts`'s rounding rule).
    Every piece stays at most ``step_len`` long."""
    # an absolute margin: a length a hair over whole steps would leave a remainder of
    # 1e-13 m, a step the robot does not move in (a wait to :mod:`gfuzzy.navigation.brisk`)
    whole = (k - 1) * step_len < length - 1e-9
    safe = np.where(length > 0, length, 1.0)
    out = np.where((lead > 0) & whole, j * step_len / safe, frac)
    return np.where((lead < 0) & whole, 1.0 - (k - j) * step_len / safe, out)


def split_edges(verts: FloatArray, edges: IntArray, lengths: FloatArray, step_len: float, first_id: int,
                lead: IntArray | None = None) -> SplitEdges:  # fmt: skip
    """Cut edges into one-step pieces of at most ``step_len`` (:func:`gfuzzy.poses.split_counts`).

    The one place the roadmap-time graph is cut: the roadmap's spanner once per (step,
    stretch) (:func:`gfuzzy.timespace.roadgraph.spanner_split`), a goal's connections
    (:meth:`gfuzzy.timespace.roadgraph.SplitSpanner.splice`) and a start's
    (:meth:`gfuzzy.planner.prepared.PreparedGoal.splice`).

    Parameters
    ----------
    verts : (n, d) float
    edges : (e, 2) int
    lengths : (e,) float
    step_len : float
        vmax * dt.
    first_id : int
        Id of the first interior point.
    lead : (e,) int, optional
        Per edge, where its pieces are whole steps: 0 (default) equal pieces; 1 whole
        steps from ``edges[:, 0]``, the remainder last; -1 whole steps up to
        ``edges[:, 1]``, the remainder first. The same steps either way (the search's
        costs and bounds do not change), but a robot that follows a plan for a moment
        and replans moves at full speed on a leading edge, where equal pieces run it at
        ``len / (k step)`` of it (:func:`leading_fractions`).

    Returns
    -------
    SplitEdges
    """
    k = split_counts(lengths, step_len)
    n_int = k - 1
    offs = np.concatenate([[0], np.cumsum(n_int)]).astype(np.int64)
    e_of = np.repeat(np.arange(len(edges)), n_int)
    j = np.arange(offs[-1]) - np.repeat(offs[:-1], n_int) + 1
    a, b = edges[e_of, 0], edges[e_of, 1]
    frac = j / k[e_of]
    if lead is not None and len(frac):
        frac = leading_fractions(frac, j, k[e_of], np.asarray(lengths, dtype=float)[e_of], step_len,
                                 np.asarray(lead)[e_of])  # fmt: skip
    inner = interpolate_segment(verts[a], verts[b], frac)
    ids = np.arange(first_id, first_id + offs[-1])
    first = np.zeros(offs[-1], dtype=bool)
    first[offs[:-1][n_int > 0]] = True
    last = np.zeros(offs[-1], dtype=bool)
    last[(offs[1:] - 1)[n_int > 0]] = True
    prev = np.where(first, a, ids - 1)
    src = np.concatenate([prev, ids[last], edges[n_int == 0, 0]])
    dst = np.concatenate([ids, b[last], edges[n_int == 0, 1]])
    return SplitEdges(k, offs, inner, a, b, j, src, dst)
