"""The OMPL space-time peer: RRTConnect in ``ob.SpaceTimeStateSpace`` on gfuzzy's queries.

A bench-only comparison. The state is (pose, t); a state is valid when the robot at the
pose is free of the static obstacles (FCL, :class:`gfuzzy.geometry.StaticGeometry`) and of
every mover present at t (closed-form distances, :func:`gfuzzy.geometry.mover_distance`).
A Python ``MotionValidator`` accepts a motion only forwards in time, within vmax (the
contract's metric: xy distance + |heading change| x circumradius), and free at samples
every ``resolution`` metres and at most ``dt`` seconds apart. The goal is a
``GoalSampleableRegion``: the goal pose at any reachable time. OMPL 2.0.1 does not bind
STRRT*, so RRTConnect finds *a* trajectory, not the earliest; its answer is then checked
with :func:`gfuzzy.check.check_trajectory`, which tests every instant, not samples.

    from tools.experiments.ompl_peer import PeerOptions, solve_peer
    ans = solve_peer(scene, query, PeerOptions(seed=1, time_limit=5.0))
    ans.status, ans.arrival, ans.seconds, ans.valid
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from gfuzzy.check import check_trajectory
from gfuzzy.geometry import StaticGeometry, metric_distance, mover_distance
from gfuzzy.scene import Query, Scene

__all__ = ["PeerOptions", "PeerAnswer", "solve_peer", "run_peer_job"]


@dataclass(frozen=True)
class PeerOptions:
    """Settings of the peer.

    Attributes
    ----------
    seed : int
        OMPL's seed (process-wide; set before each solve).
    time_limit : float
        Planning budget in seconds (RRTConnect stops at the first solution).
    horizon : float or None
        Latest arrival considered, seconds after t0 (None: 60 + 10 x straight distance / vmax).
    resolution : float
        Spatial step of the motion validator's samples, metres.
    dt : float
        Largest time step between the motion validator's samples.
    range : float
        RRTConnect's range (longest extension) in the space-time metric; 0 = OMPL's default.
    """

    seed: int = 1
    time_limit: float = 5.0
    horizon: float | None = None
    resolution: float = 0.02
    dt: float = 0.07
    range: float = 0.0


@dataclass(frozen=True)
class PeerAnswer:
    """The peer's answer to one query."""

    scene: str
    query: str
    status: str  # solved | timeout | invalid_query
    arrival: float | None  # duration (last t - t0) of the simplified path
    seconds: float  # planning wall time
    valid: bool | None  # the gfuzzy checker's verdict on the answer (None: no answer)
    reason: str = ""
    waypoints: np.ndarray | None = None


def _world(scene: Scene):
    geom = StaticGeometry(scene)
    robot = scene.robot
    movers = scene.movers

    def free(pose: np.ndarray, t: float) -> bool:
        if not geom.is_valid(pose):
            return False
        for mv in movers:
            xy, present = mv.state(np.array([t]))
            if present[0]:
                d = mover_distance(robot, pose, mv.shape, mv.radius, mv.size, xy[0])
                if float(d) <= 0.0:
                    return False
        return True

    return free


