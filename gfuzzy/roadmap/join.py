"""Join the components of a box or footprint robot's roadmap (SE(2)).

A disc robot's roadmap is repaired through its exactly computed free space
(:func:`gfuzzy.roadmap.freespace.repair`); a rigid robot's free space is three-dimensional and
is not computed. PRM and the passage sampler can leave its roadmap in pieces although the
robot fits between them (a door with a few centimetres to spare, a bent corridor it passes
only turned). :func:`join_components` spends a bounded number of collision checks joining
them: first the closest vertex pairs of two components, directly and by a turn in place and a
translation (the motions a rigid robot fits through a door with); then the doors between
them (gaps between obstacle corners, a map's cells' outer corners included: the body
centred in the gap at the headings it is narrowest across it, :func:`door_headings`,
reached along the gap's axis; a differential drive only along the axis, crossing both
ways when its body turned by pi is another); then a bidirectional RRT
(RRT-Connect, Kuffner and LaValle 2000) between a component and the rest of the roadmap.
Every pose is checked and every motion certified by
:meth:`gfuzzy.collision.geometry.StaticGeometry.motion_free`, as the roadmap's other edges;
the poses of a found path become vertices, its motions edges. The join gives up when its
budget (``CHECKS_PER_VERTEX`` checks per roadmap vertex) is spent; on a piece when its share
is (doors and RRT: ``PIECE_CHECKS_PER_VERTEX`` per vertex of the piece at most, so a stray
vertex in a pocket does not take the budget); and at once, without a check, on a component
proven apart: a disc inside the body that cannot pass between the pieces
(:func:`_disc_regions`; a sealed room). Seeded: the same roadmap and seed give the
same join.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from ..collision.exact import TOUCH_TOL
from ..collision.geometry import StaticGeometry, metric_distance
from ..typed import FloatArray, IntArray
from .freespace import TOUCHING, blocked_points, disc_centres, inscribed_free_space
from .passage import centre_bridge, lateral_middle

__all__ = ["Join", "join_components", "count_components", "component_labels"]

log = logging.getLogger(__name__)

#: Collision checks (pose validity and certified motions) the join may spend per roadmap vertex.
CHECKS_PER_VERTEX = 10
#: Closest cross-component vertex pairs tried directly, per component, before the RRT.
CLOSEST_PAIRS = 12
#: RRT step, in robot spans (twice the circumradius), in the contract's metric.
STEP = 0.5
#: Share of RRT samples drawn in the box around the two trees' closest vertices.
FOCUS = 0.6
#: Doors (gaps between obstacle corners less than a robot span apart) tried per component,
#: nearest the two pieces first, before the RRT.
DOORS = 8
#: Checks a piece may spend after its closest pairs (its doors, then RRT-Connect) per vertex
#: of its own, at most: a stray vertex or two that PRM left in a pocket the robot cannot leave
#: (among a table's legs) gets a small share, a room behind a door a large one.
PIECE_CHECKS_PER_VERTEX = 200
#: Headings tried per door, the body's narrowest across the door first (:func:`door_headings`).
DOOR_HEADINGS = 4


@dataclass
class Join:
    """What :func:`join_components` did.

    Attributes
    ----------
    vertices : (V, 3) float
    edges : (E, 2) int
        The roadmap's, then the added ones (``edges[:, 0] < edges[:, 1]``).
    before, after : int
        Connected components before and after.
    added_vertices, added_edges : int
    checks, budget : int
        Collision checks spent, and allowed.
    apart : int
        Components proven apart from the rest (no region of the inscribed disc's free space
        shared: :func:`_disc_regions`), given up without a check.
    touching : int
        Components of vertices touching an obstacle, left after the direct joins (a turn
        from contact is never certified).
    """

    vertices: FloatArray
    edges: IntArray
    before: int
    after: int
    added_vertices: int = 0
    added_edges: int = 0
    checks: int = 0
    budget: int = 0
    apart: int = 0
    touching: int = 0

    def to_dict(self) -> dict:
        """The report kept in a roadmap file's ``info.join`` (with ``seconds``)."""
        return {
            "components_before": self.before,
            "components_after": self.after,
            "added_vertices": self.added_vertices,
            "added_edges": self.added_edges,
            "checks": self.checks,
            "budget": self.budget,
            "components_apart": self.apart,
            "components_touching": self.touching,
        }


