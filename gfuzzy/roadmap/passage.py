"""Bridge samples put where a rigid robot fits: across a passage, on its middle line.

The passage sampler (:class:`PassageDraws`, handed to OMPL's PRM by
:mod:`gfuzzy.roadmap.roadmap` through :func:`passage_sampler_type`) draws uniform samples
and bridge-test samples. Its bridge test finds points inside narrow passages, each with a
heading along the passage drawn from the bridge's direction. In a door with a few
centimetres to spare that pose is almost never valid: the bridge's midpoint lies anywhere
across the door, its heading is off by the bridge's random tilt, and a footprint whose
reference point is not its body's middle (a cart pulled by its axle, an L) is placed with
the reference point, not the body, in the door's middle. :func:`centre_bridge` measures the
passage instead: the walls' faces on both sides (points where a ray leaves the free space,
found by bisection), the heading along them, and the pose whose body's lateral middle lies
on the passage's middle line.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from ..scene.maps import free_cell_draw
from ..typed import FloatArray
from .freespace import blocked_points

__all__ = ["Chains", "PassageDraws", "centre_bridge", "lateral_middle", "passage_sampler_type"]

#: Bisection steps of a ray's exit from the free space (2**-24 of a 64th of the reach).
_BISECT = 24
#: Metres along the passage between the two rays that measure a wall face's direction.
_FACE_BASE = 0.02


def lateral_middle(robot) -> float:
    """The middle of the robot's body across its heading (robot frame y): 0 for a disc or a
    box, the middle of a footprint's extent in y (an L with its arm left: left of 0)."""
    if robot.shape != "footprint":
        return 0.0
    ys = [p[1] for p in robot.footprint]
    return 0.5 * (min(ys) + max(ys))


def _exits(blocked, origins: FloatArray, dirs: FloatArray, reach: float) -> FloatArray:
    """Distances along ``dirs`` from free ``origins`` to the first blocked point within
    ``reach`` (bisection between a free and a blocked sample; NaN: none within reach).

    Rays are sampled at steps of reach / 64 before the bisection, so a wall thinner than
    that may be stepped over; passages are what is measured, the validity test decides."""
    n = len(origins)
    steps = np.linspace(0.0, reach, 65)
    pts = origins[:, None, :] + steps[None, :, None] * dirs[:, None, :]
    hit = blocked(pts.reshape(-1, 2)).reshape(n, len(steps))
    first = np.where(hit.any(axis=1), hit.argmax(axis=1), -1)
    out = np.full(n, np.nan)
    ok = first > 0
    if not ok.any():
        return out
    lo, hi = steps[first[ok] - 1], steps[first[ok]]
    o, d = origins[ok], dirs[ok]
    for _ in range(_BISECT):
        mid = 0.5 * (lo + hi)
        b = blocked(o + mid[:, None] * d)
        hi = np.where(b, mid, hi)
        lo = np.where(b, lo, mid)
    out[ok] = lo
    return out


def centre_bridge(blocked, m: FloatArray, heading: float, reach: float, y_mid: float) -> FloatArray | None:
    """A pose ``[x, y, heading]`` in the passage through the free point ``m``: the heading
    along the passage's walls, the body's lateral middle on the passage's middle line.

    Parameters
    ----------
    blocked : callable
        (n, 2) points -> (n,) bool, inside an obstacle or out of bounds.
    m : (2,) float
        A free point in the passage (a bridge's midpoint).
    heading : float
        Roughly along the passage (the bridge turned by a right angle); the answer keeps
        its sense.
    reach : float
        How far across to look for the walls on each side (the robot's diameter).
    y_mid : float
        :func:`lateral_middle` of the robot.

    Returns
    -------
    (3,) float, or None
        None where a side has no wall within ``reach`` (not a passage) or the walls are
        not found on both rays of a side.
    """
    left = np.array([-math.sin(heading), math.cos(heading)])
    at_m = _exits(blocked, np.stack([m, m]), np.stack([left, -left]), reach)
    if not np.all(np.isfinite(at_m)):
        return None
    h = _along_faces(blocked, m, heading, reach)
    if h is not None:  # the middle line across the walls' heading, when they meet it
        left_h = np.array([-math.sin(h), math.cos(h)])
        t = _exits(blocked, np.stack([m, m]), np.stack([left_h, -left_h]), reach)
        if np.all(np.isfinite(t)):
            heading, left, at_m = h, left_h, t
    middle = m + 0.5 * (at_m[0] - at_m[1]) * left
    x, y = middle - y_mid * left
    return np.array([x, y, heading])


