"""What a query is asked with and answered with: :class:`PlanOptions`, :class:`PlanStats`,
:class:`PlanResult` (and its trajectory file), for :class:`gfuzzy.planner.planner.Planner`,
which re-exports them (``from gfuzzy.planner.planner import PlanOptions`` keeps working).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from ..errors import InputError, check_number
from ..status import Status
from ..timespace.backends import BACKENDS
from ..trajectory import Trajectory, TrajectoryFile

if TYPE_CHECKING:  # the stages' modules load only when a stage runs
    from ..fuzzy.fuzzy import RuleBase
    from ..ga import GAOptions
    from .stages import RefineReport, SpeedReport

__all__ = ["PlanOptions", "PlanResult", "PlanStats"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class PlanOptions:
    """Settings of a query.

    Attributes
    ----------
    dt : float
        Time step of the search (the paper's 0.07).
    horizon : float or None
        Longest trajectory considered, in seconds after t0 (a query's ``hold`` comes on
        top); None picks ``60 + 10 * roadmap distance / vmax``, plus the time until the
        movers' behaviour stops changing (:func:`settle_time`).
    time_limit : float
        Planning-time budget in seconds; past it the answer is ``timeout``. A fresh
        installation's one compile of the search kernels (no precompiled extension, no
        numba cache: 20-40 s, more on a busy machine), and of the GA's with ``refine``, is
        done before the clock starts.
    connect_k : int
        How many nearest roadmap vertices start and goal try to connect to.
    refine : bool
        Apply the GA refinement (:mod:`gfuzzy.ga`).
    speed_layer : bool
        Apply the fuzzy speed layer (:mod:`gfuzzy.fuzzy.fuzzy`).
    seed : int
        Seed of the random steps after the search (GA, rule learning).
    ga : object or None
        ``gfuzzy.ga.GAOptions`` for the refinement (None: defaults).
    rules : object or None
        ``gfuzzy.fuzzy.fuzzy.RuleBase`` of the speed layer (None: the expert rules).
    refine_max_slowdown : float
        The refined answer is kept only if its duration is at most this fraction longer
        than the unrefined one (it is shorter and smoother, but may have to wait more).
    weight : float
        Heuristic weight of the search: 1 finds the earliest arrival the graph and the
        time step allow; w > 1 (weighted A*) expands far fewer states and arrives at most
        w times later than that.
    stretch : float
        The search runs on the roadmap's spanner of this stretch (:meth:`Roadmap.spanner`):
        every static route is at most this much longer than on the whole roadmap, with
        about half the edges to search. 1 searches the whole roadmap.
    backend : str
        ``"compiled"`` runs the search loop in machine code (:mod:`gfuzzy.timespace.search_kernel`,
        numba); ``"reference"`` runs the pure-Python definition
        (:func:`gfuzzy.timespace.timespace.sipp`). Both give the same answers. The stages'
        timing of a refined or speed-limited path (:mod:`gfuzzy.planner.retime`) uses the same.
    drive_repair : bool
        A box or footprint differential drive whose graph leaves the query's ends apart has
        its pieces joined by small-step manoeuvres (:mod:`gfuzzy.timespace.unirepair`): it
        finds ways round tight bends that turns at vertices miss, at a bounded cost where no
        way exists (``unirepair.TOTAL`` expansions; on by default, ``--no-drive-repair``
        turns it off).
    """

    dt: float = 0.07
    horizon: float | None = None
    time_limit: float = 60.0
    connect_k: int = 10
    refine: bool = False
    speed_layer: bool = False
    seed: int = 0
    ga: GAOptions | None = None
    rules: RuleBase | None = None
    refine_max_slowdown: float = 0.1
    weight: float = 1.0
    stretch: float = 1.05
    backend: str = "compiled"
    drive_repair: bool = True

    def __post_init__(self):
        check_number("dt", self.dt)
        if self.horizon is not None:
            check_number("horizon", self.horizon, finite=False)
        check_number("time_limit", self.time_limit, finite=False)
        check_number("weight", self.weight, 1.0, strict=False)
        check_number("stretch", self.stretch, 1.0, strict=False)
        if self.backend not in BACKENDS:
            raise InputError(f"backend must be one of {', '.join(BACKENDS)}, got {self.backend!r}")
        if isinstance(self.seed, (int, np.integer)) and self.seed < 0:  # the GA's; numpy refuses it later
            raise InputError(f"seed (the GA's, --ga-seed) must be a whole number >= 0, got {self.seed}")


@dataclass(frozen=True)
class PlanStats:
    """What one query's planning did; a field is None where that step did not run.

    Attributes
    ----------
    expansions, states : int or None
        States the search expanded and generated.
    graph_nodes : int or None
        Points of the space-time graph searched.
    roadmap_vertices : int or None
    mover_evaluations : int or None
        (point, step) pairs whose safety from the movers was computed.
    horizon : float or None
        The planning horizon (s after t0) of the last search round.
    hold : float or None
        The query's ``hold``, when it has one.
    search_seconds : float or None
        Seconds until the search's answer (before the stages).
    nodes : int or None
        Graph size when start and goal are not connected (no search ran).
    amax_honoured : bool or None
        For a robot with ``amax``: whether the answer keeps it (only the speed layer does,
        applied to the whole path).
    amax_note : str or None
        Why ``amax`` is not honoured.
    """

    expansions: int | None = None
    states: int | None = None
    graph_nodes: int | None = None
    roadmap_vertices: int | None = None
    mover_evaluations: int | None = None
    horizon: float | None = None
    hold: float | None = None
    search_seconds: float | None = None
    nodes: int | None = None
    amax_honoured: bool | None = None
    amax_note: str | None = None

    def to_dict(self) -> dict:
        """The trajectory file's ``stats`` form: the fields that are set, in this order."""
        return {f.name: getattr(self, f.name) for f in fields(self) if getattr(self, f.name) is not None}


