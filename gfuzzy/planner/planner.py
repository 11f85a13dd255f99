"""The query API: scene + roadmap + (start, goal, t0) -> a timed trajectory.

The pipeline runs one way: time-space search on the roadmap
(:mod:`gfuzzy.timespace.timespace`), then optionally GA refinement of the corridor
(:mod:`gfuzzy.ga`) and the fuzzy speed layer (:mod:`gfuzzy.fuzzy.fuzzy`), each re-timed among
the movers by a path-velocity search (:mod:`gfuzzy.planner.retime`). A later stage that cannot
produce a safe answer leaves the earlier answer in place.
"""

from __future__ import annotations

import copy
import logging
import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..collision.geometry import StaticGeometry
from ..errors import InputError, LimitError
from ..poses import as_number, wrap_angle
from ..roadmap.roadmap import Roadmap
from ..scene.scene import Query, Scene
from ..settings import MAX_MAGNITUDE, MAX_MOVER_SAMPLES, SPEED_SAFETY
from ..status import Status
from ..timespace.backends import BACKENDS, compile_if_cold, search_function
from ..timespace.movers import MoverField
from ..timespace.roadgraph import connect
from ..timespace.spacetime import IntervalStore, SearchResult
from ..timespace.timespace import timed_rows
from ..timespace.unilanes import OutOfTime
from ..trajectory import Trajectory
from ..typed import FloatArray
from .plantypes import PlanOptions, PlanResult, PlanStats, _amax_stats
from .queries import check_pose, first_motion_hint, goal_taken, query_problem

__all__ = [
    "Status",
    "PlanOptions",
    "PlanResult",
    "PlanStats",
    "Planner",
    "plan",
    "query_problem",
    "check_pose",
    "settle_time",
    "search_function",
    "BACKENDS",
]

log = logging.getLogger(__name__)