def _along_faces(blocked, m: FloatArray, heading: float, reach: float) -> float | None:
    """The heading along the walls on both sides of ``m`` (the mean of each side's face
    direction, measured between rays ``_FACE_BASE`` apart), or None where a ray meets no
    wall or the two faces differ by more than 0.3 rad (a corner, not a passage's walls)."""
    along = np.array([math.cos(heading), math.sin(heading)])
    left = np.array([-along[1], along[0]])
    origins = np.repeat(m[None, :] + np.array([-_FACE_BASE, _FACE_BASE])[:, None] * along[None, :], 2, axis=0)
    if blocked(origins).any():
        return None
    dirs = np.tile(np.stack([left, -left]), (2, 1))
    t = _exits(blocked, origins, dirs, reach)
    if not np.all(np.isfinite(t)):
        return None
    hits = origins + t[:, None] * dirs  # rows: (left, right) behind m, then ahead of it
    faces = [hits[2] - hits[0], hits[3] - hits[1]]
    units = [f / np.hypot(*f) for f in faces]
    if abs(math.atan2(units[0][0] * units[1][1] - units[0][1] * units[1][0], float(units[0] @ units[1]))) > 0.3:
        return None
    mean = units[0] + units[1]
    return math.atan2(mean[1], mean[0])


#: A disc robot's bridge draws (64 bridges each) that may all fail before the passage sampler
#: gives the bridge test up for the build: on a map whose pixel noise makes thin gaps no disc
#: fits, the bridge test found nothing in 4596 refills and cost 80 % of the build (tb3-arena);
#: a disc's real passages are found by the free-space repair as well (docs/planner.md).
BARREN_DRAWS = 16
#: Validity checks after which a draw that found nothing hands back (:meth:`PassageDraws.draw`).
DRAW_CHECKS = 500
#: Bridge samples in a row that make no new chain (each one centred in vain) after which the
#: sampler stops centring: bridges are then taken as they come (:meth:`Chains.plain`).
MAX_MISSES = 256
#: A bridge sample that fits with a clearance of at least this share of the robot's span
#: (twice its circumradius) is not in a narrow passage: it makes no chain.
NARROW = 0.05
#: Samples of a chain, in robot spans (twice the circumradius) along the heading from its
#: bridge pose.
CHAIN_SHIFTS = (0.35, -0.35, 0.7, -0.7, 1.05, -1.05)