def component_labels(n: int, edges) -> np.ndarray:
    """A component label per vertex (the smallest vertex index of its component)."""
    parent = list(range(n))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in np.asarray(edges, dtype=np.int64).reshape(-1, 2).tolist():
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    return np.array([find(i) for i in range(n)], dtype=np.int64)


def count_components(n: int, edges) -> int:
    """Connected components of a graph of ``n`` vertices."""
    return int(len(np.unique(component_labels(n, edges)))) if n else 0


def _wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


class _Search:
    """The join's state: the growing vertex list, new edges, the checks spent."""

    def __init__(self, geometry: StaticGeometry, vertices: FloatArray, edges: IntArray, budget: int, seed: int):
        self.geometry = geometry
        self.r = geometry.scene.robot.circumradius
        self.step = STEP * 2.0 * self.r
        self.verts = [np.asarray(v, dtype=float) for v in vertices]
        self.edges: list = []
        self.labels = component_labels(len(vertices), edges)
        self.budget = budget
        self.limit = budget  # checks allowed for the piece being joined (:func:`_join_one`)
        self.checks = 0
        self.apart = 0  # components proven apart by the inscribed disc's free space
        self.stuck = 0  # components of vertices touching obstacles, left after the direct joins
        self.rng = np.random.default_rng([int(seed), 0x6A6F696E])  # "join": apart from PRM's draws
        self.bounds = geometry.scene.bounds
        self.blocked = blocked_points(geometry.scene)
        robot = geometry.scene.robot
        self.y_mid = lateral_middle(robot)
        self.body = robot.corners(np.zeros(3))[0]  # the outline's vertices in the robot's frame
        self.drive = robot.unicycle  # a differential drive crosses a door along its heading
        self.both_ways = self.drive and not robot.half_turn_symmetric
        self.door_list: FloatArray | None = None  # computed when first needed
        self.region = _disc_regions(geometry.scene, vertices)

    def rest(self, comp: int) -> np.ndarray:
        """The vertices component ``comp`` may be joined to: the others in its regions of the
        inscribed disc's free space (all the others without it)."""
        out = self.labels != comp
        if self.region is not None:
            out &= np.isin(self.region, self.region[self.labels == comp])
        return out

    def touching(self, comp: int) -> bool:
        """True when every vertex of component ``comp`` touches an obstacle (a stray at
        contact: only its translations are certified, :meth:`direct` tried them)."""
        inside = np.nonzero(self.labels == comp)[0]
        return all(self.geometry.clearance1(self.verts[i]) < TOUCHING for i in inside)

    def separated(self, comp: int) -> bool:
        """True when no other vertex shares a region with component ``comp``: proven apart."""
        return self.region is not None and not self.rest(comp).any()

    @property
    def spent(self) -> bool:
        return self.checks >= self.limit

    def valid(self, q) -> bool:
        """Pose validity, one check of the budget (False, unchecked, once it is spent)."""
        if self.spent:
            return False
        self.checks += 1
        return bool(self.geometry.is_valid(q))

    def valid_touching(self, q) -> bool:
        """:meth:`valid`, but a pose FCL's collision test finds touching an obstacle is
        measured exactly (:meth:`StaticGeometry.clearance1`: 0 at contact, as ``gfuzzy check``
        measures it) and valid when it only touches: a body exactly as wide as a door
        touches both jambs in it. One check of the budget."""
        if self.spent:
            return False
        self.checks += 1
        return bool(self.geometry.is_valid(q) or self.geometry.clearance1(q) >= 0.0)

    def free(self, a, b) -> bool:
        """A certified straight motion, one check of the budget (False once it is spent)."""
        if self.spent:
            return False
        self.checks += 1
        return bool(self.geometry.motion_free(a, b))

    def add_path(self, poses: list, ia: int, ib: int) -> None:
        """Add the inner ``poses`` of a certified path from vertex ``ia`` to vertex ``ib``."""
        ids = [ia]
        for p in poses:
            self.verts.append(np.asarray(p, dtype=float))
            ids.append(len(self.verts) - 1)
        ids.append(ib)
        for u, w in zip(ids[:-1], ids[1:], strict=True):
            self.edges.append((min(u, w), max(u, w)))
        la, lb = self.labels[ia], self.labels[ib]
        keep = min(la, lb)
        self.labels[self.labels == max(la, lb)] = keep
        self.labels = np.concatenate([self.labels, np.full(len(poses), keep, dtype=np.int64)])
        if self.region is not None:  # a free path: the inscribed disc stays in its region
            self.region = np.concatenate([self.region, np.full(len(poses), self.region[ia], dtype=np.int64)])

    # ----------------------------------------------------------------- direct joins

    def direct(self, a: int, b: int) -> bool:
        """Join vertices ``a`` and ``b``: straight, or turning in place at either end and
        translating at the other's heading; True when joined (the path added)."""
        pa, pb = self.verts[a], self.verts[b]
        if self.free(pa, pb):
            self.add_path([], a, b)
            return True
        if pa[2] == pb[2] or (pa[0] == pb[0] and pa[1] == pb[1]):
            return False  # a translation or a turn: no other way with one turn
        for mid in (np.array([pa[0], pa[1], pb[2]]), np.array([pb[0], pb[1], pa[2]])):
            if self.valid(mid) and self.free(pa, mid) and self.free(mid, pb):
                self.add_path([mid], a, b)
                return True
        return False

    def closest_pairs(self, comp: int, limit: int) -> list:
        """The ``limit`` closest (metric) vertex pairs between component ``comp`` and the rest."""
        V = np.array(self.verts)
        inside = np.nonzero(self.labels == comp)[0]
        outside = np.nonzero(self.rest(comp))[0]
        if not len(inside) or not len(outside):
            return []
        k = min(limit, len(outside))  # each inside vertex's k nearest outside in the plane
        a, b = [], []
        for lo in range(0, len(inside), _CHUNK):
            rows = inside[lo : lo + _CHUNK]
            d = _xy_distances(V[rows, :2], V[outside, :2])
            near = np.argsort(d, axis=1, kind="stable")[:, :k]
            a.append(np.repeat(rows, k))
            b.append(outside[near].reshape(-1))
        a, b = np.concatenate(a), np.concatenate(b)
        order = np.argsort(metric_distance(V[a], V[b], self.r), kind="stable")[:limit]
        return [(int(a[i]), int(b[i])) for i in order]

    # ----------------------------------------------------------------- RRT-Connect

    def _steer(self, a: FloatArray, q: FloatArray) -> FloatArray:
        d = float(metric_distance(a, q, self.r))
        if d <= self.step:
            return q.copy()
        t = self.step / d
        delta = q - a
        delta[2] = _wrap(delta[2])
        out = a + t * delta
        out[2] = _wrap(out[2])
        return out

    def _sample(self, focus: tuple) -> tuple[FloatArray, bool]:
        """A pose to grow towards, and whether it is a passage's (a bridge sample)."""
        xmin, ymin, xmax, ymax = self.bounds
        if self.rng.random() < FOCUS:
            lo, hi = focus
            if self.rng.random() < 0.5:
                q = self._bridge(lo, hi)
                if q is not None:
                    return q, True
            x, y = self.rng.uniform(lo, hi)
        else:
            x, y = self.rng.uniform(xmin, xmax), self.rng.uniform(ymin, ymax)
        return np.array([x, y, self.rng.uniform(-math.pi, math.pi)]), False

    def _bridge(self, lo: FloatArray, hi: FloatArray) -> FloatArray | None:
        """A pose in a passage between ``lo`` and ``hi``: a bridge test (two blocked points,
        the middle free) centred across the passage (:func:`gfuzzy.roadmap.passage.centre_bridge`)."""
        a = self.rng.uniform(lo, hi, (16, 2))
        b = a + self.rng.normal(0.0, self.r, (16, 2))
        ok = self.blocked(a) & self.blocked(b)
        ok[ok] = ~self.blocked(0.5 * (a[ok] + b[ok]))
        if not ok.any():
            return None
        i = int(np.argmax(ok))
        d = b[i] - a[i]
        heading = math.atan2(d[1], d[0]) + 0.5 * math.pi + (math.pi if self.rng.random() < 0.5 else 0.0)
        return centre_bridge(self.blocked, 0.5 * (a[i] + b[i]), _wrap(heading), 2.0 * self.r, self.y_mid)

    def doors(self, comp: int, limit: int) -> bool:
        """Join component ``comp`` to the rest through one of the ``limit`` doors nearest
        both (:func:`_doors`): the body centred in the door at one of its headings that may
        cross it (:func:`door_headings`), reached from each side by a turn in place and
        translations along the door's axis (:meth:`_reach`)."""
        if self.door_list is None:
            self.door_list = _doors(self.geometry.scene, self.blocked, 2.0 * self.r)
        if not len(self.door_list):
            return False
        V = np.array(self.verts)
        trees = _Tree(V, self.labels == comp), _Tree(V, self.rest(comp))
        mids = self.door_list[:, :2]
        score = sum(_nearest_distance(mids, t.arr[:, :2]) for t in trees)
        for i in np.argsort(score, kind="stable")[:limit].tolist():
            m, axis, gap = self.door_list[i, :2], float(self.door_list[i, 2]), float(self.door_list[i, 3])
            for h in door_headings(self.body, axis, gap, DOOR_HEADINGS, self.drive):
                if self.spent:
                    return False
                if self._through(trees, self._in_door(m, h, axis), axis):
                    if self.both_ways and abs(math.sin(h - axis)) < 1e-9:
                        self._other_way(m, h, axis)
                    return True
        return False

    def _through(self, trees: tuple, q: FloatArray, axis: float) -> bool:
        """Add a path from ``trees[0]`` through the door pose ``q`` to ``trees[1]`` (:meth:`_reach`
        from each); False, nothing added, when ``q`` is not valid or a tree does not reach it."""
        if not self.valid_touching(q):
            return False
        a = self._reach(trees[0], q, axis)
        b = self._reach(trees[1], q, axis) if a is not None else None
        if b is None:
            return False
        self._add_trees(trees[0], a, trees[1], b)
        return True

    def _other_way(self, m: FloatArray, heading: float, axis: float) -> None:
        """After a differential drive crossed the door at ``m`` along its ``axis``: the crossing
        facing the other way, when the body turned by pi is another (its middle line is
        elsewhere, and without ``reverse`` it drives through only forwards), joined to the
        vertices on either side of the door a circumradius or more from it (as the passage
        sampler's chains both ways; the first crossing's pose in the door cannot turn)."""
        V = np.array(self.verts)
        side = (V[:, :2] - m) @ np.array([math.cos(axis), math.sin(axis)])
        trees = _Tree(V, side <= -self.r), _Tree(V, side >= self.r)
        self._through(trees, self._in_door(m, _wrap(heading + math.pi), axis), axis)

    def _in_door(self, m: FloatArray, heading: float, axis: float) -> FloatArray:
        """The pose at ``heading`` whose body's middle (of its extents along the door's
        ``axis`` and across it) is the point ``m``."""
        ox, oy = _door_middle(self.body, heading, axis)
        c, s = math.cos(heading), math.sin(heading)
        return np.array([m[0] - c * ox + s * oy, m[1] - s * ox - c * oy, heading])

    def rrt(self, comp: int) -> bool:
        """Grow a tree from component ``comp``'s vertices and one from the rest of the
        roadmap towards each other (RRT-Connect) until the checks allowed are spent."""
        V = np.array(self.verts)
        trees = [_Tree(V, self.labels == comp), _Tree(V, self.rest(comp))]
        pa, pb = self.closest_pairs(comp, 1)[0]
        lo = np.minimum(V[pa, :2], V[pb, :2]) - 2 * self.r
        hi = np.maximum(V[pa, :2], V[pb, :2]) + 2 * self.r
        xmin, ymin, xmax, ymax = self.bounds
        focus = (np.maximum(lo, [xmin, ymin]), np.minimum(hi, [xmax, ymax]))
        while not self.spent:
            grow, other = trees
            q, passage = self._sample(focus)
            if passage and self.valid(q):  # in a door: both trees straight to it
                a = self._reach(grow, q)
                b = self._reach(other, q) if a is not None else None
                if b is not None:
                    self._add_trees(grow, a, other, b)
                    return True
                continue
            new = self._extend(grow, q)
            if new is not None:
                reached = self._connect(other, grow.poses[new])
                if reached is not None:
                    self._add_trees(grow, new, other, reached)
                    return True
            trees.reverse()
        return False

    def _extend(self, tree: _Tree, q: FloatArray) -> int | None:
        near = tree.nearest(q, self.r)
        new = self._steer(tree.poses[near], q)
        if self.valid(new) and self.free(tree.poses[near], new):
            return tree.add(new, near)
        return None

    def _reach(self, tree: _Tree, q: FloatArray, axis: float | None = None) -> int | None:
        """Join a passage pose ``q`` to ``tree`` along the passage: from one of its 3 nearest
        nodes (in the plane), a turn in place to ``q``'s heading, a translation to a pose on
        the passage's ``axis`` (default ``q``'s heading; on the node's side), a translation to
        ``q``; the node of ``q`` added, or None. The pose on the axis is first the one abreast
        of the node, when the node is less than a span from ``q`` along the axis, then the one
        a span before ``q``: from a node beside the door, that one lies beyond the node, and
        the path went out there and back (a mover's lane through the door held such a
        crossing too long). A differential drive keeps the span: its lanes turn at their
        ends, and an off-centre drive's crossing from the pose abreast was not found
        (tests/test_join.py, the crossing both ways, seed 4)."""
        axis = float(q[2]) if axis is None else axis
        d = np.array([math.cos(axis), math.sin(axis), 0.0])
        span = 2.0 * self.r
        for near in tree.nearest_xy(q, 3):
            p = tree.poses[near]
            along = float(np.dot(p[:2] - q[:2], d[:2]))
            turned = np.array([p[0], p[1], q[2]])
            backs = (span,) if self.drive else (min(abs(along), span), span)  # abreast, then a span
            for back in dict.fromkeys(backs):
                legs = self._legs(p, [turned, q + math.copysign(back, along) * d, q])
                if legs is not None:
                    node = near
                    for leg in legs:
                        node = tree.add(leg, node)
                    return node
        return None

    def _legs(self, p: FloatArray, poses: list) -> list | None:
        """``poses`` (those equal to the one before left out) if each is valid and the
        motions from ``p`` through them certified, else None."""
        legs, at = [], p
        for k, leg in enumerate(poses):
            if np.array_equal(leg, at):
                continue
            valid = self.valid_touching if k == len(poses) - 1 else self.valid
            if not (valid(leg) and self.free(at, leg)):
                return None
            legs.append(leg)
            at = leg
        return legs

    def _connect(self, tree: _Tree, q: FloatArray) -> int | None:
        """Extend ``tree`` towards ``q`` until it reaches it (the node's index) or is blocked."""
        near = tree.nearest(q, self.r)
        while not self.spent:
            new = self._steer(tree.poses[near], q)
            if not (self.valid(new) and self.free(tree.poses[near], new)):
                return None
            near = tree.add(new, near)
            if np.array_equal(new, q):
                return near
        return None

    def _add_trees(self, grow: _Tree, new: int, other: _Tree, reached: int) -> None:
        """Add the path from ``grow``'s root through ``new`` = ``reached`` to ``other``'s root."""
        first = grow.branch(new)  # root (a roadmap vertex) ... new
        second = other.branch(reached)[::-1]  # reached (the same pose as new) ... root
        ia, ib = grow.vertex[first[0]], other.vertex[second[-1]]
        poses = [grow.poses[i] for i in first[1:]] + [other.poses[i] for i in second[1:-1]]
        self.add_path(poses, ia, ib)


