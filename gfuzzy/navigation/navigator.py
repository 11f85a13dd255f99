"""Navigation among movers whose future is unknown (CONTRACT.md section 5).

The planner of :mod:`gfuzzy.planner.planner` is told every mover's whole future; a robot among
people only sees where they are and how fast they walk now. :class:`Navigator` turns the
roadmap-time search into a receding-horizon controller:

1. **Predict.** Each observed disc ``[x, y, vx, vy, r]`` walks on at constant velocity for
   ``prediction_horizon`` seconds (a person standing still stays ``stationary_hold``
   longer), inflated by the robot's ``mover_clearance``, a ``safety_buffer`` and an
   uncertainty growing with the prediction time, by steps of ``slice`` seconds. Each
   person is one ``trajectory`` mover of the search's :class:`~gfuzzy.timespace.movers.MoverField`
   whose growing inflation is in the field's per-step margin (the same test as a chain of
   ever larger discs); only people who can come within reach of where the robot can be
   are predicted in detail (:meth:`Navigator._relevant`: the others cannot matter).
2. **Plan.** The safe-interval search runs from the robot's current pose on the roadmap's
   split graph, built once per navigator with its exact static heuristic; each call only
   splices the pose in. It stops at 75 % of ``time_budget``, even inside a batch of
   safety computations.
3. **Fall back.** No plan (the predictions block every way, or no time): the same search
   without the buffer and the uncertainty ("relaxed"); a finely checked straight dash to
   a nearby goal ("direct"); the previous plan if still clear ("previous"); otherwise the
   *evasive motion*, the statically free straight motion (or standing still) with the
   latest contact with the people walking on. The fallbacks only look at the people who
   can come near within their look-ahead, so their cost is bounded too.

``step`` never raises for a hard situation and always returns a trajectory whose first row
is ``[t, *pose]`` and that meets the speed bound.
"""

from __future__ import annotations

import functools
import logging
import math
from dataclasses import replace

import numpy as np

from ..collision.geometry import StaticGeometry, mover_distance
from ..errors import InputError, LimitError
from ..planner.planner import search_function
from ..poses import metric_distance, wrap_angle
from ..roadmap.roadmap import Roadmap
from ..scene.scene import Scene
from ..settings import SPEED_SAFETY
from ..status import Status
from ..timespace.drive import Fan, drive_rows
from ..timespace.movers import MoverField
from ..timespace.spacetime import IntervalStore, SearchResult
from ..timespace.timespace import timed_rows
from ..trajectory import Trajectory
from ..typed import FloatArray
from .brisk import brisk, brisk_arrival
from .drivenav import drive_evasion, kept_plan, rest_of, sooner_plan, static_route
from .effort import Effort
from .evasion import holonomic_evasion
from .lookout import Lookout
from .navinput import checked_pose, flat_pose, observation_rows
from .navoptions import BUDGET_CLOCKS, NavOptions
from .navtypes import GOAL_TAKEN, MOTION_SAMPLE, NavMode, NavStep, _Searched, sample_loss
from .pathspace import STILL_SPEED, PathSpace, WallCheck  # noqa: F401 (STILL_SPEED: kept importable here)
from .prediction import REACH_SAMPLES, Prediction, prior_store  # noqa: F401 (REACH_SAMPLES: kept importable here)
from .softcost import SoftCost
from .timedfield import PAIR_SECONDS, PIECE_WORK, Pace, _OutOfTime, _TimedField  # noqa: F401 (PIECE_WORK, PAIR_SECONDS: kept importable here)
from .unknown import unknown_growth, unknown_positions

__all__ = ["NavMode", "NavOptions", "NavStep", "Navigator"]

log = logging.getLogger(__name__)

#: Share of ``time_budget`` the search may use; the rest is the fallback's (more when the
#: calls have been measured to need more after the search's deadline: ``TAIL_RESERVE``).
SEARCH_SHARE = 0.75
#: The search's deadline is this many times the measured tail of the calls (from the
#: deadline to the answer: the last piece of safety work, the fallbacks) before the end of
#: the budget, when that is earlier than ``SEARCH_SHARE`` of it, but never before half of
#: ``SEARCH_SHARE``. A footprint differential drive's evasion (its turns swept, its
#: polygon's gaps to people sampled over 4 s) costs 20-28 ms of CPU and its safety pieces
#: several ms each: cut at 75 %, its calls ended at 92-108 ms on a pedestrian replay.
TAIL_RESERVE = 1.25
#: The measured tail decays by this factor each call (half-life about 14 calls), and one
#: call counts for at most ``TAIL_CAP`` of the budget.
TAIL_DECAY, TAIL_CAP = 0.95, 0.5
#: Share of ``time_budget`` after which a differential drive's two-leg motions
#: (``NavOptions.fan``) are no longer added: among walls their static checks cost
#: milliseconds a heading, and the search must still have its time.
FAN_SHARE = 0.3
#: First guess (s) of the predictions' set-up per person (then measured per navigator).
PERSON_SECONDS = 150e-6

