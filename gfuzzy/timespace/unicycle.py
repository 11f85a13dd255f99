"""The differential drive (``kinematics: unicycle``): a roadmap of heading copies.

A unicycle moves only along its heading and turns only in place (CONTRACT section 6). The
search graph keeps the roadmap's positions and straight edges and gives every vertex one
*copy* per heading it can leave or arrive with:

* a **lane** is a roadmap edge (u, v) driven at the heading of u -> v (forward from u to v;
  backwards from v to u too when ``robot.reverse``), certified free for the body held at that
  heading (:meth:`gfuzzy.collision.geometry.StaticGeometry.motion_free` with a fixed heading);
* a **turn** joins two copies at one vertex that are neighbours in heading order, both ways
  round; it takes ``|dh| / turn_rate`` seconds and, for a body that is not a disc, is
  certified against walls while it sweeps (a vertex where the sweep collides loses that turn);
* every lane and turn is a *piece* from one copy to another, cut into one-step points like
  any motion (:func:`gfuzzy.poses.split_counts`) with a turn's length counted as
  ``|dh| * vmax / turn_rate``: a step never exceeds ``vmax dt`` in the contract's metric nor
  ``turn_rate dt`` in heading, so the movers' safety of :mod:`gfuzzy.timespace.movers` holds over it;
  the robot may wait at any point.

The start and the goal join through turn + straight + turn: the start turns in place towards a
nearby vertex, drives to a new copy there (which joins its vertex's heading neighbours), and
the goal is reached from a copy at a vertex driving straight to the goal's position, then
turning to the goal's heading. The safe-interval search (:func:`gfuzzy.timespace.timespace.sipp` and
its compiled twin) runs unchanged on this directed graph: the answer is time-optimal on it
at the step dt.

For a disc the lanes are the roadmap's (its spanner's) edges: a disc's body does not depend
on its heading. For a box the lanes come from the SE(2) roadmap's vertex positions: its
edges and each vertex's nearest neighbours in the plane, each re-certified at its heading.
The lanes and the query-independent pieces are kept in ``Roadmap._derived``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..poses import split_counts, wrap_angle
from ..typed import FloatArray, IntArray
from .drive import MERGE_HEADING, SAME_HEADING, fan, lane_turn, pick_turn
from .roadgraph import vertex_clearances
from .spacetime import SpaceTimeGraph
from .uniends import _drive, _Extras
from .unilanes import LANE_NEIGHBOURS, _rings, chain_turns, lanes
from .unipaths import dijkstra, matrix, new_to_goal, steps_from_start, with_rows

__all__ = ["UnicycleGraph", "UnicycleGoal", "UnicyclePrepared", "prepare_goal", "build_graph", "lanes", "LANE_NEIGHBOURS", "SAME_HEADING"]

@dataclass
class _Base:
    """The query-independent pieces (see the module docstring).

    Attributes
    ----------
    poses : (K, 3) float
        The copies: a vertex's position and a heading.
    vertex : (K,) int
        The roadmap vertex of each copy.
    a, b : (P,) int
        Pieces: from copy a to copy b; a negative id -(1 + i) is ring point i.
    dh : (P,) float
        A turn's signed heading change; 0 for a lane.
    length : (P,) float
        Metres at vmax: a lane's length, ``|dh| vmax / turn_rate`` for a turn.
    ring : (R, 3) float
        Turning rings: every vertex with copies has ``n_ring`` points at its position, at
        headings ``-pi + i 2 pi / n_ring`` (one turning step apart), joined in a circle both
        ways; each copy joins the two ring points around its heading. A turn from one copy
        to another goes copy -> ring ... ring -> copy: at most two steps longer than the
        turn itself, however many copies the vertex has; copies with no ring point between
        them also join directly (:func:`_same_interval`). Points where the body collides,
        and arcs whose sweep does, are left out (``ring_ok``).
    ring_ptr : (V,) int
        First ring point of each vertex (-1: no ring).
    ring_ok : (R,) bool
    n_ring : int
    """

    poses: FloatArray
    vertex: IntArray
    a: IntArray
    b: IntArray
    dh: FloatArray
    length: FloatArray
    ring: FloatArray
    ring_ptr: IntArray
    ring_ok: np.ndarray
    n_ring: int

    vertex_xy: FloatArray = None
    #: A disc's static clearances of the roadmap's vertices (None for a box or footprint):
    #: the one table every query's connections share (:func:`gfuzzy.timespace.roadgraph.vertex_clearances`,
    #: which :func:`gfuzzy.timespace.unilanes.lanes` fills); the ends join only those vertices.
    clearance: FloatArray = None
    #: The roadmap's vertices, the first of ``vertex_xy``; the query ends join only these
    #: (a disc's turn points after them, :func:`gfuzzy.timespace.unilanes._turn_points`,
    #: among an end's nearest took the place of the vertices that lead on); None: all of
    #: ``vertex_xy`` (0 would let the ends join nothing).
    roadmap_vertices: int | None = None

    def copies_at(self, v: int) -> IntArray:
        lo, hi = np.searchsorted(self.vertex, [v, v + 1])
        return np.arange(lo, hi)


@dataclass
class UnicycleGraph:
    """A query's graph: the search's :class:`SpaceTimeGraph` and what the planner reports.

    Attributes
    ----------
    graph : SpaceTimeGraph
    s_id, g_id : int
    roadmap_distance : float
        Shortest static start-goal time on this graph times vmax (metres at vmax: lanes'
        lengths plus turns' ``|dh| vmax / turn_rate``); inf when not connected.
    exact_windows : callable or None
        A splice ``exact="later"``'s: the exact steps from the start to every point
        (``graph.from_start`` is None until then: 0 bounds them).
    """

    graph: SpaceTimeGraph
    s_id: int
    g_id: int
    roadmap_distance: float
    exact_windows: object = None


def _base(roadmap, geometry, stretch: float, vmax: float, step_len: float, deadline: float = math.inf,
          extra=None) -> _Base:  # fmt: skip
    """The copies, lanes and turns of the roadmap, cached per (robot, stretch); OutOfTime
    past ``deadline`` (:func:`gfuzzy.timespace.unilanes.on_time`). ``extra``: a repair's
    :class:`gfuzzy.timespace.unirepair.Chains` added (not cached: the repair keeps it)."""
    robot = geometry.robot
    rate = robot.turn_rate
    key = ("unicycle-base", geometry.scene.static_hash, float(geometry.keep), float(stretch), robot.shape,
           robot.size, bool(robot.reverse), float(rate), float(vmax), float(step_len))  # fmt: skip
    hit = roadmap._derived.get(key) if extra is None else None
    if hit is not None:
        return hit
    ln = lanes(roadmap, geometry, stretch, deadline)
    xy, e, lane_ok, ringless = ln.xy, ln.edges, ln.ok, None
    if extra is not None:
        ringless = len(xy)
        xy, e, lane_ok = np.vstack([xy, extra.xy]), np.vstack([e, extra.edges]), np.vstack([lane_ok, extra.ok])
    h_uv = np.arctan2(xy[e[:, 1], 1] - xy[e[:, 0], 1], xy[e[:, 1], 0] - xy[e[:, 0], 0])
    h_vu = wrap_angle(h_uv + math.pi)
    # copies: (vertex, heading) at both ends of every certified lane
    cv, ch = [], []
    for col, h in ((0, h_uv), (1, h_vu)):
        m = lane_ok[:, col]
        cv += [e[m, 0], e[m, 1]]
        ch += [h[m], h[m]]
    cv = np.concatenate(cv) if cv else np.zeros(0, dtype=np.int64)
    ch = np.asarray(wrap_angle(np.concatenate(ch)), dtype=float) if ch else np.zeros(0)
    order = np.lexsort((ch, cv))
    cv, ch = cv[order], ch[order]
    new = _merged(cv, ch)
    cv, ch = cv[new], ch[new]

    def copy_id(v, h):
        lo, hi = np.searchsorted(cv, v), np.searchsorted(cv, v, side="right")
        # the nearest heading among the vertex's copies (the copy made from this lane)
        seg = ch[lo:hi] if np.ndim(v) == 0 else None
        if seg is not None:
            return lo + int(np.argmin(np.abs(wrap_angle(seg - h))))
        out = np.empty(len(v), dtype=np.int64)
        for i in range(len(v)):
            s = ch[lo[i] : hi[i]]
            out[i] = lo[i] + int(np.argmin(np.abs(wrap_angle(s - h[i]))))
        return out

    pa, pb, pdh, plen = [], [], [], []
    lens = np.hypot(*(xy[e[:, 1]] - xy[e[:, 0]]).T)
    for col, h in ((0, h_uv), (1, h_vu)):
        m = lane_ok[:, col]
        tail, head = (e[m, 0], e[m, 1]) if col == 0 else (e[m, 1], e[m, 0])
        ct, chd = copy_id(tail, h[m]), copy_id(head, h[m])
        pa.append(ct)
        pb.append(chd)
        plen.append(lens[m])
        if robot.reverse:  # backwards along the same lane, the same heading
            pa.append(chd)
            pb.append(ct)
            plen.append(lens[m])
    pa = np.concatenate(pa) if pa else np.zeros(0, dtype=np.int64)
    pb = np.concatenate(pb) if pb else np.zeros(0, dtype=np.int64)
    plen = np.concatenate(plen) if plen else np.zeros(0)
    pdh = np.zeros(len(pa))
    # turns: a ring of headings per vertex, on a grid one turning step apart (see _Base)
    scale = vmax / rate
    n_ring = ring_points(vmax, rate, step_len)  # one ring past the bound: refused before any is made
    _too_many(len(np.unique(cv if ringless is None else cv[cv < ringless])) * n_ring)  # and all before they are
    memo = roadmap._derived.setdefault(("unicycle-ring-free",) + key[1:6] + (n_ring,), {})
    ring_ptr, ring_v, ring_h, ring_ok, ta, tb, tdh = _rings(geometry, xy, cv, ch, n_ring, deadline, ringless, memo)
    if extra is not None:
        chain_turns(extra.turns, copy_id, ch, ta, tb, tdh)
    tdh = np.asarray(tdh, dtype=float)
    return_ = _Base(
        poses=np.column_stack([xy[cv], ch]) if len(cv) else np.zeros((0, 3)),
        vertex=cv,
        a=np.concatenate([pa, np.asarray(ta, dtype=np.int64)]),
        b=np.concatenate([pb, np.asarray(tb, dtype=np.int64)]),
        dh=np.concatenate([pdh, tdh]),
        length=np.concatenate([plen, np.abs(tdh) * scale]),
        ring=np.column_stack([xy[ring_v], ring_h]) if len(ring_v) else np.zeros((0, 3)),
        ring_ptr=ring_ptr,
        ring_ok=ring_ok,
        n_ring=n_ring,
        vertex_xy=xy,
        clearance=vertex_clearances(roadmap, geometry) if robot.shape == "disc" else None,
        roadmap_vertices=len(roadmap.vertices),
    )
    if extra is None:
        roadmap._derived[key] = return_
    return return_


@dataclass(frozen=True)
class UnicyclePrepared:
    """:meth:`gfuzzy.planner.planner.Planner.prepare` for a unicycle: the goal's kept graph
    (:class:`UnicycleGoal`; the roadmap's copies, lanes and rings are cached on the roadmap).

    Attributes
    ----------
    goal_raw : (3,) float
    options : PlanOptions
    kept : UnicycleGoal
    """

    goal_raw: FloatArray
    options: object
    kept: object

    def splice(self, planner, start: FloatArray) -> UnicycleGraph:
        return self.kept.splice(planner, start)


def _merged(cv: IntArray, ch: FloatArray) -> np.ndarray:
    """Which copies (sorted by vertex, then heading) start a new copy: a heading within
    ``MERGE_HEADING`` of its group's *first* heading at the same vertex joins that group.

    Measured from the group's first heading, not the previous one: a chain of lanes each
    within the tolerance of the next (nearly collinear vertices) would otherwise gather
    headings farther apart than ``SAME_HEADING``, and a lane driven from one such copy to
    another would turn while moving (``gfuzzy check``: 1.4e-9 rad on an answer)."""
    new = np.ones(len(cv), dtype=bool)
    first_h, first_v = math.nan, -1
    for i, (v, h) in enumerate(zip(cv.tolist(), ch.tolist(), strict=True)):
        if v == first_v and h - first_h <= MERGE_HEADING:
            new[i] = False
        else:
            first_h, first_v = h, v
    return new


def _cut_pieces(nodes: FloatArray, A: IntArray, B: IntArray, DH: FloatArray, L: FloatArray, step_len: float,
                first: int):  # fmt: skip
    """Pieces cut into one-step points (:func:`gfuzzy.poses.split_counts`): (k, offs, p_of,
    j, inner poses, src, dst) with interior ids from ``first``. ``nodes``: the poses of the
    nodes, or a function of node ids giving them."""
    k = split_counts(L, step_len)
    n_int = k - 1
    _too_many(first + int(n_int.sum()))  # before the arrays of that many points are made
    offs = np.concatenate([[0], np.cumsum(n_int)]).astype(np.int64)
    p_of = np.repeat(np.arange(len(A)), n_int)
    j = np.arange(offs[-1]) - np.repeat(offs[:-1], n_int) + 1
    f = j / k[p_of]
    pa, pb = (nodes(A[p_of]), nodes(B[p_of])) if callable(nodes) else (nodes[A[p_of]], nodes[B[p_of]])
    inner = np.empty((len(p_of), 3))
    inner[:, :2] = pa[:, :2] + f[:, None] * (pb[:, :2] - pa[:, :2])
    inner[:, 2] = np.where(DH[p_of] != 0.0, wrap_angle(pa[:, 2] + f * DH[p_of]), pa[:, 2])
    ids = first + np.arange(offs[-1])
    is_first = np.zeros(offs[-1], dtype=bool)
    is_first[offs[:-1][n_int > 0]] = True
    is_last = np.zeros(offs[-1], dtype=bool)
    is_last[(offs[1:] - 1)[n_int > 0]] = True
    src = np.concatenate([np.where(is_first, A[p_of], ids - 1), ids[is_last], A[n_int == 0]])
    dst = np.concatenate([ids, B[p_of][is_last], B[n_int == 0]])
    return k, offs, p_of, j, inner, src, dst


def ring_points(vmax: float, rate: float, step_len: float) -> int:
    """The points of one turning ring (a full turn in place at ``rate`` rad/s, cut into steps of
    ``step_len`` at ``vmax``): TimeStepError past ``settings.MAX_POINTS``, for every query alike."""
    n_ring = int(split_counts(np.array([2 * math.pi * vmax / rate]), step_len)[0])
    _too_many(n_ring)
    return n_ring


def _too_many(total: int):
    from ..errors import TimeStepError
    from ..settings import MAX_POINTS

    if total > MAX_POINTS:
        raise TimeStepError(
            f"the time step is too fine for this roadmap: the unicycle's graph would have {total:,} points "
            f"(at most {MAX_POINTS:,}); use a larger dt"
        )


@dataclass
class UnicycleGoal:
    """A goal's graph kept for many starts (the one builder of a unicycle's query graph:
    :meth:`gfuzzy.planner.planner.Planner.plan`, ``plan_from`` and the navigator use it).

    Numbering: the base's copies, the goal's own nodes (the goal ``g_id`` first), the
    rings, then the pieces' interior points; a start adds its nodes and points after these
    (:meth:`splice`).

    Attributes
    ----------
    goal : (3,) float
    base : _Base
    poses : (N, 3) float
    indptr, neighbors : CSR one-step moves of the kept graph
    nn : int
        Nodes (copies, the goal's, rings) before the interior points.
    A, B : (P,) int ; k : (P,) int ; L : (P,) float
        The kept pieces at node level (ends, steps, metres at vmax).
    hop : (nn,) float
        Steps to the goal per node; ``heuristic`` (N,) per point.
    metres : (nn,) float
        Metres at vmax to the goal per node.
    groups : (G,) int
    p_of, j : (N - nn,) int
        Each interior point's piece and index along it.
    step_len, scale : float
    steps : scipy CSR (nn, nn)
        The kept pieces at node level weighted in steps (the starts' Dijkstra extends it).
    """

    goal: FloatArray
    base: _Base
    poses: FloatArray
    indptr: IntArray
    neighbors: IntArray
    nn: int
    A: IntArray
    B: IntArray
    k: IntArray
    L: FloatArray
    hop: FloatArray
    heuristic: FloatArray
    metres: FloatArray
    groups: IntArray
    p_of: IntArray
    j: IntArray
    g_id: int
    step_len: float
    scale: float
    connect_k: int
    steps: object = None
    #: Whether the ends tilt where they cannot turn round (:meth:`_Extras.along`).
    tilts: bool = False

    def splice(self, planner, start: FloatArray, exact: bool | str = True, fan_options=None, expired=None) -> UnicycleGraph:
        """This graph with ``start`` (``[x, y, heading]``, heading wrapped) joined in.

        ``exact``: the steps from the start to every point by Dijkstra (a fresh plan's
        safety windows); otherwise the straight distance over a step's length, a cheaper
        lower bound; ``"later"`` (the navigator's): none (0 bounds every point), and the
        Dijkstra in ``UnicycleGraph.exact_windows`` for when safety work is done (nobody
        near: none).
        ``fan_options`` (:class:`gfuzzy.timespace.drive.Fan`): also the two-leg motions of :func:`gfuzzy.timespace.drive.fan` (the navigator's),
        as many of them as are certified before ``expired()`` (a callable; None: all).
        """
        geo, robot = planner.geometry, planner.robot
        N = len(self.poses)
        ex = _Extras(self.base, geo, self.scale, N, ring_at=len(self.base.poses), tilts=self.tilts)
        ex.kept = self.poses
        s_id = ex.node(*start)
        ex.join(start, s_id, self.connect_k, True, robot.reverse)
        if fan_options is None:  # (the navigator's fan drives out along the heading itself)
            ex.along(start, s_id, self.connect_k, True, robot.reverse)
        sx, sy, sh = (float(v) for v in start)
        gx, gy, gh = (float(v) for v in self.goal)
        if math.hypot(gx - sx, gy - sy) <= 1e-9:  # the same place: a turn in place
            dh = pick_turn(geo, sx, sy, sh, gh)
            if dh == 0.0:  # the start is the goal: one step's stay (a turn of 0 is no piece, and
                ex.lane(s_id, self.g_id)  # the answer drove round a loop back to the start)
            elif dh is not None:
                ex.turn(s_id, self.g_id, dh)
        else:
            for back in (False, True) if robot.reverse else (False,):
                h = _drive(geo, robot, sx, sy, gx, gy, back)
                if h is None:
                    continue
                d1, d2 = lane_turn(geo, sx, sy, sh, h), lane_turn(geo, gx, gy, h, gh)
                if d1 is None or d2 is None:
                    continue
                a = s_id if d1 == 0.0 else ex.node(sx, sy, h)
                c = self.g_id if d2 == 0.0 else ex.node(gx, gy, h)
                ex.turn(s_id, a, d1)
                ex.turn(c, self.g_id, d2)
                ex.lane(a, c)
        if fan_options is not None:
            fan(ex, geo, start, s_id, self.goal, self.g_id, fan_options, expired)
        new = np.asarray(ex.poses, dtype=float).reshape(-1, 3)
        x = len(new)
        xp = np.asarray(ex.pieces, dtype=float).reshape(-1, 4)
        A, B = xp[:, 0].astype(np.int64), xp[:, 1].astype(np.int64)
        def pose_of(ids):
            out = np.empty((len(ids), 3))
            kept = ids < N
            out[kept] = self.poses[ids[kept]]
            out[~kept] = new[ids[~kept] - N]
            return out

        k, offs, p_of, j, inner, src, dst = _cut_pieces(pose_of, A, B, xp[:, 2], xp[:, 3], self.step_len, N + x)
        total = N + x + int(offs[-1])
        _too_many(total)
        # steps and metres to the goal of the new nodes: the kept ones bound them (a start's
        # pieces lead into the kept graph, never out of it and back)
        hop_x, met_x = new_to_goal(A, B, k, np.where(xp[:, 3] > 0, xp[:, 3], 0.0), N, x, self.hop, self.metres)
        hop = np.concatenate([np.full(N, np.inf), hop_x])
        hop[: self.nn] = self.hop
        met = np.concatenate([np.full(N, np.inf), met_x])
        rd = float(met[s_id])
        heur = np.concatenate([self.heuristic, hop[N:], hop[B[p_of]] + k[p_of] - j])
        poses = np.concatenate([self.poses, new, inner])
        # adjacency: every move of the start's is out of a new node or point (kept lists
        # stay as they are), so the new lists follow the kept ones
        order = np.argsort(src, kind="stable")
        nbrs = np.concatenate([self.neighbors, dst[order]])
        indptr = np.concatenate([self.indptr, self.indptr[-1] + np.cumsum(np.bincount(src - N, minlength=total - N))])
        later = from_start = None  # "later": no bound until it is asked for (0, a bound too, meanwhile)
        if exact is True:  # steps from the start: Dijkstra over the nodes (new ones renumbered after the kept)
            from_start = steps_from_start(self, A, B, k, p_of, j, x, total)
        elif exact == "later":
            def later():
                return steps_from_start(self, A, B, k, p_of, j, x, total)
        else:
            from_start = np.floor(np.hypot(*(poses[:, :2] - start[:2]).T) / self.step_len - 1e-9)
            from_start = np.maximum(from_start, 0.0)
        groups = np.concatenate([self.groups, N + np.arange(x + 1), N + x + offs[1:]])
        graph = SpaceTimeGraph(poses, indptr, nbrs, heur, groups=groups, from_start=from_start, kept=self)
        return UnicycleGraph(graph, s_id, self.g_id, rd, later)


@dataclass
class _BaseCut:
    """The base's pieces cut into steps, cached with it: nodes ``[copies][rings]`` (``nn0``),
    interior points numbered from ``nn0`` (a goal's nodes go between the two, shifting them),
    the moves sorted by source, and node-level graphs (forward in steps; backward in steps
    and in metres) as CSR arrays of ``nn0`` rows."""

    nodes: FloatArray
    A: IntArray
    B: IntArray
    k: IntArray
    L: FloatArray
    offs: IntArray
    p_of: IntArray
    j: IntArray
    inner: FloatArray
    src: IntArray
    dst: IntArray
    fwd: object
    back_steps: object
    back_metres: object


def _base_cut(base: _Base, step_len: float) -> _BaseCut:
    hit = getattr(base, "_cut", None)
    if hit is not None and hit[0] == step_len:
        return hit[1]
    K = len(base.poses)
    nodes = np.vstack([base.poses, base.ring])
    nn0 = len(nodes)
    A = np.where(base.a < 0, K - 1 - base.a, base.a)
    B = np.where(base.b < 0, K - 1 - base.b, base.b)
    k, offs, p_of, j, inner, src, dst = _cut_pieces(nodes, A, B, base.dh, base.length, step_len, nn0)
    order = np.argsort(src, kind="stable")
    L = np.where(base.length > 0, base.length, 0.0)
    cut = _BaseCut(nodes, A, B, k, L, offs, p_of, j, inner, src[order], dst[order],
                   matrix(A, B, k.astype(float), nn0), matrix(B, A, k.astype(float), nn0), matrix(B, A, L, nn0))  # fmt: skip
    base._cut = (step_len, cut)
    return cut


def prepare_goal(planner, goal: FloatArray, dt: float, vplan: float, connect_k: int = 10, stretch: float = 1.0,
                 tilts: bool = False, deadline: float = math.inf, base: _Base | None = None) -> UnicycleGoal:  # fmt: skip
    """The kept graph of ``goal`` (``[x, y, heading]``, heading wrapped): the base's copies,
    lanes and rings cut into steps (cached on the roadmap) with the goal joined in, and the
    static steps and metres to the goal.

    Numbering: the copies, the rings, the goal's nodes (the goal first), then the base's
    interior points and the goal's pieces' ones. OutOfTime past ``deadline`` while the
    base is built.
    """
    geo, robot, rm = planner.geometry, planner.robot, planner.roadmap
    step_len = vplan * dt
    base = base if base is not None else _base(rm, geo, stretch, robot.vmax, step_len, deadline)
    cut = _base_cut(base, step_len)
    scale = robot.vmax / robot.turn_rate
    nn0 = len(cut.nodes)
    ex = _Extras(base, geo, scale, nn0, ring_at=len(base.poses), tilts=tilts)
    g_id = ex.node(*goal)
    ex.join(goal, g_id, connect_k, False, robot.reverse)
    ex.along(goal, g_id, connect_k, False, robot.reverse)
    xg = len(ex.poses)
    nn = nn0 + xg
    nodes = np.vstack([cut.nodes, np.asarray(ex.poses, dtype=float).reshape(-1, 3)])
    xp = np.asarray(ex.pieces, dtype=float).reshape(-1, 4)
    Ag, Bg = xp[:, 0].astype(np.int64), xp[:, 1].astype(np.int64)
    I0 = int(cut.offs[-1])
    kg, offg, pg, jg, innerg, srcg, dstg = _cut_pieces(nodes, Ag, Bg, xp[:, 2], xp[:, 3], step_len, nn + I0)
    total = nn + I0 + int(offg[-1])
    _too_many(total)
    shift = np.int64(xg)
    s0 = np.where(cut.src >= nn0, cut.src + shift, cut.src)
    d0 = np.where(cut.dst >= nn0, cut.dst + shift, cut.dst)
    o = np.argsort(srcg, kind="stable")
    neighbors = np.insert(d0, np.searchsorted(s0, srcg[o], side="right"), dstg[o])
    indptr = np.zeros(total + 1, dtype=np.int64)
    np.cumsum(np.bincount(np.concatenate([s0, srcg]), minlength=total), out=indptr[1:])
    Lg = np.where(xp[:, 3] > 0, xp[:, 3], 0.0)
    hop = np.rint(dijkstra(with_rows(cut.back_steps, Bg, Ag, kg.astype(float), nn), g_id))
    metres = dijkstra(with_rows(cut.back_metres, Bg, Ag, Lg, nn), g_id)
    A, B = np.concatenate([cut.A, Ag]), np.concatenate([cut.B, Bg])
    k = np.concatenate([cut.k, kg])
    p_of = np.concatenate([cut.p_of, len(cut.A) + pg])
    j = np.concatenate([cut.j, jg])
    heur = np.concatenate([hop, hop[B[p_of]] + k[p_of] - j])
    rings = len(base.poses) + base.n_ring * np.arange(len(base.ring) // max(base.n_ring, 1))
    # a ring's points share a position: one group; the goal's nodes one each; pieces without
    # interior points add none
    offs = np.concatenate([cut.offs, I0 + offg[1:]])
    groups = np.concatenate([rings, nn0 + np.arange(xg + 1), nn + offs[np.r_[True, np.diff(offs) > 0]]])
    return UnicycleGoal(
        goal=np.asarray(goal, dtype=float), base=base, poses=np.vstack([nodes, cut.inner, innerg]), indptr=indptr,
        neighbors=neighbors, nn=nn, A=A, B=B, k=k, L=np.concatenate([cut.L, Lg]), hop=hop, heuristic=heur,
        metres=metres, groups=groups, p_of=p_of, j=j, g_id=g_id, step_len=step_len, scale=scale, connect_k=connect_k,
        steps=with_rows(cut.fwd, Ag, Bg, kg.astype(float), nn), tilts=tilts,
    )  # fmt: skip


def build_graph(planner, start: FloatArray, goal: FloatArray, dt: float, vplan: float,
                connect_k: int = 10, stretch: float = 1.0) -> UnicycleGraph:  # fmt: skip
    """The unicycle's space-time graph of a query (see the module docstring):
    :func:`prepare_goal` then :meth:`UnicycleGoal.splice` with exact safety windows.

    Parameters
    ----------
    planner : gfuzzy.planner.planner.Planner
    start, goal : (3,) float
        ``[x, y, heading]``, headings wrapped.
    dt : float
    vplan : float
        The speed the graph is cut for (``vmax * SPEED_SAFETY``).
    connect_k : int
        How many vertices the start and the goal try to join.
    stretch : float
        The disc's roadmap spanner (a box uses all its lanes).

    Returns
    -------
    UnicycleGraph
    """
    return prepare_goal(planner, goal, dt, vplan, connect_k, stretch).splice(planner, start)