class _Tree:
    """An RRT rooted at many roadmap vertices (a component, or the rest of the roadmap)."""

    def __init__(self, V: FloatArray, mask: np.ndarray):
        idx = np.nonzero(mask)[0]
        self.poses = [V[i] for i in idx]
        self.parent = [-1] * len(idx)
        self.vertex = {k: int(i) for k, i in enumerate(idx)}  # node -> roadmap vertex (roots)
        self._arr = np.array(self.poses).reshape(-1, 3)  # room to grow: rows beyond the nodes unused

    @property
    def arr(self) -> FloatArray:
        return self._arr[: len(self.poses)]

    def nearest(self, q: FloatArray, r: float) -> int:
        return int(np.argmin(metric_distance(self.arr, q[None, :], r)))

    def nearest_xy(self, q: FloatArray, k: int) -> list:
        arr = self.arr
        d = np.hypot(arr[:, 0] - q[0], arr[:, 1] - q[1])
        return [int(i) for i in np.argsort(d, kind="stable")[:k]]

    def add(self, q: FloatArray, parent: int) -> int:
        n = len(self.poses)
        if n == len(self._arr):
            self._arr = np.concatenate([self._arr, np.empty((max(n, 16), 3))])
        self._arr[n] = q
        self.poses.append(q)
        self.parent.append(parent)
        return n

    def branch(self, node: int) -> list:
        """Nodes from the root down to ``node``."""
        out = [node]
        while self.parent[out[-1]] >= 0:
            out.append(self.parent[out[-1]])
        return out[::-1]


