"""The navigator's evasive motions (:meth:`Navigator._evasive`) and their score.

When no plan answers, the navigator takes the statically free straight motion (or
standing still) whose contact with the people walking on comes latest: this module
scores the candidates (:func:`evasion_scores`, for a differential drive's too) and picks
the holonomic robot's (:func:`holonomic_evasion`; a differential drive's is
:func:`gfuzzy.navigation.drivenav.drive_evasion`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..poses import metric_distance
from ..timespace.drive import reach_fraction
from ..trajectory import Trajectory
from ..typed import FloatArray
from .navtypes import MOTION_SAMPLE

if TYPE_CHECKING:
    from .navigator import Navigator

__all__ = ["EVASION_GAP", "TTC_POINTS", "evasion_scores", "holonomic_evasion"]

#: Gaps (m) wider than this score the same in the evasive motion.
EVASION_GAP = 0.5
#: Points of an evasive candidate's score per second of its time to contact (a gap's
#: metre is worth 10, a metre of progress 1).
TTC_POINTS = 100.0


def evasion_scores(nav: Navigator, t: float, pose: FloatArray, obs: FloatArray, pts: FloatArray,
                   times: FloatArray, ends: FloatArray, vel: FloatArray | None = None,
                   with_ttc: bool = False) -> FloatArray | tuple[FloatArray, FloatArray]:  # fmt: skip
    """(C,) score of candidate motions ``pts`` (C, T, d) at ``times`` ending at ``ends``:
    the latest contact first (no contact within the horizon beats any), then the widest
    gap while close, then progress to the goal; ``with_ttc``: also each one's time to
    contact (s from ``t``, inf: none within the horizon).

    ``vel`` (C, 2): each candidate's velocity when it translates and then stands (None:
    any motion within the speed bound). Between two samples ``h`` apart the gap to a
    person changes no faster than their relative speed ``R`` (a point of the robot moves
    at most ``vmax``), so it stays above ``(g_i + g_{i+1} - R h) / 2``: contact is that
    bound at or below 0, the gap not opening up (a robot touching someone backs out).
    """
    T = times[-1] - t
    tau = times - t
    obs = nav._near(pose, obs, T, EVASION_GAP)  # farther people change no score below
    if len(obs):
        walk = np.hypot(obs[:, 2], obs[:, 3])
        if vel is None:
            rate = np.broadcast_to(float(nav.robot.vmax) + walk, (len(pts), len(obs)))
        else:  # moving (relative velocity), then standing (the person's own)
            rel = np.hypot(vel[:, None, 0] - obs[None, :, 2], vel[:, None, 1] - obs[None, :, 3])
            rate = np.maximum(rel, walk[None, :])
        h = np.diff(tau)[None, :, None]
        # gaps above both EVASION_GAP and what the gap can lose between two samples score
        # alike (no contact, the widest gap capped): their lower bound will do
        alike = max(EVASION_GAP, float(rate.max(initial=0.0)) * float(h.max(initial=0.0))) + 1e-9
        each = nav._clearance_along(pts, times, obs, exact_below=alike)  # (C, T, k)
        between = each[:, :-1] + each[:, 1:]  # in place, then halved after the minimum (exact: a power of 2)
        between -= rate[:, None, :] * h
        between = between.min(axis=-1) / 2  # (C, T - 1)
        gap = each.min(axis=-1)  # (C, T)
        later = gap[:, 1:]
        hit = (between <= 0) & (later <= gap[:, :1])
        ttc = np.where(hit.any(axis=1), tau[1:][np.argmax(hit, axis=1)], math.inf)
        worst = later.min(axis=1)
    else:
        ttc = np.full(len(pts), math.inf)
        worst = np.full(len(pts), math.inf)
    cr = nav.robot.circumradius
    progress = metric_distance(pose, nav.goal, cr) - metric_distance(ends, nav.goal[None], cr)
    score = np.minimum(ttc, T + 1.0) * TTC_POINTS + np.minimum(worst, EVASION_GAP) * 10.0 + progress
    return (score, ttc) if with_ttc else score


def holonomic_evasion(nav: Navigator, t: float, pose: FloatArray, obs: FloatArray) -> Trajectory:
    """The holonomic robot's evasive motion (:meth:`Navigator._evasive`): of straight
    motions in ``evasion_headings`` directions at full and half speed, each going on for
    ``evasion_time`` (or half, or a quarter of it, whichever is free of static obstacles)
    and then standing, and of standing still, the best by :func:`evasion_scores`."""
    opts = nav.options
    cr = nav.robot.circumradius
    T = opts.evasion_time
    n_t = int(math.ceil(T / MOTION_SAMPLE)) + 1
    times = t + np.linspace(0.0, T, n_t)
    ang = np.arange(opts.evasion_headings) * (2 * math.pi / opts.evasion_headings)
    speeds = np.array([1.0, 0.5]) * nav.vplan
    dirs = np.column_stack([np.cos(ang), np.sin(ang)])
    vel = np.vstack([np.zeros((1, 2)), (speeds[:, None, None] * dirs[None]).reshape(-1, 2)])  # (C, 2)
    move_time = np.zeros(len(vel))
    free = np.zeros(len(vel), dtype=bool)
    free[0] = True
    for c in range(1, len(vel)):
        frac = reach_fraction(nav.geometry, pose, vel[c] * T)
        if frac is not None:
            free[c] = True
            move_time[c] = T * frac
    ends = np.repeat(pose[None], len(vel), axis=0)
    ends[:, :2] += vel * move_time[:, None]
    tau = times - t
    frac = np.clip(tau[None, :] / np.maximum(move_time[:, None], 1e-12), 0.0, 1.0)  # moves, then stands
    pts = pose[None, None, :] + frac[:, :, None] * (ends - pose[None])[:, None, :]  # (C, T, d)
    score = np.where(free, evasion_scores(nav, t, pose, obs, pts, times, ends, vel), -math.inf)
    c = int(np.argmax(score))
    if c == 0:
        rows = np.array([[t, *pose], [t + max(T, opts.cover), *pose]])
    else:
        rows = np.array([[t, *pose], [t + move_time[c], *ends[c]]])
        if opts.cover > move_time[c]:
            rows = np.vstack([rows, [t + opts.cover, *ends[c]]])
    return Trajectory(rows, cr)