@dataclass(frozen=True)
class PlanResult:
    """Answer to a query.

    Attributes
    ----------
    status : Status
    trajectory : Trajectory or None
        Only for ``Status.SOLVED``.
    message : str
        Why, when not solved.
    roadmap_distance : float
        Shortest start-to-goal distance on the roadmap (inf when not connected).
    planning_seconds : float
    stats : PlanStats
        What the search did (expansions, states, graph size, horizon) and whether the
        answer honours ``robot.amax``.
    refine_report, speed_report : gfuzzy.planner.stages.RefineReport / SpeedReport or None
        What each stage did, when it ran.
    """

    status: Status
    trajectory: Trajectory | None
    message: str = ""
    roadmap_distance: float = math.inf
    planning_seconds: float = 0.0
    vmax: float = 1.0
    stats: PlanStats = field(default_factory=lambda: PlanStats())
    refine_report: RefineReport | None = None
    speed_report: SpeedReport | None = None

    @property
    def solved(self) -> bool:
        return self.status is Status.SOLVED

    @property
    def duration(self) -> float | None:
        return None if self.trajectory is None else self.trajectory.duration

    @property
    def delay_factor(self) -> float | None:
        if self.trajectory is None:
            return None
        return self.trajectory.delay_factor(self.vmax, self.roadmap_distance)

    @property
    def amax_honoured(self) -> bool | None:
        """Whether the answer keeps the robot's ``amax`` (only the speed layer does); None
        when the robot has no ``amax`` or the query is not solved. ``stats.amax_note``
        says why not."""
        return self.stats.amax_honoured

    def to_file(self, scene: str, query: str) -> TrajectoryFile:
        """The contract's trajectory file for this answer.

        Beyond the contract's keys it holds ``stats`` and, for a robot with ``amax``,
        ``amax_honoured`` (and ``amax_note`` saying why not when it is false).
        """
        rd = self.roadmap_distance if math.isfinite(self.roadmap_distance) else None
        stats = self.stats.to_dict()
        extra = {key: stats.pop(key) for key in ("amax_honoured", "amax_note") if key in stats}
        for key, report in (("refine", self.refine_report), ("speed_layer", self.speed_report)):
            if report is not None:
                stats[key] = report.to_dict()
        return TrajectoryFile(
            scene=scene,
            query=query,
            status=self.status.value,
            message=self.message,
            duration=self.duration,
            roadmap_distance=rd,
            delay_factor=self.delay_factor,
            planning_seconds=round(self.planning_seconds, 6),
            waypoints=None if self.trajectory is None else self.trajectory.waypoints,
            extra={"stats": _jsonable(stats), **extra},
        )


def _amax_stats(robot, stats: PlanStats, layer: SpeedReport | None) -> PlanStats:
    """``stats`` plus whether a solved answer honours ``robot.amax`` (when the robot has one).

    Only the speed layer (its report: ``layer``) limits acceleration; the search's and the
    GA's answers start, stop and turn at full speed. A user who set ``amax`` is told when it
    was not applied, and why.
    """
    if robot.amax is None:
        return stats
    honoured = bool(layer is not None and layer.whole)
    note = None
    if layer is None:
        note = (
            f"robot.amax {robot.amax:g} is not honoured: only the speed layer bounds "
            "acceleration, and it is off (PlanOptions.speed_layer, --speed-layer)"
        )
    elif not layer.applied:
        note = (
            f"robot.amax {robot.amax:g} is not honoured: the speed layer did not apply "
            f"({layer.reason or 'no reason given'})"
        )
    elif not layer.whole:
        h = layer.hasty
        note = (
            f"robot.amax {robot.amax:g} is not honoured on {h['legs']} of the path's {h['of']} legs "
            f"({h['length']:.2f} of {h['total']:.2f} m metric length, turns as r*angle): no timing of the whole layered path exists among "
            "the movers, and those legs keep the search's pace where a mover forces haste"
        )
    if note:
        log.info("%s", note)
    return replace(stats, amax_honoured=honoured, amax_note=note)


def _jsonable(obj):
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        return float(obj)
    if isinstance(obj, (np.integer, int)) and not isinstance(obj, bool):
        return int(obj)
    return obj