class Planner:
    """Answers queries on one scene and roadmap, sharing the collision model.

    Parameters
    ----------
    scene : Scene
    roadmap : Roadmap
        Built for ``scene`` (see :meth:`Roadmap.check_scene`).
    """

    def __init__(self, scene: Scene, roadmap: Roadmap):
        roadmap.check_scene(scene)
        self.scene = scene
        self.roadmap = roadmap
        self.geometry = StaticGeometry(scene)
        self.robot = scene.robot
        self._fs: list = []  # the disc robot's free space, computed on the first no_path

    # ---------------------------------------------------------------- free space
    def _free_space(self):
        """The disc robot's free space (:mod:`gfuzzy.roadmap.freespace`), computed once; None for
        other robots."""
        if not self._fs:
            from ..roadmap.freespace import free_space

            self._fs.append(free_space(self.scene))
        return self._fs[0]

    def _not_joined(self, start, goal, prepared: bool, linked: bool, opts: PlanOptions, deadline: float) -> tuple[Planner | None, str]:
        """The query's graph does not join start and goal: a planner to try again (see
        :meth:`through_free_space`), or None and the ``no_path`` message (a box or footprint
        drive's says when the roadmap joins them and only the drive's graph does not,
        :func:`gfuzzy.planner.hemmed.drive_split_note`)."""
        from .hemmed import drive_split_note

        if linked:
            return None, (
                "start and goal share a region of the free space, but no certified path through "
                "it joins them on the roadmap" if self._fs[0] is not None else
                "start and goal were bridged to the roadmap, but no certified path joins them on it"
            )  # fmt: skip
        if prepared:  # a kept goal graph (replanning) is not extended
            return None, drive_split_note(self.geometry, self.roadmap, start, goal, opts.drive_repair) or (
                "start and goal are not connected on the roadmap (sealed off, or the roadmap is too sparse)")
        return self.through_free_space(start, goal, opts.connect_k, deadline, opts.drive_repair)

    def through_free_space(self, start, goal, k: int, deadline: float = math.inf, repair: bool = True) -> tuple[Planner | None, str]:
        """When the roadmap does not join ``start`` and ``goal``: a planner on the roadmap
        extended through the free space, or None and the reason no way exists.

        Other holonomic robots (no free space computed) bridge the end the roadmap does not
        reach to it (:mod:`gfuzzy.planner.bridge`; ``k``: the query's ``connect_k``). A box or
        footprint drive's message names an end that is hemmed in, else says whether the
        roadmap joins the ends (its graph did not: ``repair``, whether the drive repair ran).

        A disc robot's start and goal are linked through the free space (:meth:`_linked`).
        """
        from ..roadmap.narrowest import not_joined, separation
        from .bridge import bridged_planner
        from .hemmed import drive_split_note, hemmed_note

        fs = self._free_space()
        bridged = bridged_planner(self, [start, goal], k, deadline) if fs is None and not self.robot.unicycle else None
        if bridged is not None:
            return bridged, ""
        if fs is None:
            hemmed = [n for n in (hemmed_note(self.geometry, start, "start"), hemmed_note(self.geometry, goal, "goal")) if n]
            if hemmed:  # more vertices cannot help: say what holds the end
                return None, f"start and goal are not connected on the roadmap: {'; '.join(hemmed)}"
            split = drive_split_note(self.geometry, self.roadmap, start, goal, repair)
            if split:
                return None, split
            return None, not_joined(self.scene, start, goal)
        sep = separation(self.scene, fs, start, goal)
        if sep is not None:
            return None, sep.message()
        return self._linked([start, goal], k), ""

    def _linked(self, poses: list, k: int, join: bool = True) -> Planner | None:
        """A disc robot's planner on the roadmap with ``poses`` linked to the nearest vertex of
        their free-space region by certified paths (:func:`gfuzzy.roadmap.freespace.link_pose`),
        each pose of a link joined to its ``k`` nearest vertices too (the region's nearest
        vertex in the plane may lie behind a wall: round it), and the components sharing a
        region joined (:func:`gfuzzy.roadmap.freespace.repair`: an old roadmap built without
        it is repaired here; not with ``join`` False) and the spanners keeping every added
        edge (:func:`gfuzzy.planner.bridge.extended`); None for other robots."""
        from ..roadmap.freespace import link_pose, repair
        from .bridge import extended

        fs = self._free_space()
        if fs is None:
            return None
        rm = self.roadmap
        verts = [np.asarray(rm.vertices, dtype=float)]
        edges = [np.asarray(rm.edges, dtype=np.int64).reshape(-1, 2)]
        n = len(rm.vertices)
        for pose in poses:
            chain = link_pose(self.geometry, fs, pose, rm.vertices)
            if chain is None:
                continue
            inner = [np.asarray(p, dtype=float) for p in chain[1:-1]]
            if not inner:  # keep the pose itself out of the roadmap: a point on the way
                inner = [0.5 * (np.asarray(chain[0], dtype=float) + np.asarray(chain[-1], dtype=float))]
            ids = list(range(n, n + len(inner)))
            verts.append(np.asarray(inner).reshape(-1, 2))
            n += len(inner)
            target = int(np.nonzero(np.all(rm.vertices == np.asarray(chain[-1]), axis=1))[0][0])
            ids.append(target)
            pairs = {(min(a, b), max(a, b)) for a, b in zip(ids[:-1], ids[1:], strict=True)}
            # each pose of the link joins its nearest vertices too: the link ends at the region's
            # nearest vertex in the plane, which may lie behind a wall, round it
            pairs |= {(v, i) for i, p in zip(ids[:-1], inner, strict=True) for v, _ in self._connect(p, k)}
            edges.append(np.asarray(sorted(pairs), dtype=np.int64))
        verts, edges = np.vstack(verts), np.vstack(edges)
        if join:
            joined = repair(self.geometry, fs, verts, edges)
            verts, edges = joined.vertices, joined.edges
        planner = copy.copy(self)
        planner.roadmap = extended(rm, verts, edges)
        log.info("query linked through the free space: %d vertices added", len(verts) - len(rm.vertices))
        return planner

    # ---------------------------------------------------------------- graph
    def _connect(self, pose: FloatArray, k: int, clearance: float | None = None) -> list[tuple[int, float]]:
        """Certified straight connections from ``pose`` to its nearest roadmap vertices
        (:func:`gfuzzy.timespace.roadgraph.connect`; ``clearance``: the pose's, when known)."""
        return connect(self.geometry, self.roadmap, pose, k, clearance)

    def _query_graph(self, start, prepared) -> tuple:
        """(graph, start id, goal id, roadmap distance) of a query: ``prepared`` (the goal's
        kept graph, :meth:`prepare`) with ``start`` (heading wrapped) spliced in. Every query
        graph is built so: a fresh plan prepares its goal first; ``plan_from`` and the
        navigator keep it (:mod:`gfuzzy.planner.prepared`; for a differential drive the graph
        of heading copies, :mod:`gfuzzy.timespace.unicycle`)."""
        qg = prepared.splice(self, start)
        return qg.graph, qg.s_id, qg.g_id, qg.roadmap_distance

    # ---------------------------------------------------------------- query
    def prepare(self, goal, options: PlanOptions | None = None, _tilts: bool = False, _deadline: float = math.inf,
                _base=None):  # fmt: skip
        """Keep what replanning to ``goal`` reuses: the goal's connections and the static
        distances to the goal (:mod:`gfuzzy.planner.prepared`; the spanner's cut is kept on
        the roadmap). A fresh :meth:`plan` prepares its goal so too, then splices its start in.

        Parameters
        ----------
        goal : (d,) float
        options : PlanOptions, optional
            Fixed for every :meth:`plan_from` on the result (dt, stretch, connect_k, backend...).

        Returns
        -------
        gfuzzy.planner.prepared.PreparedGoal or gfuzzy.timespace.unicycle.UnicyclePrepared
            Its ``splice(planner, start)`` is a query's graph.

        Raises
        ------
        InputError
            A malformed goal (as :meth:`plan`).
        LimitError
            When the spanner's and the goal's points would exceed ``settings.MAX_POINTS``.
        """
        from .prepared import prepare_goal

        opts = options or PlanOptions()
        goal = check_pose(goal, self.robot.dof, "goal", self.robot)
        if self.robot.unicycle:  # the copies' graph is kept on the roadmap; the rest is per query
            from ..timespace.unicycle import UnicyclePrepared
            from ..timespace.unicycle import prepare_goal as prepare_unicycle

            wrapped = goal.copy()
            wrapped[2] = wrap_angle(wrapped[2])
            kept = prepare_unicycle(self, wrapped, opts.dt, self.robot.vmax * SPEED_SAFETY, opts.connect_k, opts.stretch,
                                    _tilts, _deadline, _base)  # fmt: skip
            return UnicyclePrepared(goal, opts, kept)
        return prepare_goal(self, goal, opts, deadline=_deadline)

    def plan_from(self, prepared, start, t0: float = 0.0, movers=None, hold: float = 0.0) -> PlanResult:
        """Answer a query to a prepared goal from ``start`` at ``t0``: :meth:`plan` without
        preparing the goal again (only the start is spliced in; one Dijkstra on the vertices):
        the graph, and so the answer, of a fresh plan from ``start``.

        Parameters
        ----------
        prepared : gfuzzy.planner.prepared.PreparedGoal
            From :meth:`prepare` on this planner.
        start : (d,) float
            Any free pose (mid-edge poses connect to their nearest vertices).
        t0 : float
        movers : sequence of gfuzzy.scene.scene.Mover, optional
            The movers to avoid this time (e.g. predicted from observations); None: the
            scene's own.
        hold : float

        Returns
        -------
        PlanResult
            As :meth:`plan`: a fresh ``plan(start, goal, t0)``'s answer, except that a
            start and goal the roadmap does not join are ``no_path`` (a fresh plan may
            join them through the free space).
        """
        planner = self
        if movers is not None:
            planner = copy.copy(self)
            planner.scene = replace(self.scene, movers=tuple(movers))
        return planner.plan(start, prepared.goal_raw, t0, prepared.options, hold=hold, _prepared=prepared)

    def plan(
        self, start, goal, t0: float = 0.0, options: PlanOptions | None = None, hold: float = 0.0,
        _prepared=None,
        _linked: bool = False,
    ) -> PlanResult:
        """Answer one query.

        Parameters
        ----------
        start, goal : (d,) float
            Poses ``[x, y]`` (disc robot) or ``[x, y, heading]`` (box robot, or any
            unicycle: its answers are waits, turns in place and straight moves along the
            heading, :mod:`gfuzzy.timespace.unicycle`).
        t0 : float
            Departure time.
        options : PlanOptions, optional
        hold : float
            Seconds the robot then parks at the goal (a query's ``hold``): the goal pose
            keeps the guarantees from the arrival until ``hold`` after it; the answer
            arrives later if it must.

        Returns
        -------
        PlanResult
            ``invalid_query`` when a well-formed start or goal collide with a static obstacle (or lie
            closer than ``robot.clearance`` to one), lie out of bounds, or the start is
            closer than ``robot.mover_clearance`` to a mover at t0 (overlaps it, when 0);
            ``no_path`` when no safe trajectory exists on the roadmap within the horizon
            (the message says when the horizon cut the search); ``timeout`` when the
            planning budget ran out.

        Raises
        ------
        InputError
            A malformed request (bad input, as the command line's exit status 2): a start
            or goal that is not ``dof`` finite numbers, or a non-finite ``t0`` or ``hold``.
        """
        opts = options or PlanOptions()
        hold = _check_hold(hold)
        hold_steps = int(math.ceil(hold / opts.dt - 1e-9)) if hold > 0 else 0
        t_begin = _clock_start(opts)  # after a fresh installation's compile (the kernels' load counts)
        deadline = t_begin + opts.time_limit
        robot = self.robot
        vmax = robot.vmax
        start = check_pose(start, robot.dof, "start", robot)
        goal = check_pose(goal, robot.dof, "goal", robot)
        t0 = _check_t0(t0)

        def answer(status, message="", traj=None, rd=math.inf, stats=None):
            status, message = _in_time(Status(status), message, opts.time_limit, deadline)
            return PlanResult(status, traj, message, rd, time.perf_counter() - t_begin, vmax, stats or PlanStats())

        problem = query_problem(self.geometry, start, goal)
        if problem:
            return answer(Status.INVALID_QUERY, problem)
        ends = start.copy(), goal.copy()  # the rows at the ends repeat them exactly
        if robot.dof == 3:
            start[2], goal[2] = wrap_angle(start[2]), wrap_angle(goal[2])
        try:
            graph, s_id, g_id, rd = self._graph(start, ends[1], opts, _prepared, deadline)
        except OutOfTime:
            return answer(Status.TIMEOUT, _late(opts.time_limit, "building the search graph"))
        if not math.isfinite(rd):
            linked, message = self._not_joined(start, goal, _prepared is not None, _linked, opts, deadline)
            if linked is not None:  # in the budget left
                left = replace(opts, time_limit=max(deadline - time.perf_counter(), 1e-9))
                return linked.plan(ends[0], ends[1], t0, left, hold=hold, _linked=True)
            return answer(Status.NO_PATH, message, stats=PlanStats(nodes=0 if graph is None else len(graph.poses)))
        max_steps = self._max_steps(opts, rd, t0, hold_steps)
        run = self._search_rounds(graph, s_id, g_id, start, t0, opts, hold_steps, max_steps, deadline)
        if run.problem:
            return answer(Status.INVALID_QUERY, run.problem, rd=rd)
        res, horizon = run.result, run.horizon
        res.message += first_motion_hint(robot, opts.dt, res.message)
        stats = PlanStats(
            expansions=run.expansions,
            states=res.states,
            graph_nodes=len(graph.poses),
            roadmap_vertices=len(self.roadmap.vertices),
            mover_evaluations=run.evaluations,
            horizon=horizon,
            hold=hold if hold_steps else None,
        )
        if res.status == Status.NO_PATH and res.horizon_hit:
            res.message = goal_taken(self.scene, goal, t0 + horizon) or (
                f"no safe trajectory within the planning horizon of {horizon:g} s"
                + (f" (+ the hold of {hold:g} s)" if hold_steps else "")
                + "; the horizon cut the search: a longer one (--horizon, PlanOptions.horizon) may find one"
            )
        if res.status != Status.SOLVED:
            return answer(res.status, res.message, rd=rd, stats=stats)
        traj = Trajectory(timed_rows(res.nodes, res.steps, graph.poses, t0, opts.dt)[0], robot.circumradius)
        stats = replace(stats, search_seconds=time.perf_counter() - t_begin)
        result = answer(Status.SOLVED, "", traj, rd, stats=stats)
        if opts.refine or opts.speed_layer:
            result = self._staged(result, Query("stage", tuple(start), tuple(goal), t0, hold=hold), opts, t_begin)
        # headings are wrapped inside; the first and last rows give the query's own numbers
        wps = result.trajectory.waypoints.copy()
        wps[0, 1:], wps[-1, 1:] = ends
        return replace(result, trajectory=Trajectory(wps, robot.circumradius), stats=_amax_stats(robot, result.stats, result.speed_report))

    def _graph(self, start, goal, opts: PlanOptions, prepared, deadline: float) -> tuple:
        """(graph, start id, goal id, roadmap distance) of a query (:meth:`_query_graph`) from
        ``prepared`` or a goal prepared now; a fresh box or footprint drive's by
        :func:`gfuzzy.timespace.unirepair.drive_graph` (its lanes' proof that the ends are
        apart, its ends' tilts, the repair of its pieces). OutOfTime past ``deadline``."""
        if prepared is None and self.robot.unicycle and self.robot.shape != "disc":
            from ..timespace.unirepair import drive_graph

            return drive_graph(self, start, goal, opts, deadline)
        return self._query_graph(start, prepared if prepared is not None else self.prepare(goal, opts, _deadline=deadline))

    def _staged(self, result: PlanResult, query: Query, opts: PlanOptions, t_begin: float) -> PlanResult:
        """``result`` after the GA refinement and/or the speed layer (:mod:`gfuzzy.planner.stages`)."""
        from .stages import StageContext, apply_stages

        ctx = StageContext(self.scene, self.geometry)
        staged = apply_stages(ctx, result.trajectory, query, opts, t_begin + opts.time_limit)
        return replace(
            result,
            trajectory=staged.trajectory,
            planning_seconds=time.perf_counter() - t_begin,
            refine_report=staged.refine_report,
            speed_report=staged.speed_report,
        )

    def _max_steps(self, opts: PlanOptions, rd: float, t0: float, hold_steps: int) -> int:
        """The longest horizon searched, in steps (the parking's steps come on top)."""
        if opts.horizon is None:
            max_horizon = 60.0 + 10.0 * rd / self.robot.vmax + settle_time(self.scene, t0)
            # never more than the movers can be sampled over (a default must not fail)
            if self.scene.movers:
                cap = (MAX_MOVER_SAMPLES // len(self.scene.movers) - 1 - hold_steps) * opts.dt
                max_horizon = max(min(max_horizon, cap), opts.dt)
        else:
            max_horizon = opts.horizon
        # an infinite horizon: the rounds grow until the search is not cut (or the movers'
        # samples run out, a LimitError that says so)
        return int(math.ceil(min(max_horizon / opts.dt, 2.0**62))) + hold_steps

    def _start_problem(self, field_: MoverField, start: FloatArray, t0: float) -> str:
        """Why the start cannot be searched from (on a mover, or within mover_clearance), or ""."""
        hit = field_.collides_at(start, 0)
        if hit is not None:
            return f"start collides with mover {hit!r} at t0={t0:g}"
        keep = self.robot.mover_clearance
        hit = field_.collides_at(start, 0, keep) if keep > 0 else None
        if hit is not None:
            return f"start is closer than robot.mover_clearance={keep:g} to mover {hit!r} at t0={t0:g}"
        return ""

    def _search_rounds(self, graph, s_id, g_id, start, t0, opts, hold_steps, max_steps, deadline) -> _Rounds:
        """The search, rerun with a doubled slack while the horizon cut it off."""
        # Grow the horizon by doubling the slack above the static lower bound: safety is
        # only computed for times a node can still matter at (from_start .. horizon - h),
        # so a horizon close to the answer keeps that window, and the work, small.
        h0 = float(graph.heuristic[s_id])
        # First slack: with few movers the search dominates the cost and a second run
        # would double it, so start generously; with many, the movers' safety dominates,
        # it grows with the slack, and a rerun reuses it (IntervalStore): start tight.
        slack = max(48.0, (0.35 if len(self.scene.movers) <= 10 else 0.15) * h0)
        store = IntervalStore(graph)  # safety computed once, kept as the horizon grows
        search = search_function(opts.backend)
        expansions = evaluations = 0
        while True:
            steps = min(max_steps, int(math.ceil(h0 + slack)) + hold_steps)
            horizon = (steps - hold_steps) * opts.dt
            if len(self.scene.movers) * (steps + 1) > MAX_MOVER_SAMPLES:
                raise LimitError(
                    f"{len(self.scene.movers)} movers over {steps:,} time steps"
                    + (f" (the hold's {hold_steps:,} included)" if hold_steps else "")
                    + f" are too many to sample ({len(self.scene.movers) * (steps + 1):,} samples, at most "
                    f"{MAX_MOVER_SAMPLES:,}); use a larger dt, a shorter horizon or hold"
                )
            field_ = MoverField(self.scene, t0, opts.dt, steps, self.robot.vmax)
            field_.compiled = opts.backend == "compiled"
            if store.H < 0:  # first round: a start on a mover is not a query to search
                problem = self._start_problem(field_, start, t0)
                if problem:
                    return _Rounds(None, horizon, 0, 0, problem)
            res = search(
                graph, field_, s_id, g_id, deadline=deadline, weight=opts.weight, store=store, goal_hold=hold_steps
            )
            expansions += res.expansions
            evaluations += field_.evaluations
            if res.status != Status.NO_PATH or not res.horizon_hit or steps >= max_steps:
                return _Rounds(res, horizon, expansions, evaluations)
            slack *= 2.0


@dataclass
class _Rounds:
    """What :meth:`Planner._search_rounds` found: the last search, or why none ran."""

    result: SearchResult | None
    horizon: float
    expansions: int
    evaluations: int
    problem: str = ""


def _compile_cold(opts: PlanOptions) -> bool:
    """A fresh installation's one compile of the kernels a query will run (the search's,
    the GA's with ``refine``: numba's whatever the backend), outside the planning budget.
    Whether it compiled (loading the kernels, when nothing is compiled, is the query's time)."""
    compiled = opts.backend == "compiled" and compile_if_cold()
    if opts.refine:
        from ..ga.refine import warm_if_cold

        compiled = warm_if_cold() or compiled
    return compiled


def _clock_start(opts: PlanOptions) -> float:
    """When a query's planning clock starts: before it looks at its kernels, so their load
    (the precompiled extension, its source hashed: 8-16 ms) is the query's time, or after a
    fresh installation's compile of them (:func:`_compile_cold`) when one ran."""
    t_begin = time.perf_counter()
    return time.perf_counter() if _compile_cold(opts) else t_begin


def _late(limit: float, doing: str) -> str:
    return f"the planning budget of {limit:g} s (PlanOptions.time_limit, --time-limit) ran out {doing}"


def _in_time(status: Status, message: str, limit: float, deadline: float) -> tuple[Status, str]:
    """An answer found past ``deadline`` is not given: ``timeout`` instead of a late
    ``solved`` or ``no_path`` (the search, the stages and the differential drive's lanes
    stop at the deadline; this catches what runs on past it)."""
    if status in (Status.SOLVED, Status.NO_PATH) and time.perf_counter() > deadline:
        return Status.TIMEOUT, _late(limit, "before the answer was complete")
    return status, message


def _check_hold(hold) -> float:
    """A query's ``hold`` as a float (InputError when negative or not finite)."""
    if isinstance(hold, bool) or not isinstance(hold, (int, float, np.number)) or not (
        math.isfinite(hold) and 0 <= hold <= MAX_MAGNITUDE
    ):
        raise InputError(f"hold must be a non-negative number of at most {MAX_MAGNITUDE:g}, got {hold!r}")
    return float(hold)


def _check_t0(t0) -> float:
    """A departure time as a float (InputError when not a finite number: :func:`gfuzzy.poses.as_number`)."""
    number = as_number(t0)
    if number is None or not math.isfinite(number):
        raise InputError(f"t0: expected a finite number, got {t0!r}")
    if abs(number) > MAX_MAGNITUDE:  # as in a scene file: beyond, t0 + dt == t0 and times stop increasing
        raise InputError(f"t0: {number:g} is too large (at most {MAX_MAGNITUDE:g} in magnitude)")
    return number


def settle_time(scene: Scene, t0: float = 0.0) -> float:
    """Seconds after ``t0`` until the movers' behaviour stops changing, plus one period.

    After every ``once`` mover has stopped and every ``trajectory`` mover has left, the
    world only repeats: loop and bounce movers are periodic. A query whose answer must
    wait for a door to clear needs a horizon past that time; one more longest period
    covers a full cycle of each periodic mover after it.

    Returns
    -------
    float
        0 without movers or when nothing changes after ``t0`` but periodic motion with
        no period (speed 0).
    """
    settle = 0.0
    period = 0.0
    for mv in scene.movers:
        if mv.trajectory is not None:
            settle = max(settle, float(mv.trajectory[-1, 0]) - t0)
        elif mv.mode == "once":
            settle = max(settle, mv.rest_time - t0)  # -inf (nothing) for speed 0
        elif math.isfinite(mv.period):
            period = max(period, mv.period)
    return max(settle, 0.0) + period


def plan(
    scene: Scene,
    roadmap: Roadmap,
    start,
    goal,
    t0: float = 0.0,
    options: PlanOptions | None = None,
    hold: float = 0.0,
) -> PlanResult:
    """Answer one query (see :meth:`Planner.plan`); builds a :class:`Planner` each call."""
    return Planner(scene, roadmap).plan(start, goal, t0, options, hold=hold)
