"""The differential drive's side of the navigator (:class:`gfuzzy.navigation.navigator.Navigator`
with ``kinematics: unicycle``).

A unicycle turns in place, so a plan that changes its mind costs time: every replan that
starts a turn the next one undoes wastes the turn (at 1 rad/s a quarter turn takes 1.6 s).
:func:`kept_plan` keeps the last plan while it stays as safe as a fresh one would be (the
same inflated predictions) and arrives not much later than the fresh one; for the same
reason :func:`drive_evasion` does not undo the turn of the evasion under way unless a
candidate turning back meets people ``EVASION_COMMITMENT`` seconds later.

The same test of a kept plan serves the holonomic robot too: :func:`sooner_plan` keeps
the last plan when it arrives much sooner than the fresh one (by more than the soft costs
together), a fresh search having missed it.
"""

from __future__ import annotations

import math

import numpy as np

from ..poses import metric_distance, wrap_angle
from ..timespace.drive import evasions
from ..timespace.timespace import timed_rows
from ..trajectory import Trajectory
from ..typed import FloatArray
from .evasion import EVASION_GAP, TTC_POINTS, evasion_scores
from .navtypes import MOTION_SAMPLE, sample_loss

__all__ = ["kept_plan", "sooner_plan", "cut_rows", "rest_of", "drive_evasion", "static_route", "sample_rows", "turn_under_way",
           "EVASION_SPEEDS", "EVASION_STOPS", "EVASION_COMMITMENT", "COMMITTED_TURN"]

#: Speeds (fractions of the planning speed) of a differential drive's evasive candidates.
EVASION_SPEEDS = (1.0, 0.5, 0.25)
#: Seconds after which an evasive candidate may also stop (and stand) instead of driving on.
EVASION_STOPS = (0.5, 1.0)
#: Points (in seconds of time to contact, ``TTC_POINTS`` each) an evasive candidate that
#: keeps clear over the look-ahead and turns against the turn in place of the evasion under
#: way loses: among candidates that all keep clear the gap and progress terms of the score
#: flip with every step of the turn, and a robot re-deciding every period turned back and
#: forth in place while someone walked into it. Candidates predicted to touch someone are
#: left to their time to contact.
EVASION_COMMITMENT = 0.1
#: A turn under way smaller than this (rad) is done: it commits to nothing.
COMMITTED_TURN = 1e-3


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
    return _if_safe(nav, prev, t, pose, obs, infl)


def sooner_plan(nav, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, fresh: Trajectory,
                gain: float) -> Trajectory | None:  # fmt: skip
    """The navigator's last plan from ``t`` on, when it arrives more than ``gain`` seconds
    before ``fresh`` and still keeps, as :func:`kept_plan` checks, the inflated gap ``infl``
    (k, S) it was made with from everyone walking on at constant velocity.

    A fresh search may miss a plan the last one found (its budget spent on a long detour
    before the soft costs' second search could run, a graph spliced differently): without
    this, a robot among people standing still went back and forth between two plans, one
    keeping the personal space round the crowd and one passing closer, until time ran out.
    """
    prev = nav._previous
    if prev is None or prev.t_end <= t + 1e-9 or prev.t_end >= fresh.t_end - gain:
        return None
    return _if_safe(nav, prev, t, pose, obs, infl)


def rest_of(prev: Trajectory, t: float, pose: FloatArray) -> Trajectory | None:
    """``prev`` from ``t`` on, starting exactly at ``pose``, if the robot is on it (within
    1e-6 in the metric of :func:`gfuzzy.poses.metric_distance`); None otherwise."""
    cr = prev.circumradius
    if float(metric_distance(prev.at(t), pose, cr)) > 1e-6:
        return None
    rows = cut_rows(prev, t, prev.t_end)
    rows[0, 1:] = pose
    return Trajectory(rows, cr)


def _if_safe(nav, prev: Trajectory, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray) -> Trajectory | None:
    """``prev`` from ``t`` on, if the robot is on it and it keeps the gaps ``infl`` (k, S)."""
    traj = rest_of(prev, t, pose)
    if traj is None:
        return None
    cr = nav.robot.circumradius
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


def drive_evasion(nav, t: float, pose: FloatArray, obs: FloatArray, under_way: Trajectory | None = None) -> Trajectory:
    """A differential drive's evasive motion (:meth:`Navigator._evasive`'s for a unicycle):
    the candidate of :func:`gfuzzy.timespace.drive.evasions` (standing, or a turn in place
    and a straight move at one of ``EVASION_SPEEDS``, going on or stopping after one of
    ``EVASION_STOPS``; straight back without turning too with ``robot.reverse``) that
    :func:`gfuzzy.navigation.evasion.evasion_scores` scores best against the people
    walking on as seen, over ``NavOptions.drive_lookahead`` seconds.

    A unicycle's escape starts with a turn in place, during which it stands: a look-ahead
    as short as a holonomic robot's (``evasion_time``) finds no contact within it for
    driving straight on into someone's way and prefers it to a turn that avoids them.

    A candidate that keeps clear over the look-ahead and turns against the turn in place of
    ``under_way`` (the last answer, an evasion, still turning at ``t`` by more than
    ``COMMITTED_TURN``) loses ``EVASION_COMMITMENT`` seconds' worth of score: a turn undone
    is a turn wasted. Where contact is predicted, the time to contact decides alone.

    Parameters
    ----------
    nav : Navigator
    t : float
    pose : (3,) float
    obs : (k, 5) float
    under_way : Trajectory, optional
        The evasion the robot is following (None: none).

    Returns
    -------
    Trajectory
        Rows from ``[t, *pose]``: waits, turns in place and straight moves only.
    """
    opts = nav.options
    T = opts.drive_lookahead
    times = t + look_times(opts.evasion_time, T)
    cands = evasions(nav.geometry, t, pose, T, opts.cover, opts.evasion_headings, nav.vplan, EVASION_SPEEDS, EVASION_STOPS)
    pts = sample_rows(cands, times)
    ends = np.array([rows[-1, 1:] for rows in cands])
    score, ttc = evasion_scores(nav, t, pose, obs, pts, times, ends, with_ttc=True)
    turn = turn_under_way(under_way, t, pose)
    if abs(turn) > COMMITTED_TURN:
        # only among candidates that keep clear over the whole look-ahead: where contact is
        # predicted the time to contact, sampled, must decide (committing there drove a
        # robot into someone it would have escaped by turning back)
        back = (np.array([_first_turn(rows) for rows in cands]) * turn < 0.0) & np.isinf(ttc)
        score = np.where(back, score - EVASION_COMMITMENT * TTC_POINTS, score)
    best = cands[int(np.argmax(score))]
    return Trajectory(best, nav.robot.circumradius)


