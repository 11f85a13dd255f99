"""Timing a differential drive's speed layer among the movers.

The profile (:func:`gfuzzy.fuzzy.driveprofile.drive_profile`) is at rest at every corner:
the robot brakes to rest before each turn in place and after it. The chain the safe-interval
search runs on is cut at those rests: each stretch from rest to rest is driven at its
profile on the time grid, its last step stretched to end at the rest exactly on a grid time,
so that

* no step of the chain crosses a corner (every row is a wait, a turn in place or a straight
  move along the heading, exactly);
* the robot may wait at a rest without breaking the acceleration bound (it is at rest
  there), so waits are allowed at every corner from the first round on;
* a stretch's last step covers at most ``amax dt^2 / 2`` (it ends at rest), and the step
  before it differs from it in mean speed by at most ``amax dt``: the stretched step keeps the
  acceleration bound between rows.

Where the movers require more waiting, a search that may wait anywhere shows where, each of
its waits becomes a rest of the profile, and the search runs again (as
:func:`gfuzzy.planner.retime.retime_profile` does, but with every wait its own stop: a
differential drive creeps behind a mover the way the search found).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ..fuzzy.driveprofile import SAME_HEADING, STILL_XY, drive_profile
from ..fuzzy.profile import limit_acceleration, profile_times
from ..poses import pose_at
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..typed import FloatArray
from .retime import PROFILE_GROUP, ProfileRetime, _search_chain, s_at

if TYPE_CHECKING:
    from ..fuzzy.rules import RuleBase

__all__ = ["retime_drive", "drive_chain", "DRIVE_GROUP"]

#: Nodes per group of the chain whose safety the movers' field computes together: pairs
#: (see :func:`gfuzzy.planner.retime._search_chain`).
DRIVE_GROUP = PROFILE_GROUP


def drive_chain(path, knots, s_p, v_p, rests, dt) -> tuple[FloatArray, FloatArray]:
    """The chain of a differential drive's profile: points one time step apart, a point at
    every rest.

    Parameters
    ----------
    path : (n, 3) float
    knots : (n,) float
        Metric arc lengths of the path's poses.
    s_p, v_p : (k,) float
        The profile; every rest is one of its samples, with speed 0.
    rests : (r,) float
        Increasing arc lengths where the profile is at rest, 0 and the length included.
    dt : float

    Returns
    -------
    poses : (m, 3) float
    s : (m,) float
        Their arc lengths, increasing.
    """
    t = profile_times(s_p, v_p)
    at = np.searchsorted(s_p, rests)
    pieces = [np.array([s_p[0]])]
    for a, b in zip(at[:-1], at[1:], strict=True):
        n = max(1, int(math.ceil((t[b] - t[a]) / dt - 1e-9)))
        inner = s_at(t[a] + np.arange(1, n) * dt, s_p, v_p, t)
        inner = inner[(inner > s_p[a] + 1e-12) & (inner < s_p[b] - 1e-12)]
        pieces += [inner, np.array([s_p[b]])]
    s = np.concatenate(pieces)
    return pose_at(knots, path, s), s


def _without_null_motions(path: FloatArray) -> FloatArray:
    """``path`` without the poses that neither move (``STILL_XY``) nor turn (``SAME_HEADING``)
    from the one before: rounding leftovers, which would be motions of no length."""
    d = np.diff(path[:, :2], axis=0)
    dh = np.abs((np.diff(path[:, 2]) + math.pi) % (2 * math.pi) - math.pi)
    null = (np.hypot(d[:, 0], d[:, 1]) <= STILL_XY) & (dh <= SAME_HEADING)
    keep = np.concatenate([[True], ~null])
    keep[-1] = True  # the goal pose stays exactly
    if null[-1] and len(path) > 2:
        keep[-2] = False
    return path[keep]


def _with_stops(s_m, v_m, stops, amax):
    """The profile brought to rest at ``stops`` too (a sample between any two)."""
    if not stops:
        return s_m, v_m
    s_p = np.unique(np.concatenate([s_m, stops]))
    s_p = np.unique(np.concatenate([s_p, 0.5 * (s_p[1:] + s_p[:-1])]))
    cap = np.sqrt(np.interp(s_p, s_m, v_m**2))
    cap[np.isin(s_p, stops)] = 0.0
    return s_p, limit_acceleration(s_p, cap, amax)


def retime_drive(
    scene: Scene,
    path: FloatArray,
    t0: float,
    dt: float,
    amax: float,
    horizon: float,
    rulebase: RuleBase | None = None,
    deadline: float = math.inf,
    max_rounds: int = 5,
    hold: float = 0.0,
) -> ProfileRetime:
    """Time a differential drive's path under its speed layer, among the movers.

    Parameters
    ----------
    scene : Scene
        Its robot a differential drive (``kinematics: unicycle``).
    path : (n, 3) float
        Statically free path of turns in place and straight moves, no repeated pose.
    t0, dt : float
    amax : float
        Bound on the metric acceleration (``amax / r`` rad/s^2 in a turn).
    horizon : float
        Longest duration considered, seconds.
    rulebase : RuleBase, optional
        The fuzzy rules (default the expert rules).
    deadline : float
        ``time.perf_counter()`` value past which the answer is ``timeout``.
    max_rounds : int
        Searches among the movers, at most.
    hold : float
        Seconds the goal pose must stay safe after the arrival.

    Returns
    -------
    ProfileRetime
        ``waits``: the stops added for the movers (arc lengths); ``profile_duration``: the
        profile's duration without the movers.
    """
    robot = scene.robot
    path = _without_null_motions(np.asarray(path, dtype=float))
    prof = drive_profile(path, robot.circumradius, robot.vmax * SPEED_SAFETY, amax,
                         robot.turn_rate * SPEED_SAFETY, rulebase)  # fmt: skip
    duration = float(profile_times(prof.s, prof.v)[-1])
    total = float(prof.knots[-1])
    stops: list[float] = []
    message = ""
    for _ in range(max_rounds):
        s_p, v_p = _with_stops(prof.s, prof.v, stops, amax)
        rests = np.unique(np.concatenate([[0.0, total], prof.stops, stops]))
        poses, s = drive_chain(path, prof.knots, s_p, v_p, rests, dt)
        res = _search_chain(scene, poses, s, t0, dt, horizon, rests[:-1], deadline, hold=hold, group=DRIVE_GROUP)
        if res.status is Status.SOLVED:
            return ProfileRetime(Status.SOLVED, res.trajectory, waits=stops, profile_duration=duration)
        message = res.message
        if res.status is Status.TIMEOUT:
            break
        # where would the robot need to wait? search again allowing waits anywhere
        free = _search_chain(scene, poses, s, t0, dt, horizon, None, deadline, hold=hold, group=DRIVE_GROUP)
        if free.status is not Status.SOLVED:
            message = free.message or message
            break
        merged = sorted(set(stops) | {w for w in free.waits if 1e-9 < w < total - 1e-9})
        if merged == stops:
            break
        stops = merged
    return ProfileRetime(Status.NO_PATH, None, message or "no safe timing found", profile_duration=duration)
