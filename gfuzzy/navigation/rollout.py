"""Predictions in which people avoid each other: the observed crowd rolled forward together.

The navigator predicts each person walking on at constant velocity. Two groups crossing
do not walk through each other: they slow down and part. :func:`rollout` moves everyone
seen forward together over the prediction horizon with an anticipatory crowd model, the
time-to-collision power law of Karamouzas, Skinner and Guy (Phys. Rev. Lett. 113, 2014):
each person relaxes towards the velocity they were seen walking at (they keep going where
they were going, at the speed they had), and is pushed by every other person with whom a
collision is coming, by ``k tau^-2 exp(-tau / tau0)`` in the direction that delays it.
Anticipation (not a repulsion by distance, as the social force) is what ORCA-like people
do: they start to part seconds before they meet, so a straight line is wrong from then on.

A second crowd model fills the same slot, :func:`orca_rollout`: everyone seen becomes an
ORCA agent (reciprocal velocity obstacles, van den Berg et al. 2011, through ``pyrvo``)
whose preferred velocity is the one seen, with generic pedestrian parameters
(:data:`ORCA_PEDESTRIAN`).

Either rollout is computed once per replan (``NavOptions.interaction``). In both nobody
walks faster than seen, so every bound the navigator puts on the gap between two samples
(a person's speed plus the robot's) still holds. The navigator's search then keeps off
each person's rolled path (a trajectory mover with one row per rollout step) instead of
their straight walk, with the same growing uncertainty, and the checks of a kept plan,
of the direct motion, of the previous plan and of the evasive motions measure the gaps
to the rolled paths too (:meth:`Rollout._person_positions`).
"""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray

__all__ = ["INTERACTIONS", "ORCA_PEDESTRIAN", "ROLL_STEP", "Rollout", "orca_rollout", "pairs", "path_may_reach",
           "path_speed", "rollout", "tracks", "ttc_force"]

#: The crowd models of ``NavOptions.interaction``: none (straight walks), the time-to-collision
#: power law (:func:`rollout`), ORCA (:func:`orca_rollout`).
INTERACTIONS = ("none", "ttc", "orca")

#: Integration step (s) of the rollout; its positions are the predicted path's vertices.
ROLL_STEP = 0.2
#: The power law's strength k (m^2/s^2 ... as in the paper, 1.5), exponent and horizon tau0 (s).
TTC_K = 1.5
TTC_POWER = 2.0
TTC_TAU0 = 3.0
#: Relaxation time (s) towards the velocity seen (the paper's 0.54 s).
RELAX = 0.54
#: Largest push (m/s^2) one person gets (the sum of the pairs' and the relaxation's): gentle,
#: so that nobody swerves into the robot's way within a step (at 5 m/s^2 the rollout
#: cost 3 more collisions in 100 episodes of 20 people crossing).
FORCE_CAP = 1.5
#: A person's predicted speed stays below the larger of their speed seen and this (m/s):
#: 0, nobody walks faster than seen (someone standing stays where they stand).
SPEED_FLOOR = 0.0


def pairs(xy: FloatArray, cap: FloatArray, radii: FloatArray, horizon: float) -> tuple[FloatArray, FloatArray]:
    """The pairs (i < j) of people who can touch within ``horizon`` seconds at speeds up to
    ``cap`` (k,): the others never push each other in the rollout."""
    i, j = np.triu_indices(len(xy), 1)
    d = np.hypot(xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1])
    near = d <= radii[i] + radii[j] + (cap[i] + cap[j]) * horizon
    return i[near], j[near]


