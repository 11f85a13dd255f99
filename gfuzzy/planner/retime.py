"""Path-velocity search: time a fixed geometric path among the movers.

The path is cut into points one time step apart at the allowed speed, and the same
safe-interval search as the roadmap-time search (:func:`gfuzzy.timespace.timespace.sipp`) runs on
that chain, forward only, with waiting where it is allowed. The result keeps every
guarantee of docs/formats.md section 3 for the same reason the roadmap search does.
"""

from __future__ import annotations

import math

import numpy as np

from ..fuzzy.profile import limit_acceleration, profile_times
from ..poses import discretise, metric_distance, pose_at
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..timespace.backends import field_for, search_function
from ..timespace.spacetime import IntervalStore
from ..timespace.timespace import MoverField, SpaceTimeGraph, timed_rows
from ..trajectory import Trajectory
from ..typed import FloatArray

__all__ = ["chain_points", "retime_path", "retime_profile", "RetimeResult", "next_stops", "stopped_profile"]

#: Nodes per group of the chain whose safety is computed together.
GROUP = 16
#: Nodes per group of a chain driven under a speed profile: pairs. The movers' field takes a
#: group's points on one segment as evenly spaced (:meth:`MoverField.unsafe_pairs`), which a
#: chain that accelerates is not: with 16 it missed unsafe (point, step) pairs near rest.
PROFILE_GROUP = 2
#: Stops of the speed-layer timing closer than this (metres of path) are one stop.
STOP_MERGE = 0.3
#: A chain's first search looks this many steps, at least, beyond the chain's own length
#: (:func:`_search_chain`'s rounds) ...
CHAIN_SLACK_STEPS = 48
#: ... or this fraction of its length, whichever is more; the slack doubles while the
#: horizon cuts the search off, up to the caller's horizon.
CHAIN_SLACK = 0.25


class ChainFields:
    """The movers' fields of many chain searches of one stage (one scene, ``t0`` and ``dt``):
    the movers sampled once, over the longest horizon asked, and each search's field a
    prefix of it (:meth:`MoverField.prefix`: the field it would build, to the last bit)."""

    def __init__(self, scene: Scene, t0: float, dt: float):
        self.scene, self.t0, self.dt = scene, t0, dt
        self._field: MoverField | None = None

    def __call__(self, steps: int, most: int) -> MoverField:
        """The field over ``steps`` steps; ``most``: the longest the caller may ask next."""
        if self._field is None or self._field.steps < max(steps, most):
            self._field = MoverField(self.scene, self.t0, self.dt, max(steps, most), self.scene.robot.vmax)
        return self._field.prefix(steps)


def chain_points(path: FloatArray, circumradius: float, step: float) -> tuple[FloatArray, FloatArray]:
    """Cut a path into points at most one step apart: :func:`gfuzzy.poses.discretise`."""
    return discretise(path, circumradius, step)


class RetimeResult:
    """Outcome of :func:`retime_path`: ``status`` and, when solved, the trajectory.

    Attributes
    ----------
    status : Status
        SOLVED, NO_PATH or TIMEOUT.
    trajectory : Trajectory or None
        Only when solved.
    message : str
        Why not, when not solved.
    waits : list of float
        Arc lengths of the points where the answer waits.
    """

    def __init__(self, status, trajectory: Trajectory | None, message: str = "", waits: list | None = None):
        self.status = Status(status)
        self.trajectory = trajectory
        self.message = message
        self.waits = waits or []


