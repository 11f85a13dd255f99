"""A differential drive's query ends joined to its graph of heading copies
(:mod:`gfuzzy.timespace.unicycle`): a query's own nodes and pieces (:class:`_Extras`).

An end (the start, or the goal) joins through turn + straight + turn: it turns in place
towards a nearby vertex and drives to a new copy there, which joins its vertex's heading
neighbours (:meth:`_Extras.join`); where it cannot turn round in place, points on its own
heading line join it (:meth:`_Extras.along`), tilted by the largest free turn when that
line is blocked. :mod:`gfuzzy.timespace.unireach` runs the same joins on the lanes alone.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..poses import wrap_angle
from ..typed import FloatArray
from .drive import MERGE_HEADING, _xy_pose, lane_turn, turn_free
from .unilanes import _brackets, _same_interval

if TYPE_CHECKING:
    from .unicycle import _Base

__all__ = ["ALONG", "MIN_TILT", "TILT_DEPTH", "TILT_LINES", "TILT_SHARES"]

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


def _drive(geo, robot, ax, ay, bx, by, back: bool, ca=None, cb=None):
    """Heading for driving from a to b (backwards: facing away from b), or None when the
    lane is not free for the body held at it (``ca``, ``cb``: the ends' clearances, when
    known: a disc's do not depend on the heading)."""
    h = math.atan2(by - ay, bx - ax) + (math.pi if back else 0.0)
    if not geo.motion_free(_xy_pose(robot, ax, ay, h), _xy_pose(robot, bx, by, h), ca=ca, cb=cb):
        return None
    return h