class Chains:
    """The passage sampler's chains for a box or footprint robot.

    A bridge sample (a free point between two obstacles, a heading along the passage) is a
    milestone as it is when the robot fits there with room to spare (``NARROW`` of its span:
    the passage is not narrow for it); else it becomes a pose in the passage
    (:func:`centre_bridge`, or itself when that fails and it fits) and a *chain* of valid poses
    shifted along its heading (``CHAIN_SHIFTS``): aligned milestones that cross a door the robot passes only turned, and that a differential drive drives
    straight through. A footprint that is not the same body turned by pi also gets the chain
    facing the other way (without ``reverse`` a unicycle crosses only forwards). A bridge
    near a chain already made (half a span, a heading within 0.2 rad either way) is skipped:
    the bridges go to other passages.

    Parameters
    ----------
    valid, clearance, blocked : callable
        A pose's validity and clearance; which points lie in obstacles or out of bounds.
    robot : gfuzzy.scene.scene.Robot
    """

    def __init__(self, valid, clearance, blocked, robot):
        self.valid, self.clearance, self.blocked = valid, clearance, blocked
        self.span = 2.0 * robot.circumradius
        self.y_mid = lateral_middle(robot)
        self.both_ways = not robot.half_turn_symmetric
        self.made: list = []  # bridge poses chains were made along
        self.misses = 0

    @property
    def exhausted(self) -> bool:
        return self.misses >= MAX_MISSES

    def _near(self, q, poses, radius: float) -> bool:
        for c in poses:
            if math.hypot(q[0] - c[0], q[1] - c[1]) < radius and abs(math.sin(q[2] - c[2])) < 0.2:
                return True
        return False

    def plain(self, m: FloatArray) -> list | None:
        """Bridge sample ``m`` as it is, when the robot fits there, and its shifts along its
        heading that fit (no centring: once centring has failed ``MAX_MISSES`` times in a row,
        bridges still find passages at their random tilts, as cheaply as before it)."""
        return [m, *self._shifts(m)] if self.valid(m) else None

    def _shifts(self, p: FloatArray) -> list:
        """The valid poses ``CHAIN_SHIFTS`` spans from ``p`` along its heading."""
        d = np.array([math.cos(p[2]), math.sin(p[2]), 0.0])
        return [q for q in (p + s * self.span * d for s in CHAIN_SHIFTS) if self.valid(q)]

    def make(self, m: FloatArray) -> list | None:
        """The milestones of bridge sample ``m`` (``[x, y, heading]``): its pose first, then
        its chain; None when it is skipped or gives no valid pose."""
        half = 0.5 * self.span
        if self._near(m, self.made, half):
            return None
        fits = self.valid(m)
        if fits and self.clearance(m) >= NARROW * self.span:  # not narrow for the robot: no chain
            return [m]
        q = centre_bridge(self.blocked, m[:2], float(m[2]), self.span, self.y_mid)
        if (q is None or not self.valid(q)) and fits:
            q = m
        if q is None or not self.valid(q) or self._near(q, self.made, half):
            self.misses += 1
            return None
        self.misses = 0
        out = [q]
        if self.both_ways:
            back = centre_bridge(self.blocked, m[:2], float(q[2]) + math.pi, self.span, self.y_mid)
            if back is not None and self.valid(back):
                out.append(back)
        for p in list(out):
            p[2] = (p[2] + math.pi) % (2 * math.pi) - math.pi
            self.made.append(p)
            out += self._shifts(p)
        return out