def retime_path(
    scene: Scene,
    path: FloatArray,
    t0: float,
    dt: float,
    horizon: float,
    wait_at: FloatArray | None = None,
    deadline: float = math.inf,
    hold: float = 0.0,
    backend: str = "compiled",
) -> RetimeResult:
    """Earliest safe timing of ``path`` departing at ``t0``.

    Parameters
    ----------
    scene : Scene
    path : (n, d) float
        Statically free path (the caller certifies it), start to goal.
    t0, dt : float
    horizon : float
        Longest duration considered, seconds.
    wait_at : (k,) float, optional
        Arc lengths where the robot may stop and wait; None: anywhere. The start is
        always allowed.
    deadline : float
        ``time.perf_counter()`` value past which the answer is ``timeout``.
    hold : float
        Seconds the goal pose must stay safe after the arrival (a query's ``hold``).
    backend : {"compiled", "reference"}
        The search's implementation (``PlanOptions.backend``): the same answers.

    Returns
    -------
    RetimeResult
        ``waits`` lists the arc lengths of the points where the answer waits.
    """
    robot = scene.robot
    step = robot.vmax * SPEED_SAFETY * dt
    # a differential drive turns in place at most at turn_rate: its turns are cut as if the
    # robot's radius were vmax / turn_rate (>= r), so a step turns at most turn_rate dt
    radius = robot.vmax / robot.turn_rate if robot.unicycle else robot.circumradius
    poses, s = chain_points(path, radius, step)
    return _search_chain(scene, poses, s, t0, dt, horizon, wait_at, deadline, hold=hold, backend=backend)


def _metric_profile(path, circumradius, s_xy, v_xy, vmax, amax, ds=0.02):
    """The fuzzy bound (given along the xy arc length) as a profile along the contract
    metric's arc length, scaled so that the configuration speed stays within vmax, and
    made feasible for ``amax`` again."""
    seg_xy = np.hypot(*np.diff(path[:, :2], axis=0).T)
    seg_m = metric_distance(path[:-1], path[1:], circumradius)
    cum_xy = np.concatenate([[0.0], np.cumsum(seg_xy)])
    cum_m = np.concatenate([[0.0], np.cumsum(seg_m)])
    total = cum_m[-1]
    n = max(2, int(math.ceil(total / ds)) + 1)
    s_m = np.unique(np.concatenate([np.linspace(0.0, total, n), cum_m]))
    # metric arc length -> xy arc length (piecewise linear; flat where the robot turns in place)
    i = np.clip(np.searchsorted(cum_m, s_m, side="right") - 1, 0, len(seg_m) - 1)
    f = np.where(seg_m[i] > 0, (s_m - cum_m[i]) / np.where(seg_m[i] > 0, seg_m[i], 1.0), 0.0)
    sx = cum_xy[i] + f * seg_xy[i]
    frac = np.sqrt(np.interp(sx, s_xy, np.asarray(v_xy) ** 2)) / vmax
    inner = (s_m > 0) & (s_m < total)
    frac = np.where(inner, np.maximum(frac, 1e-3), frac)  # the fuzzy bound is > 0 inside
    return s_m, limit_acceleration(s_m, np.minimum(frac, 1.0) * vmax, amax), cum_m


def s_at(grid: FloatArray, s_m: FloatArray, v_m: FloatArray, t: FloatArray) -> FloatArray:
    """Arc lengths at times ``grid`` of driving profile (s_m, v_m) at its limit, ``t`` its
    :func:`profile_times`: constant acceleration within each interval of the profile
    (v^2 linear in s), so the speed changes between steps stay within the acceleration bound.
    """
    i = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 2)
    ds = s_m[i + 1] - s_m[i]
    acc = np.divide(v_m[i + 1] ** 2 - v_m[i] ** 2, 2 * ds, out=np.zeros_like(ds), where=ds > 0)
    tau = grid - t[i]
    return np.minimum(s_m[i] + v_m[i] * tau + 0.5 * acc * tau**2, s_m[i + 1])


