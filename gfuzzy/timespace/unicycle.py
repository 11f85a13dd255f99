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
from .drive import MERGE_HEADING, SAME_HEADING, _xy_pose, fan, lane_turn, pick_turn, turn_free
from .roadgraph import vertex_clearances
from .spacetime import SpaceTimeGraph
from .unilanes import LANE_NEIGHBOURS, _brackets, _rings, _same_interval, chain_turns, lanes
from .unipaths import dijkstra, matrix, new_to_goal, steps_from_start, with_rows

__all__ = ["UnicycleGraph", "UnicycleGoal", "UnicyclePrepared", "prepare_goal", "build_graph", "lanes", "LANE_NEIGHBOURS", "SAME_HEADING"]

#: Points on an end's own heading line (in circumradii from it) that join it to the roadmap
#: where it cannot turn round in place (:meth:`_Extras.along`).
ALONG = (0.5, 1.0, 2.0, 4.0)
#: Tilts (:meth:`_Extras.along`): the shares of the largest free turn taken, the smallest
#: tilt tried (rad), how many tilts in a row and how many heading lines per end at most.
#: Nearly all of the free turn: its heading's line is the farthest from the one the end is
#: stuck on (3/4 missed the L footprint's way into an L's inner corner, which needs 0.99 of
#: it at the goal, and arrived later on parking in a corner; two shares spend the lines
#: before the third tilt that parking nose up needs).
TILT_SHARES = (0.99,)
MIN_TILT = 1e-3
TILT_DEPTH = 3
TILT_LINES = 24


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