def ttc_force(xy: FloatArray, vel: FloatArray, radii: FloatArray, i: FloatArray, j: FloatArray) -> FloatArray:
    """(k, 2) the time-to-collision push on each person from the others of the pairs
    ``(i, j)`` (each pair once).

    For a pair walking on at constant velocity, ``tau`` is the first time their discs
    touch; the energy ``k tau^-2 exp(-tau / tau0)`` falls as ``tau`` grows, and its
    gradient with respect to i's velocity points away from where j will be at the
    contact (j gets the opposite push). Pairs that never touch push nothing; a pair
    already overlapping pushes apart at :data:`FORCE_CAP`.

    Parameters
    ----------
    xy, vel : (k, 2) float
    radii : (k,) float
    i, j : (p,) int
    """
    k = len(xy)
    wx, wy = xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1]  # j relative to i
    vx, vy = vel[i, 0] - vel[j, 0], vel[i, 1] - vel[j, 1]  # i's velocity relative to j
    rad = radii[i] + radii[j]
    a = vx * vx + vy * vy
    b = wx * vx + wy * vy
    c = wx * wx + wy * wy - rad * rad
    disc = b * b - a * c
    root = np.sqrt(np.maximum(disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        tau = (b - root) / a
    hit = (c > 0) & (a > 1e-12) & (disc > 1e-12) & (tau > 0)
    tau = np.where(hit, tau, 1.0)
    root = np.where(hit, root, 1.0)
    # -d energy / d v_i = -mag (w - v tau): away from j's position at the contact
    mag = np.where(hit, TTC_K * np.exp(-tau / TTC_TAU0) / (root * tau**TTC_POWER) * (TTC_POWER / tau + 1.0 / TTC_TAU0), 0.0)
    fx, fy = -mag * (wx - vx * tau), -mag * (wy - vy * tau)
    over = c <= 0
    if over.any():  # already touching: straight apart
        d = np.maximum(np.hypot(wx, wy), 1e-9)
        fx, fy = np.where(over, -FORCE_CAP * wx / d, fx), np.where(over, -FORCE_CAP * wy / d, fy)
    force = np.column_stack([np.bincount(i, fx, k) - np.bincount(j, fx, k), np.bincount(i, fy, k) - np.bincount(j, fy, k)])
    return _capped(force, FORCE_CAP)


def _capped(vec: FloatArray, cap) -> FloatArray:
    """Rows of ``vec`` (k, 2) shortened to at most ``cap`` (scalar or (k,))."""
    n = np.hypot(vec[:, 0], vec[:, 1])
    scale = np.minimum(1.0, np.asarray(cap) / np.maximum(n, 1e-12))
    return vec * scale[:, None]


def rollout(xy: FloatArray, vel: FloatArray, radii: FloatArray, horizon: float, step: float = ROLL_STEP) -> FloatArray:
    """(n + 1, k, 2) everyone's predicted positions at ``0, step, ..., n step`` (``n step``
    the first multiple at or past ``horizon``), the people avoiding each other.

    Parameters
    ----------
    xy, vel : (k, 2) float
        Where each person is and the velocity they walk at (zero for someone standing).
    radii : (k,) float
        Their bodies (not inflated).
    horizon, step : float
        Seconds rolled, and the integration step (semi-implicit Euler).
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    v0 = np.asarray(vel, dtype=float).reshape(-1, 2)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    n = max(1, int(np.ceil(horizon / step - 1e-9)))
    out = np.empty((n + 1, len(xy), 2))
    out[0] = xy
    cap = np.maximum(np.hypot(v0[:, 0], v0[:, 1]), SPEED_FLOOR)
    i, j = pairs(xy, cap, radii, n * step)
    x, v = xy.copy(), v0.copy()
    for s in range(n):
        push = ttc_force(x, v, radii, i, j) if len(i) else 0.0
        v = _capped(v + _capped((v0 - v) / RELAX + push, FORCE_CAP) * step, cap)
        x = x + v * step
        out[s + 1] = x
    return out


#: Generic pedestrian parameters of the ORCA rollout (not the benchmark simulator's): a time
#: horizon of 3 s, the anticipation time Karamouzas et al. (2014) measured in pedestrian
#: data (interactions fade beyond it); neighbours within 8 m (two people walking at
#: each other at 1.3 m/s close 8 m in 3 s), at most 10 of them; the body radius seen plus
#: 0.05 m of the personal distance people keep from each other when passing.
ORCA_PEDESTRIAN = {"time_horizon": 3.0, "neighbor_dist": 8.0, "max_neighbors": 10, "clearance": 0.05}


def orca_rollout(xy: FloatArray, vel: FloatArray, radii: FloatArray, horizon: float, step: float = ROLL_STEP) -> FloatArray:
    """(n + 1, k, 2) everyone's predicted positions at ``0, step, ..., n step``, the people
    avoiding each other as ORCA agents (:data:`ORCA_PEDESTRIAN`) who prefer the velocity
    they were seen walking at and walk no faster than seen (someone standing stands)."""
    from .humans import _rvo

    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    v0 = np.asarray(vel, dtype=float).reshape(-1, 2)
    radii = np.asarray(radii, dtype=float).reshape(-1)
    n = max(1, int(np.ceil(horizon / step - 1e-9)))
    out = np.empty((n + 1, len(xy), 2))
    out[0] = xy
    o = ORCA_PEDESTRIAN
    cap = np.hypot(v0[:, 0], v0[:, 1])
    sim = _rvo().RVOSimulator(step, o["neighbor_dist"], o["max_neighbors"], o["time_horizon"], o["time_horizon"], 0.3, 1.0)
    ids = [sim.add_agent((float(x), float(y)), o["neighbor_dist"], o["max_neighbors"], o["time_horizon"], o["time_horizon"],
                         float(r) + o["clearance"], float(c), (float(vx), float(vy)))
           for (x, y), r, c, (vx, vy) in zip(xy, radii, cap, v0, strict=True)]  # fmt: skip
    for a, (vx, vy) in zip(ids, v0, strict=True):
        sim.set_agent_pref_velocity(a, (float(vx), float(vy)))
    for s in range(n):
        sim.do_step()
        for i, a in enumerate(ids):
            p = sim.get_agent_position(a)
            out[s + 1, i] = (p.x, p.y)
    return out


def tracks(t: float, path: FloatArray, step: float, until: float) -> FloatArray:
    """(m, 3) one person's rolled ``path`` (n + 1, 2) as a trajectory ``[time, x, y]`` from
    ``t``, standing at its last position until ``t + until`` when that is later."""
    n = len(path) - 1
    rows = np.column_stack([t + step * np.arange(n + 1), path])
    if until > n * step + 1e-9:
        rows = np.vstack([rows, [t + until, *path[-1]]])
    return rows


def path_may_reach(paths: FloatArray, step: float, pose_xy: FloatArray, vmax: float, look: FloatArray,
                   reach: FloatArray) -> FloatArray:  # fmt: skip
    """(k,) False for each person whose rolled path (n + 1, k, 2) (then standing at its end)
    certainly stays farther than ``reach`` (k,) from a robot that starts at ``pose_xy`` and
    moves at most ``vmax``, during the next ``look`` (k,) seconds: the rollout's version of
    the navigator's reach test. Between two vertices the distance changes no faster than
    the person's speed on that piece plus ``vmax``, so the smallest sampled value minus that
    rate times half a step bounds it from below."""
    n = len(paths) - 1
    tau = step * np.arange(n + 1)
    g = np.hypot(*(paths - pose_xy[:2]).transpose(2, 0, 1)) - vmax * tau[:, None]  # (n + 1, k)
    g = np.where(tau[:, None] <= look[None, :] + step, g, np.inf)
    low = g.min(axis=0) - (path_speed(paths, step) + vmax) * step / 2
    tail = np.hypot(*(paths[-1] - pose_xy[:2]).T) - vmax * np.maximum(look, n * step)  # standing at the end
    return np.minimum(low, np.where(look > n * step, tail, np.inf)) <= reach


def path_speed(paths: FloatArray, step: float) -> FloatArray:
    """(k,) each person's fastest speed along their rolled path."""
    return np.hypot(*np.diff(paths, axis=0).transpose(2, 0, 1)).max(axis=0, initial=0.0) / step


class Rollout:
    """The navigator's predictions along rolled paths (a base of
    :class:`gfuzzy.navigation.navigator.Navigator`, whose options and walks it uses), when
    ``NavOptions.interaction`` names a crowd model: :meth:`_roll` once per replan, then the
    reach tests (:meth:`_rolled_reach`), the field's movers (:meth:`_rolled_tracks`) and
    the gaps of the checks (:meth:`_person_positions`) follow each person's rolled path
    instead of their straight walk. A row of observations is matched to its rolled path
    by its position and velocity (the ghosts of the path space, shifted, match none)."""

    #: (n + 1, k, 2) the people of this replan's observation rolled forward, or None.
    _paths: FloatArray | None = None
    _rolled_rows: dict = {}

    def _roll(self, obs: FloatArray) -> None:
        model = self.options.interaction
        if model == "none" or not len(obs):
            self._paths, self._rolled_rows = None, {}
            return
        roll = orca_rollout if model == "orca" else rollout
        self._paths = roll(obs[:, :2], self._walks(obs)[0], obs[:, 4], self.options.prediction_horizon)
        self._rolled_rows = {tuple(r): i for i, r in enumerate(obs[:, :4].tolist())}

    def _rolled_index(self, obs: FloatArray) -> np.ndarray:
        """(k,) each row's person in the rolled paths, or -1 (a ghost, someone not rolled)."""
        if self._paths is None or not len(obs):
            return np.full(len(obs), -1, dtype=np.int64)
        return np.array([self._rolled_rows.get(tuple(r), -1) for r in obs[:, :4].tolist()], dtype=np.int64)

    def _rolled_reach(self, pose: FloatArray, obs: FloatArray, look, reach: FloatArray, keep: FloatArray) -> FloatArray:
        """``keep`` (a reach test of the straight walks) with every row whose rolled path may
        come within ``reach`` during ``look`` seconds kept too (either prediction may be the
        one checked: keeping both is safe)."""
        idx = self._rolled_index(obs)
        on = idx >= 0
        if not on.any():
            return keep
        look = np.broadcast_to(np.asarray(look, dtype=float), (len(obs),))[on]
        keep = keep.copy()
        keep[on] |= path_may_reach(self._paths[:, idx[on]], ROLL_STEP, pose, float(self.robot.vmax), look,
                                   np.broadcast_to(reach, (len(obs),))[on])  # fmt: skip
        return keep

    def _rolled_tracks(self, t: float, obs: FloatArray, vanish: FloatArray, tracked: list) -> list:
        """``tracked`` (the straight walks' trajectories of the field's movers) with those of
        the people rolled along their rolled paths."""
        for i, r in enumerate(self._rolled_index(obs)):
            if r >= 0:
                tracked[i] = tracks(t, self._paths[:, r], ROLL_STEP, vanish[i])
        return tracked

    def _person_positions(self, obs: FloatArray, tau: FloatArray) -> FloatArray:
        """(T, k, 2) where each row of ``obs`` is predicted ``tau`` (T,) seconds from now:
        along the rolled path (then on at its last velocity), or walking on as seen."""
        pos = obs[None, :, :2] + tau[:, None, None] * obs[None, :, 2:4]
        idx = self._rolled_index(obs)
        on = idx >= 0
        if on.any():
            paths = self._paths[:, idx[on]]
            n = len(paths) - 1
            x = np.clip(tau / ROLL_STEP, 0.0, None)
            i0 = np.minimum(np.floor(x).astype(np.int64), n - 1)
            f = (x - i0)[:, None, None]  # past the last row: on at the last piece's velocity
            pos[:, on] = paths[i0] + f * (paths[i0 + 1] - paths[i0])
        return pos
