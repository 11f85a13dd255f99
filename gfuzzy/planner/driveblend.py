"""A differential drive's speed layer where it fits, the search's pace where a mover forces haste.

:func:`gfuzzy.planner.driveretime.retime_drive` drives the whole path under the speed layer
(every straight and every turn in place from rest to rest, within the fuzzy bound, ``amax``
and the turning rate). Among fast movers that can be impossible for any timing: the search
threads a mover's cycle at full speed, and a robot that brakes at every corner misses the
gap (on ``building-floor-unicycle`` no timing of the layered path exists within 175 s).

:func:`retime_blend` then drives some *legs* (the stretches between the profile's rests:
one straight or one turn in place each) at the search's pace instead: at ``vmax`` (a turn at
the turning rate) with no acceleration phase, as the time-space search's answer does. Every
other leg keeps the layer. The legs given haste are chosen greedily: the search on the chain
(waits allowed anywhere) finds the first rest that no timing of the chain up to it reaches;
the latest layered leg before that rest gets haste; repeat. So haste is spent just before
the place a mover blocks, and nowhere the layer fits. Every leg still starts and ends at a
rest and no step crosses a corner, so every row obeys the row rule exactly; ``amax`` is kept
on the layered legs only, and the answer says which legs are hasty (``BlendRetime.hasty``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..fuzzy.driveprofile import DriveProfile, drive_profile
from ..fuzzy.profile import profile_times
from ..poses import pose_at
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..trajectory import Trajectory
from ..typed import FloatArray
from .driveretime import DRIVE_GROUP, _with_stops, _without_null_motions
from .retime import _search_chain, s_at

if TYPE_CHECKING:
    from ..fuzzy.rules import RuleBase

__all__ = ["BlendRetime", "retime_blend", "blend_chain"]


@dataclass(frozen=True)
class BlendRetime:
    """A differential drive's path timed with the speed layer on some legs.

    Attributes
    ----------
    status : Status
    trajectory : Trajectory or None
    message : str
        Why not, when not solved.
    legs : (n + 1,) float
        Metric arc lengths of the legs' ends (0, the profile's rests, the length).
    hasty : (n,) bool
        Which legs are driven at the search's pace (no acceleration bound, no fuzzy bound).
    waits : list of float
        Stops added inside layered legs for the movers (arc lengths).
    profile_duration : float
        The layered profile's duration without the movers, seconds.
    """

    status: Status
    trajectory: Trajectory | None
    message: str = ""
    legs: FloatArray | None = None
    hasty: np.ndarray | None = None
    waits: tuple[float, ...] = ()
    profile_duration: float = math.nan

    @property
    def hasty_length(self) -> float:
        """Metric length of the hasty legs."""
        if self.legs is None or self.hasty is None:
            return 0.0
        return float(np.sum(np.diff(self.legs)[self.hasty]))


def _leg_speeds(prof: DriveProfile, legs: FloatArray, vmax: float, turn_speed: float) -> FloatArray:
    """The search's metric speed on each leg: ``vmax`` on a straight, ``r w`` in a turn."""
    mid = 0.5 * (legs[1:] + legs[:-1])
    seg = np.clip(np.searchsorted(prof.knots, mid) - 1, 0, len(prof.turning) - 1)
    return np.where(np.asarray(prof.turning)[seg], turn_speed, vmax)


