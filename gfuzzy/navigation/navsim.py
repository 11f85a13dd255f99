"""Simulated navigation: a scene's movers are the real world, the robot only observes them.

:func:`simulate` runs the loop that ``gfuzzy navigate`` and ``tools/bench_crowd.py`` share
(CONTRACT.md sections 5 and 7): every ``period`` seconds the robot observes the movers
present within ``sense`` metres as discs ``[x, y, vx, vy, radius]`` (a box mover as its
circumscribed disc) through a :class:`gfuzzy.navigation.sensing.Sensor` (true or estimated velocity,
noise, field of view, occlusion), calls
:meth:`Navigator.step`, and follows the returned trajectory until the next call. It stops
at the goal or at ``max_time`` after t0. What it executed is a trajectory that
:func:`gfuzzy.check_trajectory` verifies against the real movers.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from ..collision.geometry import metric_distance, mover_distance
from ..errors import InputError, check_interrupt, check_number
from ..roadmap.roadmap import Roadmap
from ..scene.scene import Scene
from ..settings import MAX_RUN_STEPS
from ..status import Status
from ..timespace.drive import settle_at
from ..trajectory import Trajectory
from ..typed import FloatArray
from .lookout import knowing_view
from .navigator import BUDGET_CLOCKS, Navigator, NavMode, NavOptions
from .navtypes import NavStep
from .sensing import Sensor, SensorOptions
from .socialmetrics import SocialMetrics, social_metrics

__all__ = ["NavResult", "observe", "simulate", "min_separation", "check_run", "MIN_PERIOD"]

log = logging.getLogger(__name__)

#: Forward difference (s) for the movers' velocity: the velocity of the motion to come.
VELOCITY_EPS = 1e-6
#: Shortest period (s) between two replans: a thousand a second, far more than any navigator
#: answers (its time budget is 0.1 s); below it the run's rows would be microseconds apart.
MIN_PERIOD = 1e-3


@dataclass(frozen=True)
class NavResult:
    """What a simulated navigation did.

    Attributes
    ----------
    status : Status
        ``Status.SOLVED`` (the goal was reached) or ``Status.TIMEOUT`` (it was not by max_time).
    trajectory : Trajectory
        The executed motion, from the start at t0.
    replans : int
        Calls to :meth:`Navigator.step`.
    replan_seconds : (replans,) float
        Time of each call on the navigator's budget clock (``NavOptions.budget_clock``:
        wall-clock, or the thread's CPU time).
    modes : dict
        How many calls ended as ``plan``, ``previous``, ``evasive``, ``goal``.
    min_separation : float
        Smallest robot-mover distance over the run (inf without movers).
    social : SocialMetrics
        Discomfort and intrusion counts over the run's periods.
    log : list of dict
        Some replans (every ``log_every``-th): time, pose, predicted discs, planned rows.
    out_of_time : int
        Calls whose search ran out of the navigator's ``time_budget`` before it answered
        (:attr:`NavStep.out_of_time`): most of them means the budget is too small for this
        roadmap and robot, and the robot lived on its fallbacks.
    """

    status: Status
    trajectory: Trajectory
    replans: int
    replan_seconds: FloatArray = field(compare=False)
    modes: dict = field(default_factory=dict)
    min_separation: float = math.inf
    log: list = field(default_factory=list, compare=False)
    social: SocialMetrics = field(default_factory=lambda: SocialMetrics(0, 0, 0))
    out_of_time: int = 0

    @property
    def reached(self) -> bool:
        return self.status == Status.SOLVED

    @property
    def duration(self) -> float:
        return self.trajectory.duration

    def latency(self, q: float) -> float:
        """The ``q`` quantile (0..1) of the replan time, 0 without replans."""
        return float(np.quantile(self.replan_seconds, q)) if len(self.replan_seconds) else 0.0


def observe(scene: Scene, t: float, pose: FloatArray, sense: float = math.inf) -> FloatArray:
    """The movers present at ``t`` within ``sense`` of the robot.

    Returns
    -------
    (k, 5) float
        ``[x, y, vx, vy, radius]``; the velocity is the forward difference over 1 us (the
        motion the mover is about to make); the distance is the robot-disc gap.
    """
    rows = []
    for mv in scene.movers:
        xy, present = mv.state(np.array([t, t + VELOCITY_EPS]))
        if not present[0]:
            continue
        v = (xy[1] - xy[0]) / VELOCITY_EPS if present[1] else np.zeros(2)
        r = mv.extent
        if math.isfinite(sense):
            gap = float(mover_distance(scene.robot, np.asarray(pose, float), "disc", r, (0.0, 0.0), xy[0]))
            if gap > sense:
                continue
        rows.append([xy[0, 0], xy[0, 1], v[0], v[1], r])
    return np.array(rows, dtype=float).reshape(-1, 5)


def simulate(
    scene: Scene,
    roadmap: Roadmap,
    start,
    goal,
    t0: float = 0.0,
    period: float = 0.25,
    sense: float = math.inf,
    max_time: float = 120.0,
    options: NavOptions | None = None,
    log_every: int = 4,
    navigator: Navigator | None = None,
    sensor: SensorOptions | None = None,
) -> NavResult:
    """Drive the robot from ``start`` to ``goal`` among ``scene``'s movers, unknown to it.

    Parameters
    ----------
    scene : Scene
        The world: its movers move as they will, whatever the robot does.
    roadmap : Roadmap
    start, goal : (d,) float
    t0 : float
    period, max_time : float
        Time between two observations and replans (s); the run stops (``timeout``) max_time after
        t0. A run that cannot finish is an InputError (:func:`check_run`).
    sense : float
        Range (m, robot-to-disc gap) within which movers are seen.
    options : NavOptions, optional
    log_every : int
        Keep every this-many-th replan in :attr:`NavResult.log` (0: none).
    navigator : Navigator, optional
        Reuse one (for the same scene, roadmap and goal).
    sensor : SensorOptions, optional
        How the robot observes (velocity estimated or exact, noise, field of view,
        occlusion); its ``sense`` is replaced by ``sense``. Default: the ideal sensor of
        section 5 (true velocities); ``gfuzzy navigate`` estimates them by default.

    Returns
    -------
    NavResult
    """
    check_run(period, max_time)
    robot, cr = scene.robot, scene.robot.circumradius
    goal = np.asarray(goal, dtype=float).reshape(-1)
    pose = np.asarray(start, dtype=float).reshape(-1).copy()
    if navigator is None and sensor is not None:
        options = knowing_view(options or NavOptions(), sensor.fov)
    nav = navigator or Navigator(scene, roadmap, goal, options)
    t = float(t0)
    t_stop = t + max_time
    rows = [np.array([t, *pose])]
    seconds: list = []
    modes: dict = {}
    kept: list = []
    status, out_of_time = Status.TIMEOUT, 0  # out_of_time: calls whose search ran out of the budget
    eyes = _Eyes(scene, sense, sensor, pose, goal)
    clock = BUDGET_CLOCKS[nav.options.budget_clock]  # replan times on the budget's own clock
    while True:
        if float(metric_distance(pose, goal, cr)) <= nav.options.goal_tolerance:
            status = Status.SOLVED
            rows[-1:] = _settle(rows[-1], goal, robot)  # within the tolerance: the goal exactly
            break
        if t >= t_stop - 1e-9:
            break
        obs = eyes(t, pose)
        c0 = clock()
        traj = nav.step(t, pose, obs, eyes.unknown())
        seconds.append(clock() - c0)
        check_interrupt()  # a Ctrl-C native code dropped during the replan stops the run here
        last = nav.last or NavStep(NavMode.PLAN, 0.0)  # (step sets it at every call)
        mode, out_of_time = str(last.mode), out_of_time + last.out_of_time
        modes[mode] = modes.get(mode, 0) + 1
        if log_every and (len(seconds) - 1) % log_every == 0:
            kept.append(_log_entry(t, pose, mode, nav, traj))
        t_next = min(t + period, t_stop)
        w = traj.waypoints
        if abs(w[0, 0] - t) > 1e-9 or float(metric_distance(w[0, 1:], pose, cr)) > 1e-6:
            raise RuntimeError(f"the navigator's trajectory does not start at [t, pose] (t={t})")
        # reaching the goal within the period ends the run there
        at_goal = np.nonzero(metric_distance(w[:, 1:], goal[None], cr) <= nav.options.goal_tolerance)[0]
        end = t_next
        if at_goal.size and w[at_goal[0], 0] <= t_next + 1e-9:
            end = float(w[at_goal[0], 0])
        end = max(end, t + 1e-6)
        piece = _follow(traj, t, end)
        rows.extend(piece[1:])
        eyes.moved(pose, piece[-1, 1:])
        pose = piece[-1, 1:].copy()
        if at_goal.size and abs(end - w[at_goal[0], 0]) <= 1e-9:
            pose = goal.copy()
            if not robot.unicycle:  # (a unicycle's last row is settled at the goal above)
                rows[-1] = np.array([rows[-1][0], *goal])
        t = float(piece[-1, 0])
    wps = _merge_rows(np.array(rows))
    executed = Trajectory(wps, cr)
    sep = min_separation(scene, wps)
    social = social_metrics(wps, cr, scene.movers, period)
    return NavResult(status, executed, len(seconds), np.array(seconds), modes, sep, kept, social, out_of_time)


def check_run(period: float, max_time: float, names: tuple[str, str] = ("period", "max_time")) -> None:
    """Refuse a run that cannot finish (:class:`InputError`, naming ``names``, the options'
    names: ``gfuzzy navigate`` gives its flags): ``period`` and ``max_time`` positive numbers of
    at most ``settings.MAX_MAGNITUDE`` (``check_number``), the period at least
    :data:`MIN_PERIOD`, and at most ``settings.MAX_RUN_STEPS`` replans (``max_time / period``)."""
    for name, value in zip(names, (period, max_time), strict=True):
        check_number(name, value)
    if period < MIN_PERIOD:
        raise InputError(f"{names[0]} must be at least {MIN_PERIOD:g} s (a replan every millisecond), got {period:g}")
    if max_time / period > MAX_RUN_STEPS:
        raise InputError(
            f"{names[1]} {max_time:g} s / {names[0]} {period:g} s is {max_time / period:.3g} replans, more than "
            f"{MAX_RUN_STEPS:,} a run may make: give a larger {names[0]} or a smaller {names[1]}"
        )


def _log_entry(t: float, pose: FloatArray, mode: str, nav: Navigator, traj: Trajectory) -> dict:
    """One replan of :attr:`NavResult.log`."""
    return {
        "t": t,
        "pose": pose.tolist(),
        "mode": mode,
        "predicted": np.round(nav.last.predicted, 4).tolist() if nav.last is not None else [],
        "plan": np.round(_thin(traj.waypoints, 40), 4).tolist(),
    }


class _Eyes:
    """What the robot of :func:`simulate` sees: the movers' true state within ``sense``
    (the ideal sensor of section 5), or what a :class:`Sensor` makes of it."""

    def __init__(self, scene: Scene, sense: float, sensor: SensorOptions | None, pose, goal):
        opts = replace(sensor or SensorOptions(velocity="exact"), sense=sense)
        self.scene, self.sense = scene, sense
        self.sensor = None if opts.ideal else Sensor(scene, opts)
        self.heading = _initial_heading(pose, goal)

    def __call__(self, t: float, pose: FloatArray) -> FloatArray:
        if self.sensor is None:
            return observe(self.scene, t, pose, self.sense)
        return self.sensor.observe(t, pose, self.heading, observe(self.scene, t, pose))

    def unknown(self):
        """Who of the last observation has a velocity not known yet (None: the ideal sensor)."""
        return None if self.sensor is None else self.sensor.unknown

    def moved(self, before: FloatArray, after: FloatArray) -> None:
        self.heading = _heading(before, after, self.heading)


def _initial_heading(pose: FloatArray, goal: FloatArray) -> float:
    """The robot's heading (SE(2)), else the direction to the goal."""
    if len(pose) == 3:
        return float(pose[2])
    d = goal[:2] - pose[:2]
    return float(math.atan2(d[1], d[0])) if np.hypot(*d) > 0 else 0.0


