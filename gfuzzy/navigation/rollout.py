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

The rollout is vectorised over the pairs and computed once per replan; the navigator's
search then keeps off each person's rolled path (a trajectory mover with one row per
rollout step) instead of their straight walk, with the same growing uncertainty.
"""

from __future__ import annotations

import numpy as np

from ..typed import FloatArray

__all__ = ["ROLL_STEP", "Rollout", "pairs", "path_may_reach", "path_speed", "rollout", "tracks", "ttc_force"]

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
    """The navigator's predictions along rolled paths (a mixin of
    :class:`gfuzzy.navigation.navigator.Navigator`, whose options and walks it uses), when
    ``NavOptions.interaction`` is set: :meth:`_roll` once per replan, then the reach test
    (:meth:`_rolled_reach`) and the field's movers (:meth:`_rolled_tracks`) follow each
    person's rolled path instead of their straight walk."""

    #: (n + 1, k, 2) the people of this replan's observation rolled forward, or None.
    _paths: FloatArray | None = None

    def _roll(self, obs: FloatArray) -> None:
        opts = self.options
        if not opts.interaction or not len(obs):
            self._paths = None
            return
        self._paths = rollout(obs[:, :2], self._walks(obs)[0], obs[:, 4], opts.prediction_horizon)

    def _rolled_reach(self, pose: FloatArray, obs: FloatArray, look: FloatArray, reach: FloatArray,
                      keep: FloatArray) -> FloatArray:  # fmt: skip
        """``keep`` (the reach test of the straight walks) with the people's rows (the first
        of ``obs``; ghosts follow) tested along their rolled paths instead: their reach grows
        by the search's step margin at their fastest rolled speed."""
        if self._paths is None:
            return keep
        m = min(self._paths.shape[1], len(obs))
        paths = self._paths[:, :m]
        vel = self._walks(obs[:m])[0]
        walk = np.hypot(vel[:, 0], vel[:, 1])
        grown = reach[:m] + np.maximum(path_speed(paths, ROLL_STEP) - walk, 0.0) * self.options.dt
        keep = keep.copy()
        keep[:m] = path_may_reach(paths, ROLL_STEP, pose, float(self.robot.vmax), look[:m], grown)
        return keep

    def _rolled_tracks(self, t: float, rows, vanish: FloatArray, tracked: list) -> list:
        """``tracked`` (the straight walks' trajectories of the field's movers) with those of
        the people (``rows``: each mover's row of this replan's observation; ghosts' rows come
        after the people's) along their rolled paths."""
        if self._paths is None:
            return tracked
        for i, r in enumerate(rows):
            if r < self._paths.shape[1]:
                tracked[i] = tracks(t, self._paths[:, r], ROLL_STEP, vanish[i])
        return tracked
