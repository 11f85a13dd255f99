"""What a robot's sensors make of the movers around it (CONTRACT.md section 7).

:class:`Sensor` turns the true state of the movers at an instant into what a robot
observes: only the movers within range (``sense``), inside its field of view (``fov``,
a cone about its heading) and not hidden behind a static obstacle (``occlusion``), their
positions blurred by Gaussian ``noise``; their velocity is not measured but estimated by
a :class:`Tracker` from positions observed one period apart (``velocity="estimated"``,
the default), or handed over exactly (``velocity="exact"``, the old ideal sensor).

The tracker is deliberately small: detections carry no identity; each is associated with
the track whose predicted position is nearest (an optimal assignment within a gate), and
each track runs an alpha-beta filter on position and velocity. Without noise the filter
is the plain difference of two observations one period apart; with noise it smooths.
A track that goes unseen (left the field of view, hidden) is reported, walking on at its
last velocity, for ``coast`` seconds, then dropped; while unseen its disc grows by
``coast_growth`` metres per second unseen (it may have slowed down, sped up or turned), and so
does the gate that may take it up again. A narrow field of view loses the people beside and
behind the robot, who still walk where they were going: a track kept a few seconds stops a
person who was seen and then left the view from becoming a surprise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError, check_number
from ..rng import create_rng
from ..roadmap.freespace import obstacle_shape
from ..scene.scene import Scene
from ..typed import BoolArray, FloatArray

__all__ = ["VELOCITY_MODES", "SensorOptions", "Sensor", "Tracker", "line_of_sight", "in_fov"]

VELOCITY_MODES = ("estimated", "exact")
#: Growth (m/s) of the radius of an unseen track whose velocity is unknown (seen once: it
#: may walk anywhere at a walking pace), and the cap (m) on any unseen track's growth.
UNKNOWN_GROWTH = 1.0
UNKNOWN_CAP = 1.0
#: Steady-state gains (position, velocity) of the alpha-beta filter with noisy detections.
STEADY_GAINS = (0.5, 0.2)
#: Standard deviations of a track's velocity error its unseen disc grows by, per second
#: unseen (3: the disc holds a person walking on with a Gaussian velocity error 99 % of the time).
VELOCITY_SIGMAS = 3.0


@dataclass(frozen=True)
class SensorOptions:
    """How the robot observes the movers.

    Attributes
    ----------
    velocity : {"estimated", "exact"}
        ``estimated``: from positions observed one period apart (a :class:`Tracker`);
        ``exact``: the mover's true velocity at that instant.
    noise : float
        Standard deviation (m) of the Gaussian noise on each observed coordinate.
    fov : float
        Field of view (degrees, 0 < fov <= 360), a cone centred on the robot's heading.
    occlusion : bool
        A static obstacle crossing the segment between the robot's and the mover's
        centres hides the mover.
    sense : float
        Range (m, gap between the robot's body and the mover's disc).
    coast : float
        Seconds a track that is no longer seen is still reported (walking on).
    coast_growth : float
        Growth (m per s unseen) of an unseen track's radius and of its association gate.
    gate : float
        Largest distance (m) between a track's predicted position and a detection that
        may be associated with it (plus four times ``noise``).
    seed : int
        Seed of the noise.
    """

    velocity: str = "estimated"
    noise: float = 0.0
    fov: float = 360.0
    occlusion: bool = False
    sense: float = math.inf
    coast: float = 4.0
    coast_growth: float = 0.2
    gate: float = 1.0
    seed: int = 0

    def __post_init__(self):
        if self.velocity not in VELOCITY_MODES:
            raise InputError(f"velocity must be one of {', '.join(VELOCITY_MODES)}, got {self.velocity!r}")
        check_number("noise", self.noise, strict=False)
        if not (0 < self.fov <= 360):
            raise InputError(f"fov must be in (0, 360] degrees, got {self.fov}")
        if not self.sense > 0:
            raise InputError(f"sense must be a positive number, got {self.sense}")
        if not (math.isfinite(self.coast) and self.coast >= 0) or not (math.isfinite(self.gate) and self.gate > 0):
            raise InputError("coast must be >= 0 and gate > 0")
        if not (math.isfinite(self.coast_growth) and self.coast_growth >= 0):
            raise InputError(f"coast_growth must be a number >= 0, got {self.coast_growth}")

    @property
    def ideal(self) -> bool:
        """True when the sensor gives the movers' true state (the contract's section 5)."""
        return self.velocity == "exact" and self.noise == 0 and self.fov >= 360 and not self.occlusion


def in_fov(pose_xy: FloatArray, heading: float, points: FloatArray, fov_deg: float) -> BoolArray:
    """(k,) True for each of ``points`` (k, 2) inside the cone of ``fov_deg`` degrees
    about ``heading`` (radians) from ``pose_xy`` (a point at the apex counts as inside)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if fov_deg >= 360:
        return np.ones(len(pts), dtype=bool)
    rel = pts - np.asarray(pose_xy, dtype=float)[:2]
    ang = np.arctan2(rel[:, 1], rel[:, 0]) - heading
    ang = (ang + math.pi) % (2 * math.pi) - math.pi
    return (np.abs(ang) <= math.radians(fov_deg) / 2 + 1e-12) | (np.hypot(rel[:, 0], rel[:, 1]) < 1e-12)