def _heading(before: FloatArray, after: FloatArray, heading: float) -> float:
    """The direction the field of view is centred on after a motion: the robot's heading
    (SE(2)), else its direction of motion (kept while it stands)."""
    if len(after) == 3:
        return float(after[2])
    d = after[:2] - before[:2]
    return float(math.atan2(d[1], d[0])) if np.hypot(*d) > 1e-9 else heading


def _thin(w: FloatArray, n: int) -> FloatArray:
    """At most ``n`` rows of ``w``, evenly picked, the first and last kept (for the log)."""
    if len(w) <= n:
        return w
    return w[np.unique(np.linspace(0, len(w) - 1, n).round().astype(int))]


def _follow(traj: Trajectory, ta: float, tb: float) -> FloatArray:
    """Rows of the motion along ``traj`` from ``ta`` to ``tb`` (standing at its end after it)."""
    w = traj.waypoints
    inner = w[(w[:, 0] > ta + 1e-9) & (w[:, 0] < tb - 1e-9)]
    return np.vstack([np.array([ta, *traj.at(ta)])[None], inner, np.array([tb, *traj.at(tb)])[None]])


def _settle(last: FloatArray, goal: FloatArray, robot) -> list:
    """The rows that replace ``last``, a pose within the goal tolerance, so that the run
    ends exactly at the goal (``gfuzzy check`` compares each coordinate within 1e-6, the
    tolerance the metric's: a unicycle of circumradius 0.3 stopped 2e-6 rad short of the
    goal's heading was refused): for a unicycle, whose rows may not turn while moving,
    :func:`gfuzzy.timespace.drive.settle_at`'s turn in place; otherwise ``last`` and the
    goal after it, reached within the speed bound (written over ``last``, the hair could
    exceed it)."""
    last = np.asarray(last, dtype=float)
    if robot.unicycle:
        return list(settle_at(last[None], goal, robot))
    gap = float(metric_distance(last[1:], goal, robot.circumradius))
    if gap == 0.0:
        return [last]
    return [last, np.array([last[0] + max(gap / robot.vmax, 1e-6), *goal])]