def solve_peer(scene: Scene, query: Query, options: PeerOptions | None = None) -> PeerAnswer:
    """Answer one query with RRTConnect in space-time (see the module docstring)."""
    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou

    from gfuzzy.roadmap import _seed_ompl

    opts = options or PeerOptions()
    ou.setLogLevel(ou.LogLevel.LOG_NONE)
    robot = scene.robot
    vmax = robot.vmax
    r = robot.circumradius
    box = robot.dof == 3
    free = _world(scene)
    start = np.asarray(query.start, float)
    goal = np.asarray(query.goal, float)
    t0 = float(query.t0)
    if not free(start, t0) or not StaticGeometry(scene).is_valid(goal):
        return PeerAnswer(scene.name, query.name, "invalid_query", None, 0.0, None, "start or goal not free")
    straight = float(metric_distance(start, goal, r))
    horizon = opts.horizon if opts.horizon is not None else 60.0 + 10.0 * straight / vmax
    xmin, ymin, xmax, ymax = scene.bounds
    if box:
        space = ob.SE2StateSpace()
    else:
        space = ob.RealVectorStateSpace(2)
    bounds = ob.RealVectorBounds(2)
    bounds.setLow(0, xmin)
    bounds.setLow(1, ymin)
    bounds.setHigh(0, xmax)
    bounds.setHigh(1, ymax)
    space.setBounds(bounds)
    # OMPL's own time distance uses vmax on its metric; ours adds r |dheading|: validate below
    st = ob.SpaceTimeStateSpace(space, vmax)
    st.setTimeBounds(t0, t0 + horizon)
    si = ob.SpaceInformation(st)

    def pose_of(s) -> np.ndarray:
        sp = s[0]
        if box:
            return np.array([sp.getX(), sp.getY(), sp.getYaw()])
        return np.array([sp[0], sp[1]])

    def set_pose(s, pose, t):
        sp = s[0]
        if box:
            sp.setXY(float(pose[0]), float(pose[1]))
            sp.setYaw(float(pose[2]))
        else:
            sp[0], sp[1] = float(pose[0]), float(pose[1])
        s[1].position = float(t)

    def valid(s) -> bool:
        return free(pose_of(s), s[1].position)

    si.setStateValidityChecker(valid)

    class Motion(ob.MotionValidator):
        def __init__(self, si_):
            super().__init__(si_)

        def checkMotion(self, s1, s2, *rest):
            ta, tb = s1[1].position, s2[1].position
            if tb <= ta:
                return False
            a, b = pose_of(s1), pose_of(s2)
            d = float(metric_distance(a, b, r))
            if d > vmax * (tb - ta) * (1 - 1e-9):
                return False
            n = max(1, int(math.ceil(max(d / opts.resolution, (tb - ta) / opts.dt))))
            for k in range(1, n + 1):
                f = k / n
                p = a + f * (b - a)
                if box:
                    dh = (b[2] - a[2] + math.pi) % (2 * math.pi) - math.pi
                    p[2] = a[2] + f * dh
                if not free(p, ta + f * (tb - ta)):
                    return False
            return True

    si.setMotionValidator(Motion(si))
    si.setup()

    earliest = t0 + straight / vmax

    class Goal(ob.GoalSampleableRegion):
        def __init__(self, si_):
            super().__init__(si_)
            self.setThreshold(1e-6)
            self.rng = np.random.default_rng(opts.seed)

        def distanceGoal(self, s):
            return float(metric_distance(pose_of(s), goal, r))

        def sampleGoal(self, s):
            set_pose(s, goal, self.rng.uniform(earliest, t0 + horizon))

        def maxSampleCount(self):
            return 1 << 30

    pdef = ob.ProblemDefinition(si)
    s0 = si.allocState()
    set_pose(s0, start, t0)
    pdef.addStartState(s0)
    g = Goal(si)
    pdef.setGoal(g)
    planner = og.RRTConnect(si)
    if opts.range > 0:
        planner.setRange(opts.range)
    planner.setProblemDefinition(pdef)
    planner.setup()
    _seed_ompl(opts.seed)
    tic = time.perf_counter()
    solved = planner.solve(float(opts.time_limit))
    seconds = time.perf_counter() - tic
    exact = bool(solved) and pdef.hasExactSolution()
    if not exact:
        return PeerAnswer(scene.name, query.name, "timeout", None, seconds, None, f"no solution in {opts.time_limit:g} s")
    path = pdef.getSolutionPath()
    rows = []
    for i in range(path.getStateCount()):
        s = path.getState(i)
        rows.append([s[1].position, *pose_of(s)])
    wps = np.array(rows, float)
    wps[-1, 1:] = goal  # the goal region holds the exact pose; keep the query's numbers
    wps[0, 1:] = start
    rep = check_trajectory(scene, wps, query)
    return PeerAnswer(
        scene.name, query.name, "solved", float(wps[-1, 0] - t0), seconds, rep.valid, rep.reason, wps
    )


def run_peer_job(scene: Scene, query_index: int, options: PeerOptions) -> dict:
    """One peer query as a plain dict (a Dask task's result); never raises."""
    q = scene.queries[query_index]
    try:
        ans = solve_peer(scene, q, options)
    except Exception as exc:  # noqa: BLE001 - one query's failure is its row
        return {"scene": scene.name, "query": q.name, "status": "error", "arrival": None,
                "seconds": None, "valid": None, "reason": f"{type(exc).__name__}: {exc}"}  # fmt: skip
    return {"scene": ans.scene, "query": ans.query, "status": ans.status, "arrival": ans.arrival,
            "seconds": ans.seconds, "valid": ans.valid, "reason": ans.reason}  # fmt: skip