class _Extras:
    """A query's own nodes and pieces (the goal's when preparing, the start's per call).

    Node ids: base copies ``< n_copies``; new nodes from ``first``; ring point i is
    ``ring_at + i`` (or the placeholder ``-(1 + i)`` while the ring's place is not known).
    """

    def __init__(self, base: _Base, geometry, scale: float, first: int, ring_at: int | None = None,
                 tilts: bool = False):  # fmt: skip
        self.base, self.geometry, self.scale = base, geometry, scale
        self.tilts = tilts  # whether :meth:`along` tilts (see there)
        self.first = first
        self.ring_at = ring_at
        self.poses: list = []
        self.pieces: list = []  # (a, b, dh, length)
        self.kept: FloatArray | None = None  # the kept graph's poses, when splicing into one
        self.known = None  # v -> whether join need not try v (unireach's: its component is reached)

    def node(self, x: float, y: float, h: float) -> int:
        self.poses.append((float(x), float(y), float(wrap_angle(h))))
        return self.first + len(self.poses) - 1

    def ring(self, i: int) -> int:
        return -(1 + i) if self.ring_at is None else self.ring_at + i

    def pose(self, i: int):
        if i < 0:
            return self.base.ring[-i - 1]
        if i >= self.first:
            return self.poses[i - self.first]
        return self.base.poses[i] if self.kept is None else self.kept[i]

    def lane(self, a: int, b: int) -> None:
        pa, pb = self.pose(a), self.pose(b)
        self.pieces.append((a, b, 0.0, math.hypot(pb[0] - pa[0], pb[1] - pa[1])))

    def turn(self, a: int, b: int, dh: float) -> None:
        if dh != 0.0:
            self.pieces.append((a, b, float(dh), abs(dh) * self.scale))

    def copy_at(self, v: int, h: float, out: bool) -> int:
        """The copy of vertex v at heading h: the base's when it has one, else a new copy
        joined by turns to the two ring points around its heading: out to them (``out``:
        the start arrives there and turns on), else in from them (the goal leaves there)."""
        geo, base = self.geometry, self.base
        ids = base.copies_at(v)
        rel = (base.poses[ids, 2] - h) % (2 * math.pi)
        same = (rel <= MERGE_HEADING) | (rel >= 2 * math.pi - MERGE_HEADING)
        if same.any():
            return int(ids[np.nonzero(same)[0][0]])
        x, y = (float(c) for c in base.poses[ids[0], :2])
        c = self.node(x, y, h)
        r0 = int(base.ring_ptr[v])
        step_h = 2 * math.pi / base.n_ring
        for r, arc in _brackets(h, r0, base.n_ring, step_h):
            if base.ring_ok[r] and turn_free(geo, x, y, h, arc):
                if out:
                    self.turn(c, self.ring(r), arc)
                else:
                    self.turn(self.ring(r), c, -arc)
        # the vertex's copies next to h with no ring point between: directly (_same_interval)
        hs = np.append(base.poses[ids, 2], h)
        order = np.argsort(hs, kind="stable")
        for a, b, arc in _same_interval(hs[order], 0, len(hs), step_h):
            a, b = int(order[a]), int(order[b])
            if len(ids) not in (a, b) or not turn_free(geo, x, y, hs[a], arc):
                continue
            a, b = (c if a == len(ids) else int(ids[a])), (c if b == len(ids) else int(ids[b]))
            if (a == c) == out:
                self.turn(a, b, arc)
            else:
                self.turn(b, a, -arc)
        return c

    def along(self, pose: FloatArray, node: int, connect_k: int, outward: bool, reverse: bool) -> None:
        """Where the robot cannot turn round at ``pose`` (its circumscribed disc is not
        clear: nose to a wall, in a corridor, docked, parked beside a wall), join it through
        points on its own heading's line: straight lanes along the heading, forwards (and
        backwards with ``reverse``), to points ``ALONG`` circumradii away as far as they are
        free, each point joined to the roadmap as an end is (:meth:`join`). Without them
        such a start or goal joins only vertices that lie exactly on that line.

        Where a point of a line (or the end itself) cannot turn round either, the robot
        *tilts* there: it turns by ``TILT_SHARES`` of the largest turn its walls leave it each
        way (:func:`_free_arc`) and follows the new heading's line the same way, up to
        ``TILT_DEPTH`` tilts and ``TILT_LINES`` lines per end (breadth first): the chain of
        small turns that parks a box beside a wall with a few centimetres to spare, where
        no turn in place fits on the wall's line itself. Only with ``tilts`` (the planner
        asks for them when the query's graph does not join its ends without them: they cost
        up to a second per end, joining each line's points to the roadmap)."""
        geo = self.geometry
        if geo.robot.shape == "disc" or geo.sweep_bound(float(pose[0]), float(pose[1])) > 0:
            return
        todo, lines = [(np.asarray(pose, dtype=float), node, 0)], 0
        while todo and lines < TILT_LINES:
            here, n_here, depth = todo.pop(0)
            lines += 1
            points = self._line(here, n_here, connect_k, outward, reverse)
            if depth == 0:  # the end itself tilts too (a tilted line's start is its turn)
                points.insert(0, (here, n_here))
            if depth >= (TILT_DEPTH if self.tilts else 0):
                continue
            for q, n_q in points:
                if geo.sweep_bound(float(q[0]), float(q[1])) > 0:
                    continue  # turns round there: joined to the roadmap already
                todo += self._tilts(q, n_q, outward, depth + 1)

    def _line(self, pose: FloatArray, node: int, connect_k: int, outward: bool, reverse: bool) -> list:
        """The points of :meth:`along` on ``pose``'s heading line, joined: [(pose, node)]."""
        geo = self.geometry
        px, py, ph = (float(c) for c in pose)
        out = []
        for sign in (1.0, -1.0) if reverse else (1.0,):
            way = sign if outward else -sign  # a goal is arrived at: its forward lane comes from behind
            c, s = way * math.cos(ph), way * math.sin(ph)
            prev, qx, qy = node, px, py
            for d in ALONG:
                d *= geo.r
                nx, ny = px + d * c, py + d * s
                if not geo.motion_free([qx, qy, ph], [nx, ny, ph]):
                    break
                q = self.node(nx, ny, ph)
                if outward:
                    self.lane(prev, q)
                else:
                    self.lane(q, prev)
                self.join(np.array([nx, ny, ph]), q, connect_k, outward, reverse)
                out.append((np.array([nx, ny, ph]), q))
                prev, qx, qy = q, nx, ny
        return out

    def _tilts(self, pose: FloatArray, node: int, outward: bool, depth: int) -> list:
        """New nodes at ``pose``'s place, turned each way by ``TILT_SHARES`` of the free arc
        (at least ``MIN_TILT``), joined by the turn: [(pose, node, depth)]."""
        geo = self.geometry
        x, y, h = (float(c) for c in pose)
        out = []
        for side in (1.0, -1.0):
            arc = _free_arc(geo, x, y, h, side)
            for share in TILT_SHARES:
                dh = side * share * arc
                if abs(dh) < MIN_TILT or not turn_free(geo, x, y, h, dh, swept=False):
                    continue
                t = self.node(x, y, h + dh)
                if outward:
                    self.turn(node, t, dh)
                else:  # arrives tilted, then turns to the heading it goes on with
                    self.turn(t, node, -dh)
                out.append((np.array([x, y, float(wrap_angle(h + dh))]), t, depth))
        return out

    def join(self, pose: FloatArray, node: int, connect_k: int, outward: bool, reverse: bool) -> None:
        """Join ``node`` (at ``pose``) to its nearest vertices: turn + straight to a copy
        there (``outward``: the start), or a copy there + straight + turn (the goal)."""
        geo, base = self.geometry, self.base
        robot = geo.robot
        px, py, ph = (float(c) for c in pose)
        xy = base.vertex_xy
        has = np.zeros(len(xy), dtype=bool)
        has[base.vertex] = True
        if base.roadmap_vertices is not None:
            has[base.roadmap_vertices :] = False
        d = np.hypot(xy[:, 0] - px, xy[:, 1] - py)
        order = np.argsort(d, kind="stable")
        order = order[has[order] & (d[order] > 1e-9)]
        tried = joined = 0
        disc = robot.shape == "disc"
        c_p = geo.clearance1([px, py]) if disc else None
        table = base.clearance  # the roadmap vertices' (shared by every query)
        for v in order[: 4 * max(connect_k, 1)].tolist():
            if tried >= connect_k and joined:
                break
            if self.known is not None and self.known(v):
                continue
            tried += 1
            vx, vy = float(xy[v, 0]), float(xy[v, 1])
            c_v = None
            if disc:
                c_v = table[v]
                if c_v != c_v:  # NaN: not computed yet
                    c_v = table[v] = geo.clearance1([vx, vy])
            for back in (False, True) if reverse else (False,):
                ax, ay, bx, by = (px, py, vx, vy) if outward else (vx, vy, px, py)
                ca, cb = (c_p, c_v) if outward else (c_v, c_p)
                h = _drive(geo, robot, ax, ay, bx, by, back, ca, cb)
                if h is None:
                    continue
                dh = lane_turn(geo, px, py, ph, h) if outward else lane_turn(geo, px, py, h, ph)
                if dh is None:
                    continue
                here = node
                if dh != 0.0:
                    here = self.node(px, py, h)
                    if outward:
                        self.turn(node, here, dh)
                    else:
                        self.turn(here, node, dh)
                c = self.copy_at(v, h, outward)
                if outward:
                    self.lane(here, c)
                else:
                    self.lane(c, here)
                joined += 1


def _free_arc(geo, x: float, y: float, h: float, side: float, steps: int = 12) -> float:
    """The largest turn in place at (x, y) from ``h`` towards ``side`` (+1 counter-clockwise)
    whose sweep is free, up to pi, by bisection to pi / 2**steps (0: none)."""
    if turn_free(geo, x, y, h, side * math.pi, swept=False):
        return math.pi
    lo, hi = 0.0, math.pi
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if turn_free(geo, x, y, h, side * mid, swept=False):
            lo = mid
        else:
            hi = mid
    return lo


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


def _drive(geo, robot, ax, ay, bx, by, back: bool, ca=None, cb=None):
    """Heading for driving from a to b (backwards: facing away from b), or None when the
    lane is not free for the body held at it (``ca``, ``cb``: the ends' clearances, when
    known: a disc's do not depend on the heading)."""
    h = math.atan2(by - ay, bx - ax) + (math.pi if back else 0.0)
    if not geo.motion_free(_xy_pose(robot, ax, ay, h), _xy_pose(robot, bx, by, h), ca=ca, cb=cb):
        return None
    return h


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
            if dh is not None:
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