def _merge_rows(w: FloatArray) -> FloatArray:
    """Drop rows closer than 1 ns to the one before (a cut at a waypoint), keeping the last."""
    keep = np.ones(len(w), dtype=bool)
    keep[1:] = np.diff(w[:, 0]) > 1e-9
    out = w[keep]
    out[-1] = w[-1]
    return out


def min_separation(scene: Scene, waypoints: FloatArray, step: float = 0.01) -> float:
    """Smallest distance between the robot along ``waypoints`` and any present mover.

    Exact (closed form per interval of linear relative motion) for a disc robot against
    disc movers given by ``trajectory`` rows; sampled every ``step`` seconds (and at every
    row) otherwise.

    Parameters
    ----------
    scene : Scene
    waypoints : (n, d + 1) float

    Returns
    -------
    float
        inf when no mover is ever present.
    """
    w = np.asarray(waypoints, dtype=float)
    robot = scene.robot
    best = math.inf
    sampled = []
    for mv in scene.movers:
        if robot.shape == "disc" and mv.shape == "disc" and mv.trajectory is not None:
            best = min(best, _disc_track_separation(w, mv.trajectory, robot.radius + mv.radius))
        else:
            sampled.append(mv)
    if sampled and len(w) > 1:
        times = np.unique(np.concatenate([w[:, 0], np.arange(w[0, 0], w[-1, 0], step)]))
        poses = Trajectory(w, robot.circumradius).at(times)
        for mv in sampled:
            xy, present = mv.state(times)
            if present.any():
                d = mover_distance(robot, poses[present], mv.shape, mv.radius, mv.size, xy[present])
                best = min(best, float(d.min()))
    return best


def _disc_track_separation(w: FloatArray, track: FloatArray, radii: float) -> float:
    """Exact smallest gap between a disc moving along rows ``w`` and one along ``track``."""
    lo, hi = max(w[0, 0], track[0, 0]), min(w[-1, 0], track[-1, 0])
    if lo > hi:
        return math.inf
    ts = np.concatenate([w[:, 0], track[:, 0]])
    ts = np.unique(ts[(ts >= lo) & (ts <= hi)])
    ts = np.unique(np.concatenate([[lo, hi], ts]))

    def pos(rows, tt):
        return np.column_stack([np.interp(tt, rows[:, 0], rows[:, 1]), np.interp(tt, rows[:, 0], rows[:, 2])])

    rel = pos(track, ts) - pos(w, ts)
    if len(ts) == 1:
        return float(np.hypot(*rel[0]) - radii)
    a, b = rel[:-1], rel[1:]
    d = b - a
    dd = np.einsum("ij,ij->i", d, d)
    s = np.clip(-np.einsum("ij,ij->i", a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    closest = a + s[:, None] * d
    return float(np.hypot(*closest.T).min() - radii)
