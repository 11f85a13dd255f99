"""Keeping off the way people are about to walk: their predicted paths as a preference.

CrowdNav++ (Liu et al., ICRA 2023) counts an *intrusion* whenever the robot stands where
a person will be within the next 1.25 s (:mod:`gfuzzy.navigation.socialmetrics`). The
navigator's personal space keeps a gap from where each person is predicted to be *at the
same instant*; it does not stop the robot from crossing just in front of someone, or from
waiting in their way. :func:`path_ghosts` turns the way ahead of each walking person into
predicted discs the first search keeps off as it keeps off the people themselves:
*ghosts*, copies of the person shifted ``s`` seconds ahead along their predicted walk
(the ghost at time τ is where the person is predicted at τ + s), for a few ``s`` up to
the look-ahead. A ghost has the person's radius; its inflation covers the gaps between
neighbouring ghosts, so that the robot's body stays off the whole band the person sweeps
(plus a buffer), not only off the samples.

The ghosts only enter the first search (with the personal space): when no plan keeps off
them, the relaxed search, with the people's discs as they are, answers as before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..typed import BoolArray, FloatArray, IntArray
from .navtypes import NavMode

if TYPE_CHECKING:
    from .navigator import _Searched

__all__ = ["STILL_SPEED", "PathSpace", "GHOST_SPACING", "MAX_GHOSTS", "ESCAPE_FACTOR", "Ghosts", "path_ghosts", "ghost_window", "walled_off", "WallCheck"]

#: Below this speed (m/s) an observed person counts as standing still.
STILL_SPEED = 0.1
#: Largest distance (m) between neighbouring ghosts of a person (a faster walker gets more).
GHOST_SPACING = 0.7
#: Most ghosts of one person: spaced GHOST_SPACING they cover 45 m of path. A faster or
#: farther-looking person (an absurd velocity estimate) gets them farther apart, each inflated
#: to still cover the band, instead of an array sized by the velocity (--noise 1e9: 146 GiB).
MAX_GHOSTS = 64
#: A robot in someone's way gets this many times the time to step sideways out of it at
#: full speed before their ghosts count (the roadmap's directions are not exactly sideways).
ESCAPE_FACTOR = 1.5


@dataclass(frozen=True)
class Ghosts:
    """The ghosts of the walking people of one observation.

    Attributes
    ----------
    obs : (g, 5) float
        One predicted disc ``[x, y, vx, vy, radius]`` per ghost: the person's row with its
        centre moved ``shift`` seconds ahead along their velocity.
    owner : (g,) int
        Row of the observation each ghost comes from.
    shift : (g,) float
        Seconds ahead (0 < shift <= look-ahead).
    cover : (g,) float
        Inflation (m) that, with ``buffer``, makes neighbouring ghosts' zones overlap on the
        band the person sweeps.
    """

    obs: FloatArray
    owner: IntArray
    shift: FloatArray
    cover: FloatArray

    def __len__(self) -> int:
        return len(self.obs)


def path_ghosts(obs: FloatArray, look: float, robot_radius: float, buffer: float, still: float) -> Ghosts:
    """Ghosts along the next ``look`` seconds of each walking person's predicted path.

    Parameters
    ----------
    obs : (k, 5) float
        ``[x, y, vx, vy, radius]`` per person (the navigator's observations).
    look : float
        Seconds of each person's path the robot keeps off (CrowdNav++: 1.25); 0: none.
    robot_radius : float
        The robot's circumradius: the band kept off is the person's path widened by the
        two radii (where the robot's body would overlap the person's future disc).
    buffer : float
        Extra width (m) of the band on each side.
    still : float
        Speed (m/s) below which a person counts as standing (their path is where they
        stand: no ghosts).

    Returns
    -------
    Ghosts

    Notes
    -----
    A person walking at speed v gets ``n = min(ceil(v look / GHOST_SPACING), MAX_GHOSTS)`` ghosts at
    ``s_j = look j / n``, j = 1..n, spaced ``h = v look / n`` apart. A robot centre within
    ``w = robot_radius + radius + buffer`` of the path between two neighbouring ghosts is
    within ``sqrt(w^2 + (h / 2)^2)`` of one of them, so each ghost is inflated by that
    minus ``robot_radius + radius``. The stretch between the person and the first ghost
    is the person's own disc's (with the personal space it is wider than the band).
    """
    obs = np.asarray(obs, dtype=float).reshape(-1, 5)
    speed = np.hypot(obs[:, 2], obs[:, 3])
    walking = np.nonzero((speed >= still) & (look > 0))[0]
    if len(walking) == 0:
        return Ghosts(np.zeros((0, 5)), np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0))
    n = np.clip(np.ceil(speed[walking] * look / GHOST_SPACING - 1e-9), 1, MAX_GHOSTS).astype(np.int64)
    owner = np.repeat(walking, n)
    j = np.concatenate([np.arange(1, m + 1) for m in n])
    shift = look * j / np.repeat(n, n)
    g = obs[owner].copy()
    g[:, :2] += shift[:, None] * obs[owner, 2:4]
    half = 0.5 * speed[owner] * look / np.repeat(n, n)
    w = robot_radius + obs[owner, 4] + buffer
    cover = np.sqrt(w**2 + half**2) - (robot_radius + obs[owner, 4])
    return Ghosts(g, owner, shift, cover)


def ghost_window(ghosts: Ghosts, obs: FloatArray, pose_xy: FloatArray, robot_radius: float, margin0: FloatArray,
                 vplan: float, dt: float, horizon: float,
                 inflation: FloatArray | None = None) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """When each ghost is kept, in seconds after now: (appear (g,), vanish (g,)).

    A robot already in someone's way (its centre closer to the person's line than the
    zone's reach, ``robot_radius + radius + inflation`` plus the search's first-step margin
    ``margin0``) cannot keep off that person's ghosts from the start: one walking at it
    comes on faster than the robot backs away. Their ghosts appear only once the robot
    could have stepped out of the band sideways at ``ESCAPE_FACTOR`` times the time
    that takes at ``vplan`` (a roadmap seldom points exactly sideways), plus a step: the
    search must then take it out of the way by that time. Every ghost vanishes at
    ``horizon`` (the social horizon: far predictions are too uncertain to yield to).

    Parameters
    ----------
    ghosts : Ghosts
    obs : (k, 5) float
        The observations the ghosts come from.
    pose_xy : (2,) float
        The robot's reference point now.
    robot_radius : float
    margin0 : (g,) float
        The search's continuous-time margin at step 0 for each ghost.
    vplan, dt, horizon : float
    inflation : (g,) float, optional
        What the search inflates each ghost by (the band's ``cover`` and the uncertainty
        of the prediction that far ahead); default ``ghosts.cover``. The reach must be the
        zone the search keeps off: a robot inside the uncertainty's part of the zone but
        outside ``cover`` alone would otherwise start inside a ghost that is kept from
        the first step, and the search with the ghosts often finds nothing.

    Returns
    -------
    appear, vanish : (g,) float
    """
    own = obs[ghosts.owner]
    vel = own[:, 2:4]
    speed = np.maximum(np.hypot(vel[:, 0], vel[:, 1]), 1e-12)
    p = np.asarray(pose_xy, dtype=float)[:2]
    rel = p - own[:, :2]
    lateral = np.abs(vel[:, 0] * rel[:, 1] - vel[:, 1] * rel[:, 0]) / speed
    grown = ghosts.cover if inflation is None else np.asarray(inflation, dtype=float)
    reach = robot_radius + ghosts.obs[:, 4] + grown + np.asarray(margin0, dtype=float)
    escape = ESCAPE_FACTOR * np.maximum(reach - lateral, 0.0) / vplan + dt
    # in the way of this ghost: it passes within reach of the robot before it could step aside
    a = ghosts.obs[:, :2] - p
    d = vel * escape[:, None]
    s = np.clip(-np.einsum("ij,ij->i", a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-12), 0.0, 1.0)
    near = np.hypot(*(a + s[:, None] * d).T)
    appear = np.where((lateral < reach) & (near < reach), escape, 0.0)
    return appear, np.full(len(appear), float(horizon))



class WallCheck:
    """Which straight walks cross a static obstacle of a scene (people do not walk through
    walls: a ghost behind one is where the person will not be).

    Parameters
    ----------
    scene : Scene
        Its static obstacles (maps included); the bounds are not walls (people may walk
        outside the robot's bounds).
    """

    def __init__(self, scene):
        import shapely

        from ..roadmap.freespace import obstacle_shape

        shapes = [g for g in map(obstacle_shape, scene.obstacles) if g is not None]
        self.union = shapely.union_all(shapes) if shapes else None
        if self.union is not None:
            shapely.prepare(self.union)

    def crossed(self, a: FloatArray, b: FloatArray) -> BoolArray:
        """(n,) True where the segment from ``a`` (n, 2) to ``b`` (n, 2) meets an obstacle."""
        import shapely

        a = np.asarray(a, dtype=float).reshape(-1, 2)
        if self.union is None or len(a) == 0:
            return np.zeros(len(a), dtype=bool)
        lines = shapely.linestrings(np.stack([a, np.asarray(b, dtype=float).reshape(-1, 2)], axis=1))
        return np.asarray(shapely.intersects(lines, self.union), dtype=bool)


    def near(self, points: FloatArray, distance: FloatArray) -> BoolArray:
        """(n,) True where ``points`` (n, 2) lie within ``distance`` (n,) of an obstacle."""
        import shapely

        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if self.union is None or len(pts) == 0:
            return np.zeros(len(pts), dtype=bool)
        return np.asarray(shapely.dwithin(shapely.points(pts), self.union, np.asarray(distance, dtype=float)), dtype=bool)


def walled_off(ghosts: Ghosts, obs: FloatArray, walls: WallCheck, reach: FloatArray) -> BoolArray:
    """(g,) True for each ghost that its person could only reach through a static obstacle
    (walking straight on, they will turn or stop before it), or whose zone (``reach`` (g,)
    about its centre) meets one: in a passage there is no stepping out of someone's way,
    the robot and the person share it (and the person's own disc still keeps them apart)."""
    return walls.crossed(obs[ghosts.owner, :2], ghosts.obs[:, :2]) | walls.near(ghosts.obs[:, :2], reach)


class PathSpace:
    """The navigator's part that keeps off people's ways (a base of
    :class:`gfuzzy.navigation.navigator.Navigator`, whose state and searches it uses): the
    ghosts of the first search and of the relaxed one, and the path space's soft cost."""

    def _growth_rate(self, speed: FloatArray) -> FloatArray:
        """(k,) m/s at which the prediction of people walking at ``speed`` (k,) grows
        uncertain: with how far they may stray from the straight walk (someone standing is
        where they stand; a walker at the reference speed or faster may turn)."""
        opts = self.options
        return opts.uncertainty_growth * np.minimum(speed / opts.reference_speed, 1.0)

    def _step_margin(self, speed: FloatArray) -> FloatArray:
        """(k,) the search's continuous-time margin at step 0 against people at ``speed``."""
        return (self.vplan + speed) * self.options.dt / 2

    def _path_ghosts(self, pose: FloatArray, obs: FloatArray, escape: bool = True) -> tuple[FloatArray, FloatArray]:
        """The first search's ghosts (:mod:`gfuzzy.navigation.pathspace`): predicted discs
        along each walking person's next ``path_space`` seconds, as rows ``[x, y, vx, vy,
        radius, appear, vanish]`` (g, 7) (seconds after now), and their inflation (g, S): the
        band's cover, plus the uncertainty of the person's prediction at the ghost's shift."""
        opts = self.options
        cr = self.robot.circumradius
        gh = path_ghosts(obs, opts.path_space, cr, opts.safety_buffer, STILL_SPEED)
        speed = np.hypot(gh.obs[:, 2], gh.obs[:, 3])
        # a ghost is the person predicted s seconds further on: as uncertain as they are then
        grown = gh.cover + self._growth_rate(speed) * gh.shift
        window = ghost_window(gh, obs, pose, cr, self._step_margin(speed), self.vplan, opts.dt, opts.social_horizon,
                              grown)  # fmt: skip
        n_slices = int(math.ceil(opts.prediction_horizon / opts.slice - 1e-9))
        infl = np.repeat(grown[:, None], n_slices, axis=1)
        # none due after the social horizon, behind a wall from its person, or in a passage
        reach = cr + gh.obs[:, 4] + grown
        if not escape:  # priced, not forbidden: a robot in someone's way pays from the first step
            window = (np.zeros_like(window[0]), window[1])
        kept = (window[0] < window[1] - opts.dt) & ~walled_off(gh, obs, self._walls, reach)
        return np.column_stack([gh.obs, *window])[kept], infl[kept]

    def _with_ghosts(self, pose: FloatArray, obs: FloatArray, infl: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The people and their ghosts (:meth:`_path_ghosts`), when ``path_space`` is set:
        rows ``[x, y, vx, vy, radius, appear, vanish]`` and their inflation."""
        if self.options.path_space <= 0 or not len(obs):
            return obs, infl
        ghosts, g_infl = self._path_ghosts(pose, obs)
        always = np.column_stack([obs, np.zeros(len(obs)), np.full(len(obs), math.inf)])
        return np.vstack([always, ghosts]), np.vstack([infl, g_infl])

    def _tiers(self, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, deadline: float):
        """(plan, mode, search, ghosts kept) of the tiers: the ghosts and the personal space,
        then without the ghosts (:meth:`_path_space_cost`), then without the personal space
        (:meth:`_closer`)."""
        opts = self.options
        found = self._search(t, pose, *self._with_ghosts(pose, obs, infl), deadline)
        ghosts = opts.path_space > 0 and len(obs) > 0  # the plan keeps off the people's ways
        if ghosts and found.graph is not None and self._clock() < deadline:
            ghosted = found
            found = self._path_space_cost(t, pose, obs, infl, found, deadline)
            ghosts = found is ghosted
        traj, mode = found.trajectory, NavMode.PLAN
        if opts.personal_space > 0 and len(obs) and found.graph is not None and self._clock() < deadline:
            traj, mode, found = self._closer(t, pose, obs, found, deadline, ghosts)
        return traj, mode, found, ghosts

    def _path_space_cost(self, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, found: _Searched,
                         deadline: float) -> _Searched:  # fmt: skip
        """The path space as a soft cost: the plan that keeps off the people's ways, unless
        the same search without the ghosts arrives sooner by more than
        ``path_space_cost``, or the first found none (people who keep turning, such as
        someone circling a room, are not where their straight walk says: their ghosts can
        send the robot round a long way for nothing).

        The second search runs only when it can win: when the first found no plan, or when
        the first arrives later than the static lower bound (the roadmap's time to the
        goal) by more than the cost.
        """
        opts = self.options
        first = found.trajectory
        if first is not None:
            bound = float(found.graph.heuristic[found.start]) * opts.dt
            if first.t_end - t <= bound + opts.path_space_cost + 1e-9:
                return found
        elif found.out_of_time:
            return found
        plain = self._search(t, pose, obs, infl, deadline, found)
        second = plain.trajectory
        if second is not None and (first is None or second.t_end < first.t_end - opts.path_space_cost):
            return plain
        self._ahead = found.ahead  # the second search replaced the plan's vertices ahead
        return found if first is not None else plain

    def _relaxed(self, t: float, pose: FloatArray, obs: FloatArray, found: _Searched, deadline: float):
        """The relaxed search (the people's discs as they are, plus the mover clearance):
        first still keeping off the way people are about to walk (the ghosts, which a robot
        in someone's way must leave in time: a person walking up behind the robot or at it
        leaves no plan that keeps the personal space, but one that steps aside), then not.
        What the last search found (its ``out_of_time`` counts in the call's)."""
        infl = self._inflation(pose, obs, relaxed=True)
        if self.options.path_space > 0:
            again = self._search(t, pose, *self._with_ghosts(pose, obs, infl), deadline, found)
            if again.trajectory is not None or again.out_of_time or self._clock() > deadline:
                return again
        return self._search(t, pose, obs, infl, deadline, found)