def occluders(scene: Scene):
    """The static obstacles (maps included) as one prepared shapely geometry, or None.

    Built once per sensor: on a SLAM map of thousands of cell rectangles the union costs
    a good fraction of a second, and it was built again at every look.
    """
    import shapely

    shapes = [g for g in map(obstacle_shape, scene.obstacles) if g is not None]
    if not shapes:
        return None
    union = shapely.union_all(shapes)
    shapely.prepare(union)
    return union


def line_of_sight(scene: Scene, a: FloatArray, points: FloatArray, union=None) -> BoolArray:
    """(k,) True where the segment from ``a`` (2,) to each of ``points`` (k, 2) crosses no
    static obstacle of ``scene`` (touching one's boundary hides too); ``union``: the
    scene's :func:`occluders`, when already built (a list of shapes, as before, is united
    here)."""
    import shapely

    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    if union is None:
        union = occluders(scene)
    elif isinstance(union, (list, tuple)):
        union = shapely.union_all(union) if len(union) else None
    if union is None or len(pts) == 0:
        return np.ones(len(pts), dtype=bool)
    a = np.asarray(a, dtype=float)[:2]
    lines = shapely.linestrings(np.stack([np.broadcast_to(a, pts.shape), pts], axis=1))
    return ~shapely.intersects(lines, union)