#: The answers a look may replace (a fresh plan keeping the margins, or one kept): never
#: the relaxed search's or a fallback's, which answer a situation the search could not
#: (the evasive motion is scored over ``evasion_time``, a look is checked over
#: ``lookout.LOOK_CHECK`` only).
LOOK_OVER = (NavMode.PLAN, NavMode.CLOSE, NavMode.KEPT)


class Navigator(PathSpace, Prediction, SoftCost):
    """Receding-horizon navigation to a fixed goal among observed moving discs.

    Parameters
    ----------
    scene : Scene
        Its bounds, robot and static obstacles are used; its movers are ignored.
    roadmap : Roadmap
        A roadmap of ``scene`` (see :meth:`Roadmap.check_scene`).
    goal : (d,) float
        The goal pose.
    options : NavOptions, optional

    Raises
    ------
    ValueError
        The goal is malformed, out of bounds or in a static obstacle.

    Examples
    --------
    >>> nav = Navigator(scene, roadmap, goal)                     # doctest: +SKIP
    >>> traj = nav.step(0.0, start, np.array([[1, 0, -1, 0, 0.3]]))  # doctest: +SKIP
    """

    def __init__(self, scene: Scene, roadmap: Roadmap, goal, options: NavOptions | None = None):
        roadmap.check_scene(scene)
        self.options = opts = options or NavOptions()
        self.scene = scene
        self.roadmap = roadmap
        self.robot = robot = scene.robot
        self.geometry = StaticGeometry(scene)
        goal = flat_pose(goal, robot, "goal")
        if self.geometry.bounds_clearance(goal[None])[0] < 0 or self.geometry.clearance1(goal) < 0:
            raise InputError(f"goal {goal.tolist()} is out of bounds or collides with a static obstacle")
        self.goal = goal
        self._goal_wrapped = goal.copy()
        if robot.dof == 3:
            self._goal_wrapped[2] = wrap_angle(goal[2])
        self.vplan = robot.vmax * SPEED_SAFETY
        self.step_len = self.vplan * opts.dt
        self.mover_clearance = float(getattr(robot, "mover_clearance", 0.0) or 0.0)
        # the predicted world carries the clearance in its radii: the search's robot keeps none
        self._pred_robot = replace(robot, mover_clearance=0.0) if hasattr(robot, "mover_clearance") else robot
        self.reached = False
        self.replans = 0
        self._t_last = -math.inf  # the last call's time: time never runs backwards
        self.last: NavStep | None = None
        self._previous: Trajectory | None = None
        self._previous_mode: NavMode | None = None  # the mode of the search that made it
        self._previous_ahead: list = []  # and the roadmap vertices it heads for
        self._evading: Trajectory | None = None  # the last answer when it was an evasion
        self._ahead: list = []  # (arrival time, roadmap vertex) of the last plan
        self._clock = BUDGET_CLOCKS[opts.budget_clock]  # the budget's clock (a test may replace it)
        self._person_seconds = PERSON_SECONDS  # the predictions' set-up per person, measured
        self._tail_seconds = 0.0  # from the search's deadline to the answer, measured (decaying maximum)
        self._pace = Pace()  # the time of a piece of the predictions' safety work, measured (timedfield)
        self._effort = Effort(opts)  # the searches' effort (path space, slack), from the calls' pressure on the budget
        self._walls = WallCheck(scene)
        disc = robot.shape == "disc" and robot.dof == 2  # its view follows its motion
        self._lookout = Lookout(opts.fov, opts.look_after, goal) if opts.fov < 360 and disc else None
        self._unknown = np.zeros((0, 2))  # where the people of unknown velocity stand (this call)
        self._build_base()
        if opts.backend == "compiled":  # load the compiled kernels now, not inside a step's budget
            from ..timespace.jit import note_cold

            note_cold()
            from ..timespace.search_kernel import warm

            warm()
        if opts.soft_search:  # the priced search runs numba's kernels whatever the backend
            from ..timespace.soft_kernel import warm as warm_soft

            warm_soft()

    # ------------------------------------------------------------------ graph
    def _build_base(self) -> None:
        """The goal's graph, kept for every call: the planner's (``Planner.prepare``:
        :class:`gfuzzy.planner.prepared.PreparedGoal`, or :class:`gfuzzy.timespace.unicycle.UnicycleGoal` for a
        differential drive); each call splices the robot's pose in (:meth:`_splice`)."""
        from ..planner.planner import Planner, PlanOptions

        opts = self.options
        self._planner = Planner(self.scene, self.roadmap)
        self._planner.geometry = self.geometry
        popts = PlanOptions(dt=opts.dt, connect_k=opts.connect_k, stretch=opts.stretch, backend=opts.backend)
        self._kept = self._planner.prepare(self.goal, popts)
        self._nv = 0 if self.robot.unicycle else self._kept.s_id  # vertices "ahead" (a goal's bridge's too)
        self._exit = self._no_exit = None  # a bridge out of a dead end the robot stood in (_holonomic_splice)
        self._g_id = -1
        self._windows = (None, None)  # (graph, its exact safety windows) of a unicycle's last splice
        self._fan = Fan() if self.robot.unicycle and opts.fan else None

    def _splice_ends(self, pose: FloatArray, ahead=(), fan_until: float = math.inf, deadline: float = math.inf):
        """(graph, start id, goal id, roadmap distance) of the kept graph with ``pose`` in
        (a differential drive's two-leg motions added until ``fan_until`` on the budget's
        clock; a holonomic robot's bridge out of a dead end sought until ``deadline``)."""
        start = pose.copy()
        if self.robot.dof == 3:
            start[2] = wrap_angle(start[2])
        if self.robot.unicycle:
            expired = None if fan_until == math.inf else (lambda: self._clock() > fan_until)
            qg = self._kept.kept.splice(self._planner, start, "later", fan_options=self._fan, expired=expired)
            self._windows = (qg.graph, qg.exact_windows)  # the exact windows, when safety work is done
        else:
            qg = self._holonomic_splice(start, ahead, deadline)
        return qg.graph, qg.s_id, qg.g_id, qg.roadmap_distance

    def _holonomic_splice(self, start: FloatArray, ahead, deadline: float):
        """The kept graph with ``start`` in (its connections leave at full speed). From deep in
        a dead end that no certified motion leaves to the roadmap, the kept graph with a
        bridge from there (:meth:`~gfuzzy.planner.prepared.PreparedGoal.bridged_from`, sought until
        ``deadline``), kept from then on: a superset of the goal's, it answers wherever that
        does, and along the bridge on the way out. A pose whose bridge was not found (none
        there, not for lack of time) is not bridged again while the robot stands there."""
        qg = None
        for kept in (self._exit, self._kept):
            if kept is not None:
                qg = kept.splice(self._planner, start, ahead=ahead, lead=True)
                if math.isfinite(qg.roadmap_distance):
                    return qg
        if self._no_exit is not None and np.array_equal(self._no_exit, start):
            return qg
        found = self._kept.bridged_from(self._planner, start, deadline, self._clock)
        out = None if found is None else found.splice(self._planner, start, ahead=ahead, lead=True)
        if out is None or not math.isfinite(out.roadmap_distance):
            self._no_exit = start if self._clock() <= deadline else None
            return qg
        self._exit, self._no_exit = found, None
        return out

    def roadmap_distance(self, pose) -> float:
        """Shortest distance from ``pose`` to the goal on the whole roadmap (static
        obstacles only; inf when not connected; a unicycle's: its turns included, see
        :class:`gfuzzy.timespace.unicycle.UnicycleGraph`)."""
        return float(self._splice_ends(np.asarray(pose, dtype=float).reshape(-1))[3])

    def _splice(self, pose: FloatArray, t: float = -math.inf, deadline: float = math.inf):
        """The kept graph with ``pose`` spliced in: (graph, start id), or (None, reason);
        ``deadline``: the search's (the two-leg motions stop at ``FAN_SHARE`` of the budget).

        The robot is usually inside an edge of its last plan: it also connects to the
        vertices that plan was heading for (the nearest ones may all lie behind it, and
        going back to one of them before going on would make it dither).
        """
        ahead = [v for ta, v in self._ahead if ta > t + 1e-9]
        # the fan's share of the search's time, FAN_SHARE of SEARCH_SHARE (less with a reserve)
        fan_until = deadline - (1.0 - FAN_SHARE / SEARCH_SHARE) * self._search_seconds()
        graph, s_id, g_id, rd = self._splice_ends(pose, ahead, fan_until, deadline)
        self._g_id = g_id
        if not math.isfinite(rd):
            return None, "the robot's pose connects to no roadmap vertex that leads to the goal"
        return graph, s_id

    # ------------------------------------------------------------------- step
    def step(self, t: float, pose, observations, unknown=None) -> Trajectory:
        """Replan from ``pose`` at time ``t`` given what is seen now.

        Parameters
        ----------
        t : float
        pose : (d,) float
            The robot's pose now (need not be a roadmap vertex).
        observations : (k, 5) float
            ``[x, y, vx, vy, radius]`` per moving obstacle seen at ``t`` (k may be 0).
        unknown : (k,) bool, optional
            Whose velocity is not known (``Sensor.unknown``): walkers of unknown direction (:mod:`.unknown`).

        Returns
        -------
        Trajectory
            First row ``[t, *pose]``; meets the speed bound; the robot follows it until the
            next call. Never raises for a hard situation (no plan: the evasive motion).

        Raises
        ------
        ValueError
            Malformed input (wrong shapes, non-finite numbers, a ``t`` before the last
            call's): a caller's bug.
        """
        t_begin = self._clock()
        opts = self.options
        pose = checked_pose(pose, self.robot, t, self._t_last)
        t = float(t)
        obs = observation_rows(observations)
        self._unknown = unknown_positions(obs, unknown)
        since, self._t_last = t - self._t_last, t  # the time since the last call (inf at the first)
        self.replans += 1
        if self._lookout is not None:
            self._lookout.observe(t, pose)
        cr = self.robot.circumradius
        if float(metric_distance(pose, self.goal, cr)) <= opts.goal_tolerance:
            self.reached = True
            self._evading = None
            self.last = NavStep(NavMode.GOAL, self._clock() - t_begin)
            return Trajectory(np.array([[t, *pose], [t + opts.cover, *pose]]), cr)
        deadline = t_begin + self._search_seconds()
        infl = self._inflation(pose, obs)
        predicted = obs.copy()
        if len(obs):
            predicted[:, 4] = obs[:, 4] + infl[:, 0]
        soft = opts.soft_search and len(obs) > 0 and (opts.path_space > 0 or opts.personal_space > 0)
        traj, mode, found, infl, ghosts = self._searches(t, pose, obs, infl, deadline, soft)
        if traj is not None and mode in (NavMode.PLAN, NavMode.CLOSE):  # at full speed: all of it, or into the goal
            keep = functools.cache(lambda: self._kept_inflation(pose, obs, infl, mode))  # only when checked
            if opts.full_speed:
                traj = brisk(self, t, pose, traj, obs, keep, ghosts)
            traj = brisk_arrival(self, t, pose, traj, obs, keep, ghosts, since)
        out_of_time = found.out_of_time
        if traj is None and len(obs) and not found.out_of_time and self._clock() < deadline:
            # blocked by the margins (someone beside the goal, a narrow gap): the discs as they are + mover clearance
            with self._effort.searching(self):
                relaxed = self._relaxed(t, pose, obs, found, deadline)
            traj, mode, out_of_time = relaxed.trajectory, NavMode.RELAXED, relaxed.out_of_time
        self._effort.record(out_of_time, self._clock() - t_begin, deadline - t_begin)
        if traj is None:
            traj = self._direct(t, pose, obs)
            mode = NavMode.DIRECT
        if traj is None:
            traj, mode = self._previous_if_clear(t, pose, obs), NavMode.PREVIOUS
            if traj is None and self.robot.unicycle:  # nobody near: on along the static route, not standing
                traj, mode = static_route(self, t, pose, obs, found.graph, found.start), NavMode.ROUTE
            if traj is None:
                traj, mode = self._evasive(t, pose, obs), NavMode.EVASIVE
        else:
            if self.robot.unicycle:  # a unicycle's change of mind costs turns: keep the last plan if as good
                kept = kept_plan(self, t, pose, obs, self._kept_inflation(pose, obs, infl, mode), traj,
                                 opts.commitment)
                if kept is not None:
                    traj, mode = kept, NavMode.KEPT
            elif soft and mode in (NavMode.PLAN, NavMode.CLOSE):  # the last plan if as good at the price
                traj, mode = self._priced_kept(t, pose, obs, traj, mode)
            elif self._previous_mode in (NavMode.PLAN, NavMode.CLOSE) and mode != NavMode.DIRECT and len(obs):
                # the last plan, still as safe as when it was made, arriving much sooner
                kept = sooner_plan(self, t, pose, obs, self._kept_inflation(pose, obs, infl, self._previous_mode),
                                   traj, self._soft_costs())
                if kept is not None:
                    traj, mode = kept, NavMode.KEPT
                    self._ahead = self._previous_ahead  # the vertices the kept plan heads for
            self._previous = traj
            if mode != NavMode.KEPT:
                self._previous_mode, self._previous_ahead = mode, self._ahead
        if mode == NavMode.EVASIVE:
            self._previous = None
        self._evading = traj if mode == NavMode.EVASIVE and self.robot.unicycle else None
        if self._lookout is not None and mode in LOOK_OVER:  # never instead of a fallback
            looked = self._lookout.look(self, t, pose, obs, traj)
            if looked is not None:
                traj, mode = looked, NavMode.LOOK
        t_end = self._clock()
        self._measure_tail(t_end - deadline)
        self.last = NavStep(mode, t_end - t_begin, found.message, predicted, found.detailed, out_of_time)
        return traj

    def _searches(self, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, deadline: float, soft: bool):
        """(plan, mode, search, inflation, ghosts kept) of the priced search (``soft``) or the
        tiers, at the effort the calls' pressure on the budget leaves them (:mod:`.effort`)."""
        with self._effort.searching(self):
            if soft:  # one priced search: its plan keeps the buffer and the uncertainty only
                traj, mode, found, infl = self._priced(t, pose, obs, deadline)
                return traj, mode, found, infl, False
            traj, mode, found, ghosts = self._tiers(t, pose, obs, infl, deadline)
            return traj, mode, found, infl, ghosts

    def _measure_tail(self, over: float) -> None:
        """Keep the time a call went on past the search's deadline (``over``), to reserve it:
        at most ``TAIL_CAP`` of the budget (a stall of the machine is not a tail), in a
        maximum that decays every call (one slow call must not halve the search's time for
        the rest of the run)."""
        over = min(max(over, 0.0), TAIL_CAP * self.options.time_budget)
        self._tail_seconds = max(over, TAIL_DECAY * self._tail_seconds)

    def _search_seconds(self) -> float:
        """The share of the budget the searches may use: ``SEARCH_SHARE``, less when the
        calls have been measured to go on after the deadline for longer than the rest
        (``TAIL_RESERVE`` times that tail kept free), but at least half of it."""
        budget = self.options.time_budget
        spare = budget - TAIL_RESERVE * self._tail_seconds
        return max(min(SEARCH_SHARE * budget, spare), 0.5 * SEARCH_SHARE * budget)

    def _keeps_gaps(self, traj: Trajectory, t: float, t_end: float, obs: FloatArray, infl: FloatArray) -> bool:
        """Whether ``traj`` keeps, from ``t`` to ``t_end`` (sampled every ``MOTION_SAMPLE``
        s, with the gap two samples can lose), the gap ``infl`` (k, S) (by prediction slice)
        from each of ``obs`` walking on at constant velocity (:meth:`_short_along`)."""
        times = t + np.arange(0.0, t_end - t + MOTION_SAMPLE, MOTION_SAMPLE)
        lost = sample_loss(self.vplan, np.hypot(obs[:, 2], obs[:, 3]))
        return not bool(self._short_along(traj, t, times, obs, infl, lost).any())

    def _short_along(self, traj: Trajectory, t: float, times: FloatArray, obs: FloatArray, infl: FloatArray,
                     lost: FloatArray | float = 0.0) -> np.ndarray:  # fmt: skip
        """(T, k) whether ``traj`` at ``times`` is within the gap ``infl`` (k, S) (slice by
        time after ``t``) plus ``lost`` of each of ``obs`` walking on at constant velocity;
        rows of 7 columns (ghosts) count only from ``t + appear`` to ``t + vanish``."""
        pts = traj.at(np.minimum(times, traj.t_end))
        gap = self._clearance_along(pts, times, obs[:, :5]) + self.mover_clearance  # (T, k)
        s_of = np.minimum(np.floor((times - t) / self.options.slice + 1e-9).astype(np.int64), infl.shape[1] - 1)
        short = gap < infl[:, s_of].T + np.reshape(lost, (1, -1))
        if obs.shape[1] > 6:
            tau = (times - t)[:, None]
            short &= (tau >= obs[None, :, 5] - MOTION_SAMPLE) & (tau <= obs[None, :, 6] + MOTION_SAMPLE)
        return short

    def _kept_inflation(self, pose: FloatArray, obs: FloatArray, infl: FloatArray, mode: NavMode) -> FloatArray:
        """(k, S) the gaps the fresh plan of ``mode`` kept: a kept plan must keep them too."""
        if mode == NavMode.PLAN:
            return infl
        if mode == NavMode.CLOSE:  # the safety buffer and the uncertainty, not the personal space
            return self._inflation(pose, obs, personal=False)
        return self._inflation(pose, obs, relaxed=True)

    def _closer(self, t: float, pose: FloatArray, obs: FloatArray, found: _Searched, deadline: float,
                ghosts: bool = False) -> tuple[Trajectory | None, NavMode, _Searched]:  # fmt: skip
        """The personal space as a soft cost: the first search's plan, unless the search
        without the personal space (the safety buffer and the uncertainty kept, and the
        people's ways when ``ghosts``: the first kept them) arrives sooner by more than
        ``personal_space_cost``, or the first found none.

        The second search runs only when it can win: when the first found no plan, or
        when the first's arrival is later than the static lower bound (the roadmap's
        time to the goal) by more than the cost.
        """
        opts = self.options
        first = found.trajectory
        if first is not None:
            bound = float(found.graph.heuristic[found.start]) * opts.dt
            if first.t_end - t <= bound + opts.personal_space_cost + 1e-9:
                return first, NavMode.PLAN, found
        elif found.out_of_time:
            return None, NavMode.PLAN, found
        bare = self._inflation(pose, obs, personal=False)
        close = self._search(t, pose, *(self._with_ghosts(pose, obs, bare) if ghosts else (obs, bare)), deadline, found)
        second = close.trajectory
        if second is not None and (first is None or second.t_end < first.t_end - opts.personal_space_cost):
            return second, NavMode.CLOSE, close
        if first is not None:
            self._ahead = found.ahead  # the second search replaced the plan's vertices ahead
            return first, NavMode.PLAN, found
        return None, NavMode.PLAN, close

    def _search(self, t: float, pose: FloatArray, obs: FloatArray, infl: FloatArray, deadline: float,
                before: _Searched | None = None) -> _Searched:  # fmt: skip
        """The safe-interval search among the predicted people, within ``deadline``.

        The predictions are built only when the time left can pay for them (their cost
        per person is measured as the navigator runs); the search stops at ``deadline``
        even inside a batch of safety computations (:class:`_TimedField`). A request the
        search refuses (:class:`InputError`, :class:`LimitError`: e.g. a horizon beyond
        the memory bounds) is a hard situation the fallback answers; any other exception
        is a bug and propagates.
        """
        opts = self.options
        try:
            start = self._search_start(pose, t, deadline, before)
            if isinstance(start, _Searched):
                return start
            graph, s_id, h0 = start
            store, safety = None, None
            search = search_function(opts.backend)
            slack = (opts.plan_slack + opts.prediction_horizon) / opts.dt
            detailed = 0
            for _ in range(2):
                steps = int(math.ceil(h0 + slack))
                keep = self._relevant(pose, obs, infl, steps * opts.dt)
                detailed = int(keep.sum())
                c0 = self._clock()
                if not self._affords(c0, detailed, deadline):  # the fallback answers
                    return _Searched(None, "time budget spent before the search", detailed, True, graph, s_id)
                if store is None:  # a unicycle's exact windows only pay where someone is predicted
                    if detailed:
                        self._exact_windows(graph)
                    store = IntervalStore(graph)
                field_ = self._field(t, obs[keep], infl[keep], steps, deadline)
                earlier = before.safety if before is not None and before.graph is graph else None
                store.prior = prior_store(earlier, obs, infl, keep)  # the earlier search's safe points, if they hold here
                safety = (store, obs, infl, keep)
                if detailed >= 10:  # a cautious running estimate: up at once, down by a fifth
                    took = (self._clock() - c0) / detailed
                    self._person_seconds = max(took, 0.8 * self._person_seconds + 0.2 * took)
                if self._goal_taken(store, field_):  # the search would exhaust its budget to learn it
                    res = SearchResult(Status.NO_PATH, message=GOAL_TAKEN, horizon_hit=True)
                else:
                    res = search(graph, field_, s_id, self._g_id, deadline=deadline, store=store, clock=self._clock)
                if res.status != Status.NO_PATH or not res.horizon_hit or self._clock() > deadline:
                    break
                slack *= 2.0
        except _OutOfTime:
            return _Searched(None, "time budget spent on the predicted people's safety", detailed, True, graph, s_id,
                             safety=safety)  # fmt: skip
        except (InputError, LimitError) as exc:  # a request the search refuses: the fallback answers
            log.warning("navigator search refused at t=%g: %s", t, exc)
            return _Searched(None, f"search refused: {exc}")
        return replace(self._answered(res, graph, s_id, t, pose, detailed), safety=safety)

    def _search_start(self, pose: FloatArray, t: float, deadline: float, before: _Searched | None = None):
        """(graph, start id, the start's heuristic in steps) for a search from ``pose`` (the
        graph ``before`` spliced, if any), or the :class:`_Searched` saying why none can run
        (no splice, or a goal the roadmap does not reach from there)."""
        if before is not None and before.graph is not None:
            graph, s_id = before.graph, before.start
        else:
            graph, s_id = self._splice(pose, t, deadline)
        if graph is None:
            return _Searched(None, s_id)
        h0 = float(graph.heuristic[s_id])
        if not math.isfinite(h0):
            return _Searched(None, "the goal is not reachable on the roadmap", graph=graph, start=s_id)
        return graph, s_id, h0

    def _exact_windows(self, graph) -> None:
        """Give a unicycle's ``graph`` (spliced without them: 0 bounds every point) its exact safety
        windows: a Dijkstra from the pose that pays only where safety work is done."""
        spliced, later = self._windows
        if spliced is graph and later is not None:
            graph.from_start, self._windows = later(), (None, None)

    def _answered(self, res: SearchResult, graph, s_id: int, t: float, pose: FloatArray, detailed: int) -> _Searched:
        """What a finished search found (this one's or the priced one's): its plan timed from
        ``pose`` at ``t`` to the goal, the roadmap vertices it heads for kept, or why none."""
        dt = self.options.dt
        if res.status != Status.SOLVED:
            return _Searched(None, res.message, detailed, res.status == Status.TIMEOUT, graph, s_id)
        rows, _ = timed_rows(res.nodes, res.steps, graph.poses, t, dt)
        self._ahead = [(t + st * dt, nd) for nd, st in zip(res.nodes, res.steps, strict=True) if nd < self._nv]
        rows[0, 1:] = pose
        rows[-1, 1:] = self.goal
        return _Searched(Trajectory(rows, self.robot.circumradius), "", detailed, False, graph, s_id, self._ahead)

    def _goal_taken(self, store: IntervalStore, field_: MoverField) -> bool:
        """True when the goal is unsafe at every step the search could arrive there (its
        window of the horizon): someone stands on it, with this search's margins. No plan
        exists then, and the search would only learn it by expanding every reachable state
        (among people standing round the goal that outlasts the budget, and a fallback
        without the next tier answers); one batch of safety tells it."""
        store.set_horizon(field_, pool=self.options.backend == "compiled")
        return len(store.get(self._g_id)[0]) == 0

    # --------------------------------------------------------------- fallback
    def _clearance_along(self, pts: FloatArray, times: FloatArray, obs: FloatArray,
                         exact_below: float = math.inf) -> FloatArray:  # fmt: skip
        """(..., k) gap between the robot at ``pts`` (..., T, d) and each person walking
        on at constant velocity at ``times`` (T,), minus the mover clearance (and the
        growth of a person of unknown velocity).

        ``exact_below``: a robot that is not a disc gets its exact gap only where the gap of
        its circumscribed disc (a lower bound) is below this; elsewhere that bound. The
        evasive motion's scores cannot tell gaps above their threshold apart, and a
        footprint's exact gaps to 60 people over 50 candidates and 4 s cost 75-150 ms."""
        pos = obs[None, :, :2] + (times - times[0])[:, None, None] * obs[None, :, 2:4]  # (T, k, 2)
        less = self.mover_clearance + unknown_growth(self._unknown, obs, times - times[0])  # (T, k)
        if exact_below == math.inf and self.robot.shape != "disc":
            return mover_distance(self._pred_robot, pts[..., None, :], "disc", obs[:, 4], (0.0, 0.0), pos) - less
        else:  # the centres' distance, in place: the evasions' (C, T, k) arrays are most of their cost
            d = np.hypot(pos[..., 0] - pts[..., None, 0], pos[..., 1] - pts[..., None, 1])
            d -= self.robot.radius if self.robot.shape == "disc" else self.robot.circumradius
            d -= obs[:, 4]
        if self.robot.shape != "disc":
            exact = d - less < exact_below
            if exact.any():
                at = np.broadcast_to(pts[..., None, :], (*d.shape, pts.shape[-1]))[exact]
                d[exact] = mover_distance(self._pred_robot, at, "disc", np.broadcast_to(obs[:, 4], d.shape)[exact],
                                          (0.0, 0.0), np.broadcast_to(pos, (*d.shape, 2))[exact])  # fmt: skip
        d -= less
        return d

    def _direct(self, t: float, pose: FloatArray, obs: FloatArray) -> Trajectory | None:
        """Straight to the goal at full speed, if it is statically free and keeps clear of
        everyone seen now walking on at constant velocity (un-inflated) until arrival and
        for a second after; None otherwise.

        The search's own margin (half a step of motion) can close the last gap to a goal
        beside a person standing still; this motion is checked every 0.01 s with a margin
        of 0.02 m, which bounds the gap between the samples (it changes by at most 2 m/s).
        """
        cr = self.robot.circumradius
        if self.robot.unicycle:
            rows = drive_rows(self.geometry, t, pose, [], self.goal, self.vplan)
            if rows is None:
                return None
            duration = float(rows[-1, 0] - t)
        else:
            if not self.geometry.motion_free(pose, self.goal):
                return None
            length = float(metric_distance(pose, self.goal, cr))
            duration = length / self.vplan
            rows = np.array([[t, *pose], [t + duration, *self.goal]])
        if duration > self.options.prediction_horizon:
            return None
        traj = Trajectory(rows, cr)
        speed = float(np.max(np.hypot(obs[:, 2], obs[:, 3]), initial=0.0))
        tol = (self.vplan + speed) * 0.005 + 1e-3
        obs = self._near(pose, obs, duration + 1.0 + 0.01, tol)
        if len(obs):
            times = np.arange(t, t + duration + 1.0 + 0.01, 0.01)
            if np.min(self._clearance_along(traj.at(times), times, obs)) <= tol:
                return None
        return traj

    def _previous_if_clear(self, t: float, pose: FloatArray, obs: FloatArray) -> Trajectory | None:
        """The last plan from ``t`` on, if the robot is on it and it keeps clear of everyone
        seen now (walking on at constant velocity, un-inflated) over the prediction horizon:
        sampled every ``MOTION_SAMPLE`` s, with a gap that bounds the one in between
        (:meth:`_sample_gap`)."""
        prev = self._previous
        if prev is None or prev.t_end <= t + 1e-9:
            return None
        rest = rest_of(prev, t, pose)
        if rest is None:
            return None
        horizon = self.options.prediction_horizon
        tol = self._sample_gap(obs)
        obs = self._near(pose, obs, horizon, tol)
        if len(obs):
            times = np.linspace(t, t + horizon, int(math.ceil(horizon / MOTION_SAMPLE)) + 1)
            if np.min(self._clearance_along(rest.at(times), times, obs)) <= tol:
                return None
        return rest

    def _soft_costs(self) -> float:
        """Seconds of arrival the soft costs are worth together (the personal space's and,
        when it is kept, the path space's): a last plan kept for arriving sooner must beat
        the fresh one by more, or it would undo what the soft costs bought."""
        opts = self.options
        return opts.personal_space_cost + (opts.path_space_cost if opts.path_space > 0 else 0.0)

    def _sample_gap(self, obs: FloatArray) -> float:
        """Gap (m) to keep at samples ``MOTION_SAMPLE`` apart so that there is none
        between them: no point of the robot moves faster than ``vmax`` (the speed bound
        counts turning at the circumscribed radius) nor a person faster than seen, so
        the gap changes by at most their sum times half the sampling interval there."""
        speed = float(np.max(np.hypot(obs[:, 2], obs[:, 3]), initial=0.0))
        return sample_loss(float(self.robot.vmax), speed) + 1e-6

    def _evasive(self, t: float, pose: FloatArray, obs: FloatArray) -> Trajectory:
        """The statically free straight motion (or standing still) with the latest contact.

        Candidates: ``evasion_headings`` directions at full and half speed, each going on
        for ``evasion_time`` (or half, or a quarter of it, whichever is free of static
        obstacles) and then standing, and standing still. Each is scored by its time to
        contact with the people walking on at constant velocity (un-inflated, sampled every
        ``MOTION_SAMPLE`` s over ``evasion_time``, with a bound on the gap between two
        samples, see :func:`.evasion.evasion_scores`), then by the smallest gap, then by progress to the goal.
        """
        if self.robot.unicycle:  # turn in place, then drive along the heading (drivenav.drive_evasion)
            return drive_evasion(self, t, pose, obs, self._evading)
        return holonomic_evasion(self, t, pose, obs)
