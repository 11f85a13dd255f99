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

from ..fuzzy.driveprofile import SAME_HEADING, STILL_XY, DriveProfile, drive_profile
from ..fuzzy.profile import limit_acceleration, profile_times
from ..poses import pose_at
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..typed import FloatArray
from .retime import PROFILE_GROUP, ChainFields, ProfileRetime, _search_chain, s_at

if TYPE_CHECKING:
    from ..fuzzy.rules import RuleBase

__all__ = ["retime_drive", "drive_chain", "DriveTiming", "leg_speeds", "DRIVE_GROUP"]

#: Nodes per group of the chain whose safety the movers' field computes together: pairs
#: (see :func:`gfuzzy.planner.retime._search_chain`).
DRIVE_GROUP = PROFILE_GROUP


def drive_chain(path, knots, s_p, v_p, rests, dt, haste=None) -> tuple[FloatArray, FloatArray]:
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
    haste : (r - 1,) float, optional
        For each stretch between two rests: its metric speed when it is driven at the
        search's pace (equal steps of at most that speed times ``dt``), or 0 to drive the
        profile (its last step stretched to end at the rest). Default: the profile everywhere.

    Returns
    -------
    poses : (m, 3) float
    s : (m,) float
        Their arc lengths, increasing.
    """
    t = profile_times(s_p, v_p)
    at = np.searchsorted(s_p, rests)
    haste = np.zeros(len(rests) - 1) if haste is None else haste
    pieces = [np.array([s_p[0]])]
    for a, b, speed in zip(at[:-1], at[1:], haste, strict=True):
        lo, hi = s_p[a], s_p[b]
        if speed > 0:
            n = max(1, int(math.ceil((hi - lo) / (speed * dt) - 1e-9)))
            inner = lo + (hi - lo) * np.arange(1, n) / n
        else:
            n = max(1, int(math.ceil((t[b] - t[a]) / dt - 1e-9)))
            inner = s_at(t[a] + np.arange(1, n) * dt, s_p, v_p, t)
            inner = inner[(inner > lo + 1e-12) & (inner < hi - 1e-12)]
        pieces += [inner, np.array([hi])]
    s = np.concatenate(pieces)
    return pose_at(knots, path, s), s


def leg_speeds(prof: DriveProfile, legs: FloatArray, vmax: float, turn_speed: float) -> FloatArray:
    """The search's metric speed on each leg: ``vmax`` on a straight, ``turn_speed`` (``r w``)
    in a turn."""
    mid = 0.5 * (legs[1:] + legs[:-1])
    seg = np.clip(np.searchsorted(prof.knots, mid) - 1, 0, len(prof.turning) - 1)
    return np.where(np.asarray(prof.turning)[seg], turn_speed, vmax)


class DriveTiming:
    """A differential drive's profile on its path, some of its legs (the stretches between
    the profile's rests) driven at the search's pace, and the searches among the movers.

    :func:`retime_drive` is :meth:`rounds` with no leg hasty; the partial layer
    (:mod:`gfuzzy.planner.driveblend`) chooses the hasty legs.
    """

    def __init__(self, scene, path, prof, t0, dt, amax, horizon, deadline, hold, backend="compiled"):
        robot = scene.robot
        self.scene, self.path, self.prof = scene, path, prof
        self.t0, self.dt, self.amax, self.horizon, self.deadline, self.hold = t0, dt, amax, horizon, deadline, hold
        #: the searches' implementation (``PlanOptions.backend``)
        self.backend = backend
        #: the movers sampled once for all the searches
        self.fields = ChainFields(scene, t0, dt)
        #: (n + 1,) float: the legs' ends (0, the profile's rests, the length)
        self.legs = np.unique(np.concatenate([[0.0, float(prof.knots[-1])], prof.stops]))
        turn = robot.turn_rate * SPEED_SAFETY * robot.circumradius
        self.speeds = leg_speeds(prof, self.legs, robot.vmax * SPEED_SAFETY, turn)

    def chain(self, hasty, stops):
        """The chain with rests added at ``stops``: (poses, s, rests)."""
        s_p, v_p = _with_stops(self.prof.s, self.prof.v, stops, self.amax)
        rests = np.unique(np.concatenate([self.legs, stops]))
        leg = np.searchsorted(self.legs, 0.5 * (rests[1:] + rests[:-1])) - 1
        poses, s = drive_chain(self.path, self.prof.knots, s_p, v_p, rests, self.dt, np.where(hasty[leg], self.speeds[leg], 0.0))
        return poses, s, rests

    def search(self, poses, s, wait_at, hold=None):
        """The safe-interval search on the chain (``hold`` default the query's)."""
        hold = self.hold if hold is None else hold
        return _search_chain(self.scene, poses, s, self.t0, self.dt, self.horizon, wait_at, self.deadline,
                             hold=hold, group=DRIVE_GROUP, backend=self.backend, fields=self.fields)  # fmt: skip

    def leg_of(self, s, hasty):
        """The leg of each arc length in ``s``."""
        return np.clip(np.searchsorted(self.legs, s, side="right") - 1, 0, len(hasty) - 1)

    def rounds(self, hasty, max_rounds):
        """Waits at rests and anywhere on hasty legs; more rests where a free search waits.

        Returns the last search's result (solved, or why not) and the stops added."""
        stops: list[float] = []
        res = None
        for _ in range(max_rounds):
            poses, s, rests = self.chain(hasty, stops)
            res = self.search(poses, s, np.concatenate([rests[:-1], s[hasty[self.leg_of(s, hasty)]]]))
            if res.status is Status.SOLVED or res.status is Status.TIMEOUT:
                return res, stops
            # where would the robot need to wait? search again allowing waits anywhere
            free = self.search(poses, s, None)
            if free.status is not Status.SOLVED:
                return (free if free.message else res), stops
            leg = self.leg_of(np.asarray(free.waits, dtype=float), hasty)
            new = {w for w, g in zip(free.waits, leg, strict=True) if not hasty[g] and 1e-9 < w < self.legs[-1] - 1e-9}
            merged = sorted(set(stops) | new)
            if merged == stops:
                break
            stops = merged
        return res, stops


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
    backend: str = "compiled",
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
    backend : {"compiled", "reference"}
        The searches' implementation (``PlanOptions.backend``): the same answers.

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
    timing = DriveTiming(scene, path, prof, t0, dt, amax, horizon, deadline, hold, backend)
    res, stops = timing.rounds(np.zeros(len(timing.legs) - 1, dtype=bool), max_rounds)
    if res is not None and res.status is Status.SOLVED:
        return ProfileRetime(Status.SOLVED, res.trajectory, waits=stops, profile_duration=duration)
    message = res.message if res is not None and res.message else "no safe timing found"
    return ProfileRetime(Status.NO_PATH, None, message, profile_duration=duration)
