"""The differential drive's side of the navigator (:class:`gfuzzy.navigation.navigator.Navigator`
with ``kinematics: unicycle``).

A unicycle turns in place, so a plan that changes its mind costs time: every replan that
starts a turn the next one undoes wastes the turn (at 1 rad/s a quarter turn takes 1.6 s).
:func:`kept_plan` keeps the last plan while it stays as safe as a fresh one would be (the
same inflated predictions) and arrives not much later than the fresh one.
"""

from __future__ import annotations

import math

import numpy as np

from ..poses import metric_distance
from ..timespace.drive import evasions
from ..trajectory import Trajectory
from ..typed import FloatArray
from .evasion import evasion_scores
from .navtypes import MOTION_SAMPLE, sample_loss

__all__ = ["kept_plan", "cut_rows", "drive_evasion", "swerved", "SWERVE", "EVASION_COMMIT"]

#: Angle (rad) by which each person's observed walk is also turned, both ways, when a
#: differential drive's evasions are scored: people swerve round each other, and a robot
#: that must turn before it moves sideways cannot answer a swerve once it has begun.
SWERVE = math.radians(25.0)
#: Score (:func:`gfuzzy.navigation.evasion.evasion_scores`: 100 per second of time to
#: contact) by which a new evasion must beat the last one, still under way, to replace it:
#: an evasion that turns one way and then the other loses both turns.
EVASION_COMMIT = 5.0


def cut_rows(traj: Trajectory, ta: float, tb: float) -> FloatArray:
    """Rows of ``traj`` between ``ta`` and ``tb`` (both ends interpolated), t strictly increasing."""
    w = traj.waypoints
    inner = w[(w[:, 0] > ta + 1e-9) & (w[:, 0] < tb - 1e-9)]
    rows = [np.array([ta, *traj.at(ta)])[None], inner]
    if tb > ta + 1e-9:
        rows.append(np.array([tb, *traj.at(tb)])[None])
    return np.vstack(rows)


def kept_plan(nav, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, fresh: Trajectory,
              slack: float) -> Trajectory | None:  # fmt: skip
    """The navigator's last plan from ``t`` on, when it is worth keeping instead of ``fresh``.

    Kept when the robot is on it, it arrives at most ``slack`` seconds after ``fresh``, and
    it keeps, at every sample ``MOTION_SAMPLE`` apart over the prediction horizon, the
    inflated gap ``infl`` (k, S) the fresh search kept from each person walking on at
    constant velocity (plus what the gap can lose between two samples).

    Parameters
    ----------
    nav : Navigator
    t : float
    pose : (3,) float
    obs : (k, 5) float
        ``[x, y, vx, vy, radius]`` per person seen.
    infl : (k, S) float
        Inflation per person and prediction slice (the fresh search's).
    fresh : Trajectory
        The fresh plan.
    slack : float
        Seconds the kept plan may arrive later than the fresh one.

    Returns
    -------
    Trajectory or None
    """
    prev = nav._previous
    if prev is None or slack <= 0 or prev.t_end <= t + 1e-9 or prev.t_end > fresh.t_end + slack:
        return None
    cr = nav.robot.circumradius
    if float(metric_distance(prev.at(t), pose, cr)) > 1e-6:
        return None
    rows = cut_rows(prev, t, prev.t_end)
    rows[0, 1:] = pose
    traj = Trajectory(rows, cr)
    opts = nav.options
    horizon = opts.prediction_horizon
    if len(obs) == 0:
        return traj
    # only the people who may come within the inflation of the robot matter
    reach = obs[:, 4] + cr + nav.mover_clearance + float(np.max(infl, initial=0.0)) + 0.1
    keep = nav._may_reach(pose, obs[:, :2], obs[:, 2:4], math.inf, horizon, reach)
    if not keep.any():
        return traj
    near, infl = obs[keep], infl[keep]
    times = t + np.arange(0.0, horizon + 1e-9, MOTION_SAMPLE)
    pts = traj.at(np.minimum(times, traj.t_end))
    gap = nav._clearance_along(pts, times, near) + nav.mover_clearance  # (T, k)
    s_of = np.minimum(np.floor((times - t) / opts.slice + 1e-9).astype(np.int64), infl.shape[1] - 1)
    speed = np.hypot(near[:, 2], near[:, 3])
    lost = sample_loss(nav.vplan, speed)  # (k,) the gap's fall between two samples
    if np.any(gap < infl[:, s_of].T + lost[None, :]):
        return None
    return traj



def swerved(obs: FloatArray, angle: float) -> FloatArray:
    """The people ``obs`` (k, 5), then each again with their walk turned by ``+angle`` and
    by ``-angle``: (3k, 5) (k when ``angle`` is 0)."""
    if angle == 0 or len(obs) == 0:
        return obs
    out = [obs]
    for a in (angle, -angle):
        c, s = math.cos(a), math.sin(a)
        turned = obs.copy()
        turned[:, 2] = c * obs[:, 2] - s * obs[:, 3]
        turned[:, 3] = s * obs[:, 2] + c * obs[:, 3]
        out.append(turned)
    return np.vstack(out)


def drive_evasion(nav, t: float, pose: FloatArray, obs: FloatArray, times: FloatArray) -> Trajectory:
    """A differential drive's evasive motion (:meth:`Navigator._evasive`'s for a unicycle).

    The candidates of :func:`gfuzzy.timespace.drive.evasions` (standing, or a turn in
    place and a straight move), and the last evasion from ``t`` on when the robot is on
    it, are scored by :func:`gfuzzy.navigation.evasion.evasion_scores` against the people
    walking on as seen and against each walk turned by :data:`SWERVE` both ways (the
    earliest contact counts); the last evasion is kept unless a new one scores
    :data:`EVASION_COMMIT` more.

    Parameters
    ----------
    nav : Navigator
    t : float
    pose : (3,) float
    obs : (k, 5) float
    times : (T,) float
        Sample times from ``t`` over ``evasion_time``.

    Returns
    -------
    Trajectory
        Rows from ``[t, *pose]``: waits, turns in place and straight moves only.
    """
    opts = nav.options
    cr = nav.robot.circumradius
    cands = evasions(nav.geometry, t, pose, times[-1] - t, opts.cover, opts.evasion_headings, nav.vplan)
    prev = nav._evasion
    on_prev = (prev is not None and prev.t_end > t + 1e-9
               and float(metric_distance(prev.at(t), pose, cr)) <= 1e-6)  # fmt: skip
    if on_prev:
        rows = cut_rows(prev, t, prev.t_end)
        rows[0, 1:] = pose
        cands.append(rows)
    trajs = [Trajectory(rows, cr) for rows in cands]
    pts = np.stack([tr.at(np.minimum(times, tr.t_end)) for tr in trajs])
    ends = np.array([rows[-1, 1:] for rows in cands])
    score = evasion_scores(nav, t, pose, swerved(obs, SWERVE), pts, times, ends)
    best = int(np.argmax(score))
    if on_prev and score[-1] >= score[best] - EVASION_COMMIT:
        best = len(trajs) - 1
    nav._evasion = trajs[best]
    return trajs[best]