class Tracker:
    """Tracks of observed people from detections without identity.

    Parameters
    ----------
    noise : float
        The detections' noise (m); it sets the filter's gains and widens the gate.
    coast : float
        Seconds an unseen track is still reported.
    gate : float
        Association gate (m) on top of ``4 * noise``.
    growth : float
        Growth (m per s unseen) of an unseen track's reported radius and of its gate
        (``UNKNOWN_GROWTH`` for a person seen once; both capped at ``UNKNOWN_CAP``).

    Notes
    -----
    Alpha-beta filter per track: prediction ``p + v dt``; residual ``r = z - p_pred``;
    ``p = p_pred + alpha r``, ``v = v + beta r / dt``. Without noise alpha = beta = 1,
    which makes ``v`` exactly ``(z - z_prev) / dt``, the velocity from positions observed
    one period apart. With noise the gains start as the expanding-memory filter's,
    ``alpha_n = 2 (2n - 1) / (n (n + 1))``, ``beta_n = 6 / (n (n + 1))`` at the n-th
    sighting (the least-squares line through the first n positions when they are evenly
    spaced: the first difference at n = 2, then ever less noisy), each clamped from below
    at its steady state alpha = 0.5, beta = 0.2 (beta reaches it at n = 5, alpha at n = 7:
    sightings 5 and 6 are a blend of the two, not least squares) (a compromise between lag and
    noise for people walking at up to ~1.5 m/s, 0.25 s apart). A fixed gain from the
    second sighting on kept the first difference's error (noise x sqrt(2) / 0.25 s per
    coordinate: 0.28 m/s at 0.05 m) for a second or more, and a person lost from view
    was then coasted the wrong way.

    An unseen track's disc grows by ``growth`` plus ``VELOCITY_SIGMAS`` times the standard
    deviation of its velocity estimate per second unseen: a person seen a few times
    through noise may be walking a good deal off the estimated velocity.
    """

    def __init__(self, noise: float = 0.0, coast: float = 4.0, gate: float = 1.0, growth: float = 0.2):
        self.noise = noise
        self.alpha, self.beta = (1.0, 1.0) if noise == 0 else STEADY_GAINS
        self.coast = coast
        self.gate = gate + 4 * noise
        self.growth = growth
        self.pos = np.zeros((0, 2))
        self.vel = np.zeros((0, 2))
        self.radius = np.zeros(0)
        self.seen = np.zeros(0)  # time each track was last seen
        self.first = np.zeros(0)  # time each track was first seen
        self.hits = np.zeros(0, dtype=np.int64)
        self.t: float | None = None

    def update(self, t: float, detections: FloatArray) -> FloatArray:
        """Take the detections ``[x, y, radius]`` (k, 3) made at ``t``; return the tracks
        as observations ``[x, y, vx, vy, radius]`` (m, 5) (a new track: velocity 0).

        Returns
        -------
        (m, 5) float
        """
        from scipy.optimize import linear_sum_assignment

        det = np.asarray(detections, dtype=float).reshape(-1, 3)
        dt = 0.0 if self.t is None else t - self.t
        self.t = t
        pred = self.pos + self.vel * dt
        matched_t = np.zeros(len(pred), dtype=bool)
        matched_d = np.zeros(len(det), dtype=bool)
        if len(pred) and len(det):
            cost = np.hypot(*(pred[:, None, :] - det[None, :, :2]).transpose(2, 0, 1))
            # the gate grows as the track's reported disc does (below): faster for a person
            # seen once, whose velocity is not known yet
            unseen = np.maximum(t - self.seen - dt, 0.0)
            gate = self.gate + np.minimum(self._growth_rates() * unseen, UNKNOWN_CAP)
            big = 1e6
            rows, cols = linear_sum_assignment(np.where(cost <= gate[:, None], cost, big))
            for i, j in zip(rows.tolist(), cols.tolist(), strict=True):
                if cost[i, j] > gate[i]:
                    continue
                r = det[j, :2] - pred[i]
                alpha, beta = self._gains(int(self.hits[i]) + 1)
                self.pos[i] = pred[i] + alpha * r
                since = t - self.seen[i]  # the residual built up since the last sighting
                if since > 0:
                    self.vel[i] = self.vel[i] + beta * r / since
                self.radius[i] = det[j, 2]
                self.seen[i] = t
                self.hits[i] += 1
                matched_t[i] = matched_d[j] = True
        coasting = ~matched_t
        self.pos[coasting] = pred[coasting]
        keep = matched_t | (t - self.seen <= self.coast + 1e-9)
        new = det[~matched_d]
        self.pos = np.vstack([self.pos[keep], new[:, :2]])
        self.vel = np.vstack([self.vel[keep], np.zeros((len(new), 2))])
        self.radius = np.concatenate([self.radius[keep], new[:, 2]])
        self.seen = np.concatenate([self.seen[keep], np.full(len(new), t)])
        self.first = np.concatenate([self.first[keep], np.full(len(new), t)])
        self.hits = np.concatenate([self.hits[keep], np.ones(len(new), dtype=np.int64)])
        # unseen tracks are less certain; one seen once has no velocity yet: it may be
        # walking anywhere at a walking pace (capped: beyond that it is as good as gone)
        grown = self.radius + np.minimum(self._growth_rates() * (t - self.seen), UNKNOWN_CAP)
        return np.column_stack([self.pos, self.vel, grown]).reshape(-1, 5)

    def unknown(self) -> BoolArray:
        """(m,) True for each track of the last :meth:`update` whose velocity is not known
        (seen once: it is reported standing, but may walk anywhere)."""
        return self.hits == 1

    def _gains(self, n: int) -> tuple[float, float]:
        """(alpha, beta) at a track's ``n``-th sighting: the expanding-memory filter's
        (the least-squares line through the n positions), never below the steady state."""
        alpha_n = 2.0 * (2 * n - 1) / (n * (n + 1))
        beta_n = 6.0 / (n * (n + 1))
        return max(alpha_n, self.alpha), max(beta_n, self.beta)

    def velocity_sigma(self) -> FloatArray:
        """(m,) standard deviation (m/s, per coordinate) of each track's velocity estimate
        due to the detections' noise: the least-squares slope's through ``hits`` positions
        spread over the track's seen span, never below the steady-state filter's
        (``beta / sqrt(alpha (4 - 2 alpha - beta) / 2)`` noise per period); 0 without noise,
        and for a track seen once (its velocity is unknown, not noisy)."""
        n = self.hits.astype(float)
        if self.noise == 0 or not len(n):
            return np.zeros(len(n))
        span = self.seen - self.first
        ok = (n > 1) & (span > 0)
        n_, span_ = np.where(ok, n, 2.0), np.where(ok, span, 1.0)
        least = np.sqrt(12.0 * (n_ - 1) / (n_ * (n_ + 1))) / span_
        a, b = STEADY_GAINS
        steady = b / math.sqrt(a * (4 - 2 * a - b) / 2) / (span_ / (n_ - 1))
        return np.where(ok, self.noise * np.maximum(least, steady), 0.0)

    def _growth_rates(self) -> FloatArray:
        """(m,) growth (m per s unseen) of each track's disc and gate."""
        return np.where(self.hits > 1, self.growth + VELOCITY_SIGMAS * self.velocity_sigma(), UNKNOWN_GROWTH)