def join_components(
    geometry: StaticGeometry, vertices: FloatArray, edges: IntArray, seed: int, budget: int | None = None
) -> Join:
    """Join the components of an SE(2) roadmap within a budget of collision checks.

    Components are taken largest first after the largest; each is joined to the rest of the
    roadmap by its ``CLOSEST_PAIRS`` closest vertex pairs (straight, or a turn in place and a
    translation), then through doors and by RRT-Connect for an equal share of what is left of
    the budget, at most ``PIECE_CHECKS_PER_VERTEX`` per vertex of the piece.

    Parameters
    ----------
    geometry : StaticGeometry
        Of the box or footprint robot's scene.
    vertices : (V, 3) float
    edges : (E, 2) int
    seed : int
        The roadmap's seed (the RRT's draws).
    budget : int, optional
        Collision checks to spend at most (default ``CHECKS_PER_VERTEX`` per vertex).

    Returns
    -------
    Join
    """
    vertices = np.asarray(vertices, dtype=float).reshape(-1, 3)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    budget = CHECKS_PER_VERTEX * len(vertices) if budget is None else int(budget)
    s = _Search(geometry, vertices, edges, budget, seed)
    before = len(np.unique(s.labels))
    comps = _by_size(s.labels)[1:]
    for k, comp in enumerate(comps):
        if s.spent:
            break
        comp = int(s.labels[comp])  # its label now (an earlier join may have relabelled it)
        if len(np.unique(s.labels)) == 1:
            break
        if not _join_one(s, comp, len(comps) - k):
            log.debug("join: component of vertex %d not joined (%d of %d checks)", comp, s.checks, budget)
    added = np.array(s.edges, dtype=np.int64).reshape(-1, 2)
    out_edges = np.vstack([edges, added])  # joined ends lay in two components: no duplicates
    return Join(
        np.array(s.verts, dtype=float).reshape(-1, 3),
        out_edges,
        before,
        len(np.unique(s.labels)),
        len(s.verts) - len(vertices),
        len(out_edges) - len(edges),
        s.checks,
        budget,
        s.apart,
        s.stuck,
    )