def _chain_from_profile(path, cum_m, s_m, v_m, dt):
    """Points of the path at the times t = n dt of driving profile (s_m, v_m) at its limit.

    Returns
    -------
    poses : (m, d) float
    s : (m,) float
        Their arc lengths.
    corners : (c, 2) float
        ``[s, t]`` of each corner of the path strictly inside: where the chain's straight
        steps would cut it, the trajectory gets an extra row at the corner's time.
    times : (m,) float
        Profile times of the chain's points.
    """
    t = profile_times(s_m, v_m)
    n = int(math.ceil(t[-1] / dt - 1e-9))
    grid = np.minimum(np.arange(n + 1) * dt, t[-1])
    s = s_at(grid, s_m, v_m, t)
    s[-1] = s_m[-1]
    keep = np.concatenate([[True], np.diff(s) > 1e-12])
    s, grid = s[keep], grid[keep]
    # the corners' times: invert s(t) on their profile intervals
    cs = cum_m[1:-1]
    j = np.clip(np.searchsorted(s_m, cs, side="right") - 1, 0, len(s_m) - 2)
    dsj = s_m[j + 1] - s_m[j]
    aj = np.divide(v_m[j + 1] ** 2 - v_m[j] ** 2, 2 * dsj, out=np.zeros_like(dsj), where=dsj > 0)
    x = cs - s_m[j]
    root = np.sqrt(np.maximum(v_m[j] ** 2 + 2 * aj * x, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        tc = np.where(np.abs(aj) > 1e-12, (root - v_m[j]) / np.where(aj != 0, aj, 1.0), x / v_m[j])
    tc = t[j] + np.clip(np.nan_to_num(tc), 0.0, t[j + 1] - t[j])
    corners = np.column_stack([cs, tc])
    return pose_at(cum_m, path, s), s, corners, grid


class ProfileRetime(RetimeResult):
    def __init__(self, status, trajectory, message="", waits=None, profile_duration=math.nan):
        super().__init__(status, trajectory, message, waits)
        self.profile_duration = profile_duration


def retime_profile(
    scene: Scene,
    path: FloatArray,
    s_xy: FloatArray,
    v_xy: FloatArray,
    t0: float,
    dt: float,
    amax: float,
    horizon: float,
    deadline: float = math.inf,
    max_rounds: int = 5,
    hold: float = 0.0,
    backend: str = "compiled",
) -> ProfileRetime:
    """Time a path under a speed profile and an acceleration bound, among the movers.

    Round 1 drives the profile with no stop but a wait at the start. If the movers block
    it, a search that may wait anywhere finds where to stop; the profile is computed again
    with the robot at rest at those points (so it brakes and accelerates within ``amax``),
    and the search runs once more, waiting only there (:func:`next_stops`: a wait found near a
    stop moves it). Up to ``max_rounds`` rounds.

    Parameters
    ----------
    path : (n, d) float
        Statically free path.
    s_xy, v_xy : (k,) float
        Speed bound along the xy arc length (from :func:`gfuzzy.fuzzy.fuzzy.speed_limit`).
    hold : float
        Seconds the goal pose must stay safe after the arrival.
    backend : {"compiled", "reference"}
        The search's implementation (``PlanOptions.backend``): the same answers.
    """
    robot = scene.robot
    vmax = robot.vmax * SPEED_SAFETY
    path = np.asarray(path, dtype=float)
    fields = ChainFields(scene, t0, dt)
    s_m, v_m, cum_m = _metric_profile(path, robot.circumradius, s_xy, v_xy, vmax, amax)
    duration = float(profile_times(s_m, v_m)[-1])
    stops: list[float] = []
    message = ""
    for _ in range(max_rounds):
        prof_s, prof_v = stopped_profile(s_m, v_m, stops, amax)
        try:
            poses, s, corners, times = _chain_from_profile(path, cum_m, prof_s, prof_v, dt)
        except ValueError as exc:  # a stretch the profile never crosses
            message = str(exc)
            break
        wait_at = np.array([0.0] + stops)
        # near a stop the robot crawls: waiting at any point within amax dt^2 / 2 of it
        # (where it moves at most amax dt) keeps the speed changes within amax dt
        res = _search_chain(
            scene, poses, s, t0, dt, horizon, wait_at, deadline, (path, cum_m, corners, times), 0.5 * amax * dt**2,
            hold=hold, group=PROFILE_GROUP, backend=backend, fields=fields,
        )
        if res.status is Status.SOLVED:
            return ProfileRetime(Status.SOLVED, res.trajectory, waits=stops, profile_duration=duration)
        message = res.message
        if res.status is Status.TIMEOUT:
            break
        # where would the robot need to stop? search again allowing waits anywhere
        free = _search_chain(
            scene, poses, s, t0, dt, horizon, None, deadline, (path, cum_m, corners, times), hold=hold, group=PROFILE_GROUP,
            backend=backend, fields=fields,
        )
        if free.status is not Status.SOLVED or not free.waits:
            message = free.message or message
            break
        merged = next_stops(stops, free.waits)
        if merged == stops:
            break
        stops = merged
    return ProfileRetime(Status.NO_PATH, None, message or "no safe timing found", profile_duration=duration)


def stopped_profile(s_m: FloatArray, v_m: FloatArray, stops: list, amax: float) -> tuple[FloatArray, FloatArray]:
    """The speed profile (s_m, v_m) brought to rest at each arc length of ``stops``, within
    ``amax``. Two places of rest (the stops, and the profile's own: its ends) with no sample
    between made an interval with zero speed at both ends, which no profile crosses: a sample
    is added midway (only there, so the profiles that had one are as they were)."""
    if not stops:
        return s_m, v_m
    rests = np.unique(np.concatenate([np.asarray(stops, dtype=float), s_m[v_m <= 0.0]]))
    prof_s = np.unique(np.concatenate([s_m, stops]))
    a, b = rests[:-1], rests[1:]
    bare = np.searchsorted(prof_s, b, side="left") - np.searchsorted(prof_s, a, side="right") == 0
    prof_s = np.unique(np.concatenate([prof_s, 0.5 * (a[bare] + b[bare])]))
    cap = np.interp(prof_s, s_m, v_m)
    cap[np.isin(prof_s, stops)] = 0.0
    return prof_s, limit_acceleration(prof_s, cap, amax)


def next_stops(stops: list, waits: list) -> list:
    """The stops of :func:`retime_profile`'s next round: ``stops`` with the waits of a search
    that could wait anywhere. One stop per place: a wait within :data:`STOP_MERGE` of a stop
    moves that stop there. When that gives the same stops again (the search waited short of
    a stop moved past its waits), each place the search waited at becomes a stop of its own,
    rather than giving up on a timing the search showed to exist."""
    merged = list(stops)
    for w in waits:
        if w <= 1e-9:
            continue
        near = [i for i, x in enumerate(merged) if abs(w - x) <= STOP_MERGE]
        if near:
            merged[near[0]] = max(merged[near[0]], w)
        else:
            merged.append(w)
    merged = sorted(merged)
    if merged == sorted(stops):
        merged = sorted(set(stops) | {w for w in waits if w > 1e-9})
    return merged


def _search_chain(
    scene, poses, s, t0, dt, horizon, wait_at, deadline, corners=None, wait_tol=0.0, hold=0.0, group=GROUP,
    backend="compiled", fields=None,
) -> RetimeResult:
    """The safe-interval search on a chain of points one step apart.

    The robot may wait at the point nearest each arc length of ``wait_at`` and at every
    point within ``wait_tol`` of it (None: anywhere).

    ``corners`` = (path, cum_m, [[s, t]...], node times): rows are added at the path's
    corners that a step would otherwise cut (see :func:`_chain_from_profile`).

    ``group``: nodes whose safety is computed together. The movers' field takes a group whose
    points lie on one segment as evenly spaced along it (:meth:`MoverField.unsafe_pairs`);
    a chain driven under a speed profile is not, least of all a differential drive's (it
    brakes to rest at every corner and turns in place, many nodes at one point): its groups
    are pairs, which always are.

    Rounds: the search runs first with a horizon of the chain's length plus a slack
    (:data:`CHAIN_SLACK`), the slack doubled while the horizon cut it off, up to ``horizon``;
    the safety computed stays in one store. The same answer as one search with the whole
    horizon: the search expands states in order of arrival plus the steps left, never more
    than the arrival it returns, and every such state, its safe interval's index and its
    successors within that bound are the same under any longer horizon (a state's window
    ends at the horizon minus the steps left); a search that ran empty without touching its
    horizon runs empty under any longer one. A chain's safety is computed over each point's
    whole window at once, so a horizon of three times the path's duration cost about ten
    times the safety the answer needs.

    ``backend``: the search of ``PlanOptions.backend`` (:func:`gfuzzy.timespace.backends.search_function`)
    with the safety kernels of the same backend; both judge every group by the same rule
    (a group not evenly spaced on its segment has every point examined), so both give the
    same answer. ``fields``: a :class:`ChainFields` the caller's searches share (default: the
    movers sampled for this search alone).
    """
    robot = scene.robot
    m = len(poses)
    hold_steps = int(math.ceil(hold / dt - 1e-9)) if hold > 0 else 0
    if m == 1 and hold_steps == 0:
        return RetimeResult(Status.SOLVED, Trajectory(np.array([[t0, *poses[0]]]), robot.circumradius))
    indptr = np.arange(m + 1, dtype=np.int64)
    indptr[-1] = m - 1
    nbrs = np.arange(1, m, dtype=np.int64)
    heur = (m - 1 - np.arange(m)).astype(float)
    can_wait = None
    if wait_at is not None:
        can_wait = np.zeros(m, dtype=bool)
        can_wait[0] = True
        for w in np.atleast_1d(wait_at):
            can_wait[int(np.argmin(np.abs(s - w)))] = True
            can_wait |= np.abs(s - w) <= wait_tol
    groups = np.unique(np.append(np.arange(0, m, group), m))
    graph = SpaceTimeGraph(
        poses, indptr, nbrs, heur, can_wait=can_wait, groups=groups, from_start=np.arange(m, dtype=float)
    )
    res = _rounds(scene, graph, t0, dt, int(math.ceil(horizon / dt)), hold_steps, deadline, backend, fields)
    if res.status != Status.SOLVED:
        return RetimeResult(res.status, None, res.message)
    between = None
    if corners is not None:
        path, cum_m, cs, times = corners

        def between(a: int, b: int):
            """Rows at the corners a step from a to b would cut: (fraction of the step, pose)."""
            inside = (cs[:, 0] > s[a] + 1e-12) & (cs[:, 0] < s[b] - 1e-12)
            for sc, tc in cs[inside]:
                frac = (tc - times[a]) / (times[b] - times[a])
                if 0.0 < frac < 1.0:
                    yield frac, pose_at(cum_m, path, np.array([sc]))[0]

    wps, wait_nodes = timed_rows(res.nodes, res.steps, poses, t0, dt, between)
    waits = [float(s[a]) for a in wait_nodes]
    return RetimeResult(Status.SOLVED, Trajectory(wps, robot.circumradius), waits=waits)


def _rounds(scene, graph, t0, dt, horizon_steps, hold_steps, deadline, backend, fields=None):
    """The chain's search with a horizon that doubles its slack while it cut the search off
    (:func:`_search_chain`), at most ``horizon_steps``; the safety kept in one store."""
    h0 = float(graph.heuristic[0])
    most = horizon_steps + hold_steps
    slack = max(float(CHAIN_SLACK_STEPS), CHAIN_SLACK * h0)
    store = IntervalStore(graph)
    search = search_function(backend)
    while True:
        steps = min(most, int(math.ceil(h0 + slack)) + hold_steps)
        if fields is None:
            field_ = MoverField(scene, t0, dt, steps, scene.robot.vmax)
        else:
            field_ = fields(steps, most)
        field_ = field_for(field_, backend)
        res = search(graph, field_, 0, len(graph.poses) - 1, deadline=deadline, store=store, goal_hold=hold_steps)
        if res.status != Status.NO_PATH or not res.horizon_hit or steps >= most:
            return res
        slack *= 2.0
