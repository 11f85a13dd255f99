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
the latest layered leg before that rest gets haste; repeat. Then each hasty leg, last first,
gets the layer back where the chain can still be timed. The set is minimal, not the smallest:
no hasty leg can get the layer back alone (:func:`retime_legs` times any set), but another
set of fewer legs may exist. Every leg still starts and ends at a
rest and no step crosses a corner, so every row obeys the row rule exactly; ``amax`` is kept
on the layered legs only, and the answer says which legs are hasty (``BlendRetime.hasty``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..fuzzy.driveprofile import drive_profile
from ..fuzzy.profile import profile_times
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..trajectory import Trajectory
from ..typed import FloatArray
from .driveretime import DriveTiming, _without_null_motions, drive_chain
from .retime import RetimeResult

if TYPE_CHECKING:
    from ..fuzzy.rules import RuleBase

__all__ = ["BlendRetime", "retime_blend", "retime_legs", "blend_chain"]


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
    waits : tuple of float
        Where the answer stops for the movers (arc lengths): the stops added inside layered
        legs and the waits inside hasty legs.
    profile_duration : float
        The blend's duration without the movers: the layered legs at their profile, the
        hasty ones at the search's pace, seconds.
    hasty_spans : tuple of (float, float)
        For each hasty leg, the times the answer leaves its start and reaches its end.
    """

    status: Status
    trajectory: Trajectory | None
    message: str = ""
    legs: FloatArray | None = None
    hasty: np.ndarray | None = None
    waits: tuple[float, ...] = ()
    profile_duration: float = math.nan
    hasty_spans: tuple[tuple[float, float], ...] = ()

    @property
    def hasty_length(self) -> float:
        """Metric length of the hasty legs."""
        if self.legs is None or self.hasty is None:
            return 0.0
        return float(np.sum(np.diff(self.legs)[self.hasty]))


def _hasty_spans(rows: FloatArray, circumradius: float, legs: FloatArray, hasty) -> tuple[tuple[float, float], ...]:
    """(t leaving its start, t reaching its end) of each hasty leg, from the rows' metric arc length."""
    step = np.hypot(*np.diff(rows[:, 1:3], axis=0).T)
    if rows.shape[1] > 3:
        step = step + circumradius * np.abs((np.diff(rows[:, 3]) + math.pi) % (2 * math.pi) - math.pi)
    s = np.concatenate([[0.0], np.cumsum(step)])
    tol = 1e-6 * max(1.0, float(legs[-1]))
    spans = []
    for g in np.flatnonzero(hasty):
        i = max(int(np.searchsorted(s, legs[g] + tol, side="right")) - 1, 0)
        j = min(int(np.searchsorted(s, legs[g + 1] - tol, side="left")), len(s) - 1)
        spans.append((float(rows[i, 0]), float(rows[j, 0])))
    return tuple(spans)


def _solved(blend, res, stops, hasty, duration) -> BlendRetime:
    legs = blend.legs
    inside = [w for w in res.waits if hasty[blend.leg_of(np.array([w]), hasty)[0]] and np.min(np.abs(legs - w)) > 1e-9]
    t = profile_times(blend.prof.s, blend.prof.v)
    layered = np.diff(np.interp(legs, blend.prof.s, t))
    blend_duration = float(np.sum(np.where(hasty, np.diff(legs) / blend.speeds, layered)))
    rows = res.trajectory.waypoints
    return BlendRetime(Status.SOLVED, res.trajectory, legs=legs, hasty=hasty, waits=tuple(sorted(set(stops) | set(inside))),
                       profile_duration=blend_duration if hasty.any() else duration,
                       hasty_spans=_hasty_spans(rows, blend.scene.robot.circumradius, legs, hasty))  # fmt: skip


def blend_chain(path, knots, s_p, v_p, rests, hasty_of, dt) -> tuple[FloatArray, FloatArray]:
    """The chain of a partly layered profile: :func:`gfuzzy.planner.driveretime.drive_chain`
    with ``haste=hasty_of`` (for each stretch between two rests its metric speed at the
    search's pace, or 0 for the layer).

    Returns
    -------
    poses : (m, 3) float
    s : (m,) float
    """
    return drive_chain(path, knots, s_p, v_p, rests, dt, hasty_of)


class _Blend(DriveTiming):
    """The chain of one choice of hasty legs and its searches among the movers."""

    def first_blocked(self, hasty) -> tuple[int | None, RetimeResult]:
        """The first leg end no timing of the chain reaches (waits anywhere), or None, and the
        search of the whole chain with waits anywhere (with the query's ``hold``).

        The prefixes are searched without ``hold``: the robot only passes their ends, and a
        prefix reachable so is reachable at every earlier end too, which the bisection needs.
        """
        poses, s, _ = self.chain(hasty, [])
        whole = self.search(poses, s, None)
        if whole.status is Status.SOLVED or whole.status is Status.TIMEOUT:
            return None, whole
        ends = np.searchsorted(s, self.legs[1:])
        lo, hi = 0, len(ends) - 1  # find the first j whose prefix up to ends[j] fails
        while lo < hi:
            mid = (lo + hi) // 2
            m = int(ends[mid]) + 1
            if self.search(poses[:m], s[:m], None, hold=0.0).status is Status.SOLVED:
                lo = mid + 1
            else:
                hi = mid
        return lo, whole


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


def _blend_of(scene, path, t0, dt, amax, horizon, rulebase, deadline, hold, backend="compiled") -> _Blend:
    robot = scene.robot
    path = _without_null_motions(np.asarray(path, dtype=float))
    prof = drive_profile(path, robot.circumradius, robot.vmax * SPEED_SAFETY, amax,
                         robot.turn_rate * SPEED_SAFETY, rulebase)  # fmt: skip
    return _Blend(scene, path, prof, t0, dt, amax, horizon, deadline, hold, backend)


def retime_legs(
    scene: Scene,
    path: FloatArray,
    hasty,
    t0: float,
    dt: float,
    amax: float,
    horizon: float,
    rulebase: RuleBase | None = None,
    deadline: float = math.inf,
    max_rounds: int = 5,
    hold: float = 0.0,
    backend: str = "compiled",
) -> RetimeResult:
    """Time a differential drive's path with the given legs at the search's pace.

    The timing :func:`retime_blend` tries for each choice of hasty legs (the same chain and
    rounds), for one choice given: to see whether a set of legs is enough.

    Parameters
    ----------
    scene, path, t0, dt, amax, horizon, rulebase, deadline, max_rounds, hold, backend
        As for :func:`retime_blend`.
    hasty : (n,) bool
        For each leg (``BlendRetime.legs``), whether it is driven at the search's pace.

    Returns
    -------
    RetimeResult
        Solved with the trajectory, or why not.
    """
    blend = _blend_of(scene, path, t0, dt, amax, horizon, rulebase, deadline, hold, backend)
    hasty = np.asarray(hasty, dtype=bool)
    if hasty.shape != (len(blend.legs) - 1,):
        raise ValueError(f"hasty has {hasty.size} entries, the path has {len(blend.legs) - 1} legs")
    res, _ = blend.rounds(hasty, max_rounds)
    return res


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
    backend: str = "compiled",
) -> BlendRetime:
    """Time a differential drive's path with the speed layer on the legs the movers leave it.

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
    backend : {"compiled", "reference"}
        The searches' implementation (``PlanOptions.backend``): the same answers.

    Returns
    -------
    BlendRetime
        Solved with ``hasty`` all false is the layer on the whole path; not solved when even
        all legs at the search's pace find no timing (the path itself is blocked), or only
        that does (no leg keeps the layer).
    """
    blend = _blend_of(scene, path, t0, dt, amax, horizon, rulebase, deadline, hold, backend)
    duration = float(profile_times(blend.prof.s, blend.prof.v)[-1])
    legs = blend.legs

    def fail(message, hasty):
        if time.perf_counter() > deadline:
            status, message = Status.TIMEOUT, "the time limit passed"
        else:
            status = Status.NO_PATH
        return BlendRetime(status, None, message, legs=legs, hasty=hasty, profile_duration=duration)

    # the fastest the path goes: every leg at the search's pace, waits anywhere
    fastest = blend.search(*blend.chain(np.ones(len(legs) - 1, dtype=bool), [])[:2], None)
    if fastest.status is not Status.SOLVED:
        why = "not even the search's pace on every leg finds a timing of the path among the movers"
        return fail(why, np.ones(len(legs) - 1, dtype=bool))
    hasty = np.zeros(len(legs) - 1, dtype=bool)
    message = "no safe timing found"
    while True:
        res, stops = blend.rounds(hasty, max_rounds)
        if res is not None and res.status is Status.SOLVED:
            res, stops, hasty = _prune(blend, hasty, res, stops, max_rounds)
            if hasty.all():
                return fail("no leg of the path keeps the layer among the movers, only the search's pace", hasty)
            return _solved(blend, res, stops, hasty, duration)
        message = res.message if res is not None and res.message else message
        if hasty.all() or res is not None and res.status is Status.TIMEOUT or time.perf_counter() > deadline:
            break
        blocked, free = blend.first_blocked(hasty)
        if blocked is None:  # reachable with waits anywhere: haste where the free search waits
            if free.status is not Status.SOLVED:
                break
            waits = np.asarray(free.waits or [], dtype=float)
            inside = waits[np.min(np.abs(waits[:, None] - legs[None, :]), axis=1) > 1e-9] if waits.size else waits
            candidates = [int(g) for g in np.unique(blend.leg_of(inside, hasty)) if not hasty[g]]
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
    return fail(message, hasty)