def _by_size(labels: np.ndarray) -> list:
    """A vertex of each component, largest component first (ties: smallest label)."""
    ids, counts = np.unique(labels, return_counts=True)
    order = np.lexsort((ids, -counts))
    return [int(ids[i]) for i in order]


def _join_one(s: _Search, comp: int, left: int) -> bool:
    """Join component ``comp`` to the rest: closest pairs, then doors and RRT-Connect with a
    ``1/left`` share of the remaining budget, at most ``PIECE_CHECKS_PER_VERTEX`` per vertex
    of the piece; nothing spent on a component proven apart."""
    if s.separated(comp):
        s.apart += 1
        return False
    for a, b in s.closest_pairs(comp, CLOSEST_PAIRS):
        if s.spent:
            return False
        if s.labels[a] != s.labels[b] and s.direct(a, b):
            return True
    if s.touching(comp):  # no turn leaves it, and the RRT's steps turn
        s.stuck += 1
        return False
    size = int(np.count_nonzero(s.labels == comp))
    share = min((s.budget - s.checks) // max(left, 1), PIECE_CHECKS_PER_VERTEX * size)
    s.limit = s.checks + share
    try:
        return share > 0 and (s.doors(comp, DOORS) or s.rrt(comp))
    finally:
        s.limit = s.budget


def repair_roadmap(geometry: StaticGeometry, fs, vertices: FloatArray, edges: IntArray, k: int):
    """(vertices, edges, the repair's report) after :func:`gfuzzy.roadmap.freespace.repair`, or
    as given with an empty report when ``fs`` is None (not a disc, or no repair)."""
    if fs is None:
        return vertices, edges, {}
    from .freespace import repair

    t = time.perf_counter()
    rep = repair(geometry, fs, vertices, edges, k)
    if rep.added_vertices:
        log.info("free-space repair: %d components joined, %d vertices added", rep.joined, rep.added_vertices)
    return rep.vertices, rep.edges, {**rep.to_dict(), "seconds": round(time.perf_counter() - t, 4)}


def join_roadmap(geometry: StaticGeometry, vertices: FloatArray, edges: IntArray, options):
    """(vertices, edges, the join's report) after :func:`join_components` for a box or
    footprint robot's roadmap in pieces with ``options.join``; else as given with an empty
    report (nothing written)."""
    if not options.join or vertices.shape[1] != 3 or count_components(len(vertices), edges) < 2:
        return vertices, edges, {}
    t = time.perf_counter()
    j = join_components(geometry, vertices, edges, options.seed)
    log.info(
        "component join: %d -> %d components, %d vertices and %d edges added, %d of %d checks",
        j.before, j.after, j.added_vertices, j.added_edges, j.checks, j.budget,
    )
    return j.vertices, j.edges, {**j.to_dict(), "seconds": round(time.perf_counter() - t, 4)}


#: Rows of a distance matrix computed at once (memory: this many times the other side).
_CHUNK = 256
#: Point pairs up to which nearest distances are computed by brute force, not a k-d tree.
_BRUTE = 4_000_000


def _xy_distances(a: FloatArray, b: FloatArray) -> FloatArray:
    """(len(a), len(b)) distances between points."""
    return np.hypot(a[:, None, 0] - b[None, :, 0], a[:, None, 1] - b[None, :, 1])


def _nearest_distance(a: FloatArray, b: FloatArray) -> FloatArray:
    """Each point of ``a``'s distance to the nearest point of ``b`` (by a k-d tree when
    there are many: a map's doors are tens of thousands)."""
    if len(a) * len(b) <= _BRUTE:
        return np.concatenate([_xy_distances(a[lo : lo + _CHUNK], b).min(axis=1) for lo in range(0, len(a), _CHUNK)])
    from scipy.spatial import cKDTree

    return cKDTree(b).query(a)[0]


def _corners(scene, blocked) -> FloatArray:
    """The corners of the scene's polygon and box obstacles, and a map's outer corners: the
    corners of the rectangles covering its blocked cells with one of the four cells around
    them blocked (``blocked``: points -> bool), not those inside a wall or along its face.
    Discs have none."""
    pts = []
    for ob in scene.obstacles:
        if hasattr(ob, "rects"):  # a map: [xmin, ymin, xmax, ymax] rows
            pts += [tuple(p) for p in _map_corners(ob, blocked)]
        elif hasattr(ob, "vertices"):
            pts += [tuple(p) for p in ob.vertices()]
        elif hasattr(ob, "points"):
            pts += [tuple(p) for p in ob.points]
            for hole in getattr(ob, "holes", ()):
                pts += [tuple(p) for p in hole]
    return np.array(pts, dtype=float).reshape(-1, 2)


def _map_corners(ob, blocked) -> FloatArray:
    """The outer corners of a map's blocked cells (see :func:`_corners`)."""
    r = np.asarray(ob.rects, dtype=float).reshape(-1, 4)
    c = np.unique(np.concatenate([r[:, [0, 1]], r[:, [2, 1]], r[:, [2, 3]], r[:, [0, 3]]]), axis=0)
    h = 0.5 * float(ob.resolution)
    around = [blocked(c + np.array([dx, dy])) for dx in (-h, h) for dy in (-h, h)]
    return c[np.sum(around, axis=0) == 1]


def _doors(scene, blocked, span: float) -> FloatArray:
    """Rows ``[x, y, heading, gap]``: the free midpoints of obstacle corners (or a corner and
    its nearest point on the bounds) less than ``span`` apart, the heading across the gap (the
    door's axis), the gap's width."""
    c = _corners(scene, blocked)
    if not len(c):
        return np.zeros((0, 4))
    xmin, ymin, xmax, ymax = scene.bounds
    wall = np.concatenate([c, c, c, c])  # each corner's foot on the four sides of the bounds
    n = len(c)
    wall[:n, 0], wall[n : 2 * n, 0], wall[2 * n : 3 * n, 1], wall[3 * n :, 1] = xmin, xmax, ymin, ymax
    pairs = []
    for lo in range(0, len(c), _CHUNK):
        i, j = np.nonzero(_xy_distances(c[lo : lo + _CHUNK], c) < span)
        i = i + lo
        pairs.append(np.column_stack([i, j])[i < j])
    pairs = np.concatenate(pairs)
    a = np.concatenate([c[pairs[:, 0]], np.tile(c, (4, 1))])
    b = np.concatenate([c[pairs[:, 1]], wall])
    gap = np.hypot(*(b - a).T)
    keep = (gap > 1e-9) & (gap < span)
    a, b, gap = a[keep], b[keep], gap[keep]
    mid = 0.5 * (a + b)
    free = ~blocked(mid)
    d = (b - a)[free]
    return np.column_stack([mid[free], np.arctan2(d[:, 1], d[:, 0]) + 0.5 * math.pi, gap[free]])


def door_headings(body: FloatArray, axis: float, gap: float, limit: int, drive: bool = False) -> list:
    """Headings at which a body may cross a door along ``axis``, narrowest across it first.

    The candidates are the heading along the axis and each outline edge laid along the axis
    (where a convex body is narrowest across, by the rotating calipers), each either way
    round; those at which the body is at least ``gap`` wide across the axis are left out (its
    translation through the door would meet a corner). A U or a box crossing sideways, a
    footprint longer than wide: the heading a door with a few centimetres to spare needs is
    one of these. Ties keep the heading along the axis first. A differential drive
    (``drive``) gets only the heading along the axis, either way round: it crosses only along
    its heading, and its lanes through the door join the positions centred for that heading
    (a crossing at another heading is a sideways slide it cannot drive: counted as a join, it
    kept the doors after it and the RRT from finding one it can).

    Parameters
    ----------
    body : (k, 2) float
        The outline's vertices in the robot's frame.
    axis : float
        The door's axis (across the gap between its corners).
    gap : float
        The door's width.
    limit : int
        Headings returned at most.
    drive : bool
        Only the heading along the axis (either way round).

    Returns
    -------
    list of float
    """
    edges = np.roll(body, -1, axis=0) - body
    rel = np.concatenate([[0.0, math.pi], np.arctan2(edges[:, 1], edges[:, 0])])  # heading = axis - rel
    rel = np.concatenate([rel[:2], rel[2:], rel[2:] + math.pi])
    out, seen = [], set()
    widths = [_width_across(body, float(r)) for r in rel]
    order = np.argsort(widths, kind="stable").tolist()
    if drive:
        order = [0, 1]
    for k in order:
        key = (round(math.cos(rel[k]), 9), round(math.sin(rel[k]), 9))
        if widths[k] > gap + TOUCH_TOL or key in seen:  # (as wide as the door: touching both jambs)
            continue
        seen.add(key)
        out.append(float(_wrap(axis - rel[k])))
        if len(out) == limit:
            break
    return out


def _width_across(body: FloatArray, rel: float) -> float:
    """The body's width across a door whose axis is at ``rel`` in the robot's frame."""
    return float(np.ptp(body @ np.array([-math.sin(rel), math.cos(rel)])))


def _door_middle(body: FloatArray, heading: float, axis: float) -> tuple[float, float]:
    """The middle of the body's extents along a door's ``axis`` and across it, in the robot's
    frame at ``heading`` (the middle of its extents in x and y when the two agree)."""
    rel = axis - heading
    along = np.array([math.cos(rel), math.sin(rel)])
    across = np.array([-along[1], along[0]])
    pt, pu = body @ along, body @ across
    mt, mu = 0.5 * (pt.min() + pt.max()), 0.5 * (pu.min() + pu.max())
    return float(mt * along[0] + mu * across[0]), float(mt * along[1] + mu * across[1])


def _disc_regions(scene, vertices: FloatArray) -> IntArray | None:
    """The region of each vertex's inscribed disc (:func:`~gfuzzy.roadmap.freespace.inscribed_disc`) in that disc's free
    space, or None where it cannot prove anything.

    The disc lies inside the body, so wherever the robot moves the disc moves free too: two
    vertices whose discs lie in different regions are never joined by any motion
    (:func:`~gfuzzy.roadmap.freespace.inscribed_free_space`: a free space that holds the
    true one); None where it proves nothing, or for a vertex whose disc is found in no region.
    """
    got = inscribed_free_space(scene)
    if got is None:
        return None
    centre, fs = got
    region = fs.region_of(disc_centres(centre, vertices))
    return None if (region < 0).any() else region