class PassageDraws:
    """The draws of the passage sampler (see :class:`gfuzzy.roadmap.roadmap.RoadmapOptions`):
    uniform + bridge-test samples; on a map mostly blocked, half the uniform ones in free
    cells (when they are below ``free_cell_share`` of the bounds).

    Plain Python (no OMPL object, no closure over one), so that a build's sampler dies
    by reference counting with the build, without a garbage collection.
    """

    def __init__(self, geometry, rng: np.random.Generator, ratio: float, free_cell_share: float):
        scene = geometry.scene
        self.rng, self.ratio = rng, ratio
        self.bounds = scene.bounds
        self.box = scene.robot.space_dof == 3
        self.sigma = max(scene.robot.circumradius, 1e-3)
        self.disc_radius = scene.robot.circumradius  # (when a disc)
        self.valid = geometry.is_valid
        self.geometry = geometry
        self.blocked = blocked_points(scene)
        self.in_free_cell = free_cell_draw(scene.obstacles, scene.bounds, rng, free_cell_share)
        self.chains = Chains(self.valid, geometry.clearance1, self.blocked, scene.robot) if self.box else None
        self.queue: list = []
        self.bridges: list = []
        self.dry = 0  # refills in a row that found no bridge
        self.barren = 0  # a disc's bridge draws that found no valid sample, before the first that did

    def _uniform(self):
        rng = self.rng
        xmin, ymin, xmax, ymax = self.bounds
        if self.in_free_cell is not None and rng.random() < 0.5:  # a map mostly blocked
            q = list(self.in_free_cell())
        else:
            q = [rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)]
        if self.box:
            q.append(rng.uniform(-math.pi, math.pi))
        return np.array(q)

    def _refill(self):
        # bridge test on points: both ends inside obstacles, the middle free
        rng, blocked = self.rng, self.blocked
        xmin, ymin, xmax, ymax = self.bounds
        n = 4096
        a = np.column_stack([rng.uniform(xmin, xmax, n), rng.uniform(ymin, ymax, n)])
        b = a + rng.normal(0.0, self.sigma, (n, 2))
        # a disc never fits in the middle of a bridge shorter than its diameter (the middle is
        # within half the length of a point inside): dropped before testing (86 % of them)
        ok = blocked(a) if self.box else (np.hypot(*(b - a).T) >= 2.0 * self.disc_radius) & blocked(a)
        ok[ok] = blocked(b[ok])  # b tested only where a is blocked: the same answer, cheaper
        mid = 0.5 * (a[ok] + b[ok])
        free = ~blocked(mid)
        a, b, mid = a[ok][free], b[ok][free], mid[free]
        head = np.arctan2(b[:, 1] - a[:, 1], b[:, 0] - a[:, 0]) + 0.5 * math.pi
        head = head + rng.normal(0.0, 0.1, len(head))
        self.bridges = list(np.column_stack([mid, head]))

    def _bridge(self):
        if self.barren >= BARREN_DRAWS:  # a disc fits through none of the bridges: sample uniformly
            return None
        q = self._bridge_draw()
        if not self.box:
            self.barren = -math.inf if q is not None else self.barren + 1
        return q

    def _bridge_draw(self):
        for _ in range(64):
            if not self.bridges:
                if self.dry >= 3:  # no narrow passages to find: sample uniformly
                    return None
                self._refill()
                if not self.bridges:
                    self.dry += 1
                    continue
                self.dry = 0
            m = self.bridges.pop()
            if not self.box:
                if self.valid(m[:2]):
                    return m[:2]
                continue
            m[2] = (m[2] + math.pi) % (2 * math.pi) - math.pi
            if self.chains.exhausted:  # centring keeps failing: the bridge as it is, shifted
                poses = self.chains.plain(m)
            else:
                poses = self.chains.make(m)
            if poses is not None:
                self.queue += poses[:0:-1]  # popped from the end: the chain in order
                return poses[0]
        return None

    def draw(self):
        """The next milestone (a valid configuration), or None after 1000 tries or
        ``DRAW_CHECKS`` validity checks (OMPL asks its termination condition between
        draws: a box's 1000 tries in a space with no room took 30,000 checks, 2-3 s).
        None changes nothing but when the caller may stop: the next draw goes on where
        this one stopped (the same generator, the same queues)."""
        checks = self.geometry.checks
        for _ in range(1000):
            if self.geometry.checks - checks > DRAW_CHECKS:
                return None
            if self.rng.random() < self.ratio:  # a chain's samples count as bridge samples too
                q = self.queue.pop() if self.queue else self._bridge()
                if q is not None:
                    return q
            q = self._uniform()
            if self.valid(q):
                return q
        return None


@functools.cache
def passage_sampler_type():
    """OMPL's ``ValidStateSampler`` subclass handing out :class:`PassageDraws`' samples.

    Every state it hands out becomes a PRM milestone; they are appended to ``record`` so
    that milestones PRM leaves without an edge (and out of its planner data) are kept.

    Made once per process: a class made per build is a reference cycle (a class always is)
    holding the build's SpaceInformation through its methods' closures until a garbage
    collection, which costs 0.1-0.2 s in a large heap.
    """
    from ompl import base as ob

    class PassageSampler(ob.ValidStateSampler):
        def __init__(self, si, draws: PassageDraws, record: list):
            super().__init__(si)
            self.draws = draws
            self.record = record

        def sample(self, state):
            q = self.draws.draw()
            if q is None:
                return False
            self.record.append(tuple(float(v) for v in q))
            if self.draws.box:
                state.setX(float(q[0]))
                state.setY(float(q[1]))
                state.setYaw(float(q[2]))
            else:
                state[0] = float(q[0])
                state[1] = float(q[1])
            return True

        def sampleNear(self, state, near, distance):
            return False

    return PassageSampler