def blend_chain(path, knots, s_p, v_p, rests, hasty_of, dt) -> tuple[FloatArray, FloatArray]:
    """The chain of a partly layered profile: points one time step apart, a point at every rest.

    Parameters
    ----------
    path : (n, 3) float
    knots : (n,) float
        Metric arc lengths of the path's poses.
    s_p, v_p : (k,) float
        The layered profile; every rest is one of its samples, with speed 0.
    rests : (r,) float
        Increasing arc lengths where the robot is at rest, 0 and the length included.
    hasty_of : (r - 1,) float
        For each stretch between two rests: its metric speed when it is driven at the
        search's pace (equal steps of at most that speed times ``dt``), or 0 to drive the
        layered profile (its last step stretched to end at the rest).
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
    for a, b, speed in zip(at[:-1], at[1:], hasty_of, strict=True):
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


class _Blend:
    """The chain of one choice of hasty legs and its searches among the movers."""

    def __init__(self, scene, path, prof, legs, speeds, t0, dt, amax, horizon, deadline, hold):
        self.scene, self.path, self.prof, self.legs, self.speeds = scene, path, prof, legs, speeds
        self.t0, self.dt, self.amax, self.horizon, self.deadline, self.hold = t0, dt, amax, horizon, deadline, hold

    def chain(self, hasty, stops):
        s_p, v_p = _with_stops(self.prof.s, self.prof.v, stops, self.amax)
        rests = np.unique(np.concatenate([self.legs, stops]))
        leg = np.searchsorted(self.legs, 0.5 * (rests[1:] + rests[:-1])) - 1
        poses, s = blend_chain(self.path, self.prof.knots, s_p, v_p, rests, np.where(hasty[leg], self.speeds[leg], 0.0), self.dt)
        return poses, s, rests

    def search(self, poses, s, wait_at):
        return _search_chain(self.scene, poses, s, self.t0, self.dt, self.horizon, wait_at, self.deadline,
                             hold=self.hold, group=DRIVE_GROUP)  # fmt: skip

    def hasty_points(self, s, hasty):
        leg = np.clip(np.searchsorted(self.legs, s, side="right") - 1, 0, len(hasty) - 1)
        return s[hasty[leg]]

    def rounds(self, hasty, max_rounds):
        """Waits at rests and anywhere on hasty legs; more rests where a free search waits."""
        stops: list[float] = []
        res = None
        for _ in range(max_rounds):
            poses, s, rests = self.chain(hasty, stops)
            res = self.search(poses, s, np.concatenate([rests[:-1], self.hasty_points(s, hasty)]))
            if res.status is Status.SOLVED or res.status is Status.TIMEOUT:
                return res, stops
            free = self.search(poses, s, None)
            if free.status is not Status.SOLVED:
                return free, stops
            leg = np.clip(np.searchsorted(self.legs, free.waits, side="right") - 1, 0, len(hasty) - 1)
            new = {w for w, g in zip(free.waits, leg, strict=True) if not hasty[g] and 1e-9 < w < self.legs[-1] - 1e-9}
            merged = sorted(set(stops) | new)
            if merged == stops:
                break
            stops = merged
        return res, stops

    def first_blocked(self, hasty) -> int | None:
        """The first leg end no timing of the chain reaches (waits anywhere), or None."""
        poses, s, _ = self.chain(hasty, [])
        ends = np.searchsorted(s, self.legs[1:])
        lo, hi = 0, len(ends) - 1  # find the first j whose prefix up to ends[j] fails
        if self.search(poses, s, None).status is Status.SOLVED:
            return None
        while lo < hi:
            mid = (lo + hi) // 2
            m = int(ends[mid]) + 1
            if self.search(poses[:m], s[:m], None).status is Status.SOLVED:
                lo = mid + 1
            else:
                hi = mid
        return lo


def _prune(blend: _Blend, hasty, res, stops, max_rounds):
    """Give each hasty leg, last first, the layer back where the chain can still be timed."""
    for g in np.flatnonzero(hasty)[::-1]:
        if time.perf_counter() > blend.deadline:
            break
        trial = hasty.copy()
        trial[g] = False
        r, st = blend.rounds(trial, max_rounds)
        if r is not None and r.status is Status.SOLVED:
            hasty, res, stops = trial, r, st
    return res, stops, hasty


def retime_blend(
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
) -> BlendRetime:
    """Time a differential drive's path with the speed layer on as many legs as the movers allow.

    Parameters
    ----------
    scene : Scene
        Its robot a differential drive (``kinematics: unicycle``).
    path : (n, 3) float
        Statically free path of turns in place and straight moves.
    t0, dt : float
    amax : float
        Bound on the metric acceleration on the layered legs.
    horizon : float
        Longest duration considered, seconds.
    rulebase : RuleBase, optional
        The fuzzy rules (default the expert rules).
    deadline : float
        ``time.perf_counter()`` value past which the answer is ``timeout``.
    max_rounds : int
        Searches with waits at the rests, at most, per choice of hasty legs.
    hold : float
        Seconds the goal pose must stay safe after the arrival.

    Returns
    -------
    BlendRetime
        Solved with ``hasty`` all false is the layer on the whole path; not solved when even
        all legs at the search's pace find no timing (the path itself is blocked), or only
        that does (no leg keeps the layer).
    """
    robot = scene.robot
    path = _without_null_motions(np.asarray(path, dtype=float))
    vmax, turn_rate = robot.vmax * SPEED_SAFETY, robot.turn_rate * SPEED_SAFETY
    prof = drive_profile(path, robot.circumradius, vmax, amax, turn_rate, rulebase)
    duration = float(profile_times(prof.s, prof.v)[-1])
    legs = np.unique(np.concatenate([[0.0, float(prof.knots[-1])], prof.stops]))
    speeds = _leg_speeds(prof, legs, vmax, turn_rate * robot.circumradius)
    blend = _Blend(scene, path, prof, legs, speeds, t0, dt, amax, horizon, deadline, hold)
    hasty = np.zeros(len(legs) - 1, dtype=bool)
    message = "no safe timing found"
    while True:
        res, stops = blend.rounds(hasty, max_rounds)
        if res is not None and res.status is Status.SOLVED:
            res, stops, hasty = _prune(blend, hasty, res, stops, max_rounds)
            if hasty.all():
                message = "no leg of the path keeps the layer among the movers, only the search's pace"
                break
            return BlendRetime(Status.SOLVED, res.trajectory, legs=legs, hasty=hasty, waits=tuple(stops),
                               profile_duration=duration)  # fmt: skip
        message = res.message if res is not None and res.message else message
        if hasty.all():
            message = "not even the search's pace on every leg finds a timing of the path among the movers"
            break
        if res is not None and res.status is Status.TIMEOUT or time.perf_counter() > deadline:
            break
        blocked = blend.first_blocked(hasty)
        if blocked is None:  # reachable with waits anywhere: haste where the free search waits
            poses, s, _ = blend.chain(hasty, [])
            waits = np.asarray(blend.search(poses, s, None).waits or [], dtype=float)
            inside = waits[np.min(np.abs(waits[:, None] - legs[None, :]), axis=1) > 1e-9] if waits.size else waits
            leg = np.clip(np.searchsorted(legs, inside, side="right") - 1, 0, len(hasty) - 1)
            candidates = [int(g) for g in np.unique(leg) if not hasty[g]]
            if not candidates:
                break
            hasty = hasty.copy()
            hasty[candidates[0]] = True
            continue
        before = np.flatnonzero(~hasty[: blocked + 1])
        if before.size == 0:
            message = "not even the search's pace reaches a rest of the path among the movers"
            break
        hasty = hasty.copy()
        hasty[before[-1]] = True
    return BlendRetime(Status.NO_PATH, None, message, legs=legs, hasty=hasty, profile_duration=duration)