@dataclass
class Sensor:
    """The robot's view of the movers, one observation at a time.

    Parameters
    ----------
    scene : Scene
        For its static obstacles (occlusion) and robot (range).
    options : SensorOptions, optional

    Notes
    -----
    Call :meth:`observe` once per period, in time order: the tracker (estimated
    velocities) remembers what it saw before. After each call ``unknown`` (m,) marks the
    people observed whose velocity is not known yet (seen once); hand it to
    :meth:`gfuzzy.Navigator.step`.
    """

    scene: Scene
    options: SensorOptions = field(default_factory=SensorOptions)

    def __post_init__(self):
        o = self.options
        self._rng = create_rng(o.seed)
        self._tracker = Tracker(o.noise, o.coast, o.gate, o.coast_growth)
        self._occluders = (None, None)  # (scene, its occluders), built at the first look
        self.unknown = np.zeros(0, dtype=bool)

    def visible(self, pose: FloatArray, heading: float, truth: FloatArray) -> BoolArray:
        """(k,) which of the true discs ``[x, y, vx, vy, r]`` (k, 5) the robot at ``pose``
        with ``heading`` (radians) sees (range, field of view, occlusion)."""
        from ..collision.geometry import mover_distance

        o = self.options
        truth = np.asarray(truth, dtype=float).reshape(-1, 5)
        pose = np.asarray(pose, dtype=float)
        seen = np.ones(len(truth), dtype=bool)
        if not len(truth):
            return seen
        if math.isfinite(o.sense):
            gap = mover_distance(self.scene.robot, pose[None, :], "disc", truth[:, 4], (0.0, 0.0), truth[:, :2])
            seen &= np.asarray(gap).reshape(-1) <= o.sense
        if o.fov < 360:
            seen &= in_fov(pose[:2], heading, truth[:, :2], o.fov)
        if o.occlusion and seen.any():
            idx = np.nonzero(seen)[0]
            if self._occluders[0] is not self.scene:  # a new scene (the field is mutable)
                self._occluders = (self.scene, occluders(self.scene))
            seen[idx] = line_of_sight(self.scene, pose[:2], truth[idx, :2], self._occluders[1])
        return seen

    def observe(self, t: float, pose: FloatArray, heading: float, truth: FloatArray) -> FloatArray:
        """What the robot observes at ``t`` of the movers whose true state is ``truth``.

        Parameters
        ----------
        t : float
        pose : (d,) float
        heading : float
            Direction (radians) the field of view is centred on.
        truth : (k, 5) float
            ``[x, y, vx, vy, radius]`` of every mover present.

        Returns
        -------
        (m, 5) float
            ``[x, y, vx, vy, radius]`` per observed (or tracked) person.
        """
        o = self.options
        truth = np.asarray(truth, dtype=float).reshape(-1, 5)
        seen = truth[self.visible(pose, heading, truth)]
        if o.noise > 0 and len(seen):
            seen = seen.copy()
            seen[:, :2] += self._rng.normal(0.0, o.noise, size=(len(seen), 2))
        if o.velocity == "exact":
            self.unknown = np.zeros(len(seen), dtype=bool)
            return seen
        out = self._tracker.update(t, seen[:, [0, 1, 4]])
        self.unknown = self._tracker.unknown()
        return out