def static_route(nav, t: float, pose: FloatArray, obs: FloatArray, graph, s_id: int) -> Trajectory | None:
    """A differential drive's way on when no fresh plan came in time and nobody is near: its
    static route, the spliced ``graph``'s shortest way from ``s_id`` to the goal (down its
    exact steps-to-goal heuristic, one step of ``NavOptions.dt`` a point), timed from ``t``.

    Only when no one seen can come within ``EVASION_GAP`` of any place the robot can reach
    over ``NavOptions.drive_lookahead`` (:meth:`Navigator._near`): there every evasive
    candidate keeps clear, the evasion ranks them by straight-line progress alone, and
    where the way to the goal leads round a wall it stood still for ever (a newcomer's
    box on a house map, its search out of time: 600 evasive answers, still at t = 150 s).
    None otherwise, or without a graph or a way down (the evasive motion answers).
    """
    if graph is None or s_id < 0 or len(nav._near(pose, obs, nav.options.drive_lookahead, EVASION_GAP)):
        return None
    h, indptr, nbrs = graph.heuristic, graph.indptr, graph.neighbors
    if not math.isfinite(h[s_id]):
        return None
    nodes, v = [s_id], s_id
    while v != nav._g_id:
        nb = nbrs[indptr[v] : indptr[v + 1]]
        down = nb[h[nb] <= h[v] - 1.0 + 1e-9]
        if len(down) == 0 or len(nodes) > h[s_id]:
            return None
        v = int(down[0])
        nodes.append(v)
    rows, _ = timed_rows(nodes, list(range(len(nodes))), graph.poses, t, nav.options.dt)
    rows[0, 1:] = pose
    rows[-1, 1:] = nav.goal
    return Trajectory(rows, nav.robot.circumradius)


def turn_under_way(prev: Trajectory | None, t: float, pose: FloatArray) -> float:
    """The signed turn in place (rad) left of ``prev`` at ``t``, when the robot is on it at
    ``pose`` and turning there; 0 otherwise (no ``prev``, off it, driving or standing)."""
    if prev is None or prev.t_end <= t + 1e-9:
        return 0.0
    rest = rest_of(prev, t, pose)
    return 0.0 if rest is None else _first_turn(rest.waypoints)


def _first_turn(rows: FloatArray) -> float:
    """The signed heading change (rad) of the first row step of ``rows`` (r, 4) when it turns
    in place; 0 when it moves or stands."""
    if len(rows) < 2 or float(np.hypot(*(rows[1, 1:3] - rows[0, 1:3]))) > 1e-9:
        return 0.0
    return float(wrap_angle(rows[1, 3] - rows[0, 3]))


def look_times(near: float, far: float) -> FloatArray:
    """Sample times (s from now) of an evasion's look-ahead: every ``MOTION_SAMPLE`` over the
    first ``near`` seconds, twice as far apart from there to ``far`` (the scores bound the
    gap between samples whatever their spacing; far contacts need less precision)."""
    near = min(near, far)
    first = np.linspace(0.0, near, int(math.ceil(near / MOTION_SAMPLE)) + 1)
    rest = far - near
    if rest <= 1e-9:
        return first
    return np.concatenate([first, near + np.linspace(0.0, rest, int(math.ceil(rest / (2 * MOTION_SAMPLE))) + 1)[1:]])


def sample_rows(cands: list, times: FloatArray) -> FloatArray:
    """(C, T, 3) poses of each candidate's rows (r_c, 4) at ``times`` (T,), standing after
    its last row (each row's heading reached along the shorter arc, as :func:`gfuzzy.poses.pose_at`)."""
    n = max(len(rows) for rows in cands)
    pad = np.empty((len(cands), n, 4))  # (C, n, 4): each candidate's rows, its last repeated
    for c, rows in enumerate(cands):
        pad[c, : len(rows)] = rows
        pad[c, len(rows) :] = rows[-1]
    pad[:, :, 0] = np.maximum.accumulate(pad[:, :, 0], axis=1)
    knots = pad[:, :, 0]
    i = np.clip((knots[:, None, :] <= times[None, :, None]).sum(axis=2) - 1, 0, n - 2)  # (C, T)
    c = np.arange(len(cands))[:, None]
    ta, tb = knots[c, i], knots[c, i + 1]
    seg = tb - ta
    f = np.where(seg > 0, np.clip((times[None, :] - ta) / np.where(seg > 0, seg, 1.0), 0.0, 1.0), 0.0)
    a, b = pad[c, i, 1:], pad[c, i + 1, 1:]
    out = a + f[..., None] * (b - a)
    out[..., 2] = wrap_angle(a[..., 2] + f * wrap_angle(b[..., 2] - a[..., 2]))
    return out
