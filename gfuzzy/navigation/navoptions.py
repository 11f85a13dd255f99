"""The navigator's settings: :class:`NavOptions` (prediction, search, fallbacks, the social
layers, the budget and its clock, :data:`BUDGET_CLOCKS`), checked when made.
:mod:`gfuzzy.navigation.navigator` re-exports them (``from gfuzzy.navigation.navigator
import NavOptions`` keeps working).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from ..errors import InputError, check_number
from ..timespace.backends import BACKENDS

__all__ = ["BUDGET_CLOCKS", "NavOptions"]


#: The clocks a time budget can be measured on (``NavOptions.budget_clock``).
BUDGET_CLOCKS = {"wall": time.perf_counter, "cpu": time.thread_time}


@dataclass(frozen=True)
class NavOptions:
    """Settings of the navigator.

    Attributes
    ----------
    dt : float
        Time step of the search (s). Larger than the planner's 0.07: a replan must be fast,
        and the plan is redone every period anyway.
    prediction_horizon : float
        How long (s) an observed person is predicted to walk on at constant velocity.
    uncertainty_growth : float
        Growth (m per s of prediction time) of the inflation around a predicted person
        walking at ``reference_speed`` or faster; slower people get a proportionally
        slower growth (someone standing still gets none).
    reference_speed : float
        Walking speed (m/s) at which the uncertainty grows at its full rate.
    safety_buffer : float
        Distance (m) kept from every predicted person on top of ``robot.mover_clearance``.
    personal_space : float
        Further distance (m) the first search keeps from every predicted person: the
        robot passes people no closer than this gap (CrowdNav's discomfort distance,
        0.2 m) whenever a plan exists that does; when none does, the relaxed search (the
        people's discs as they are) answers, so the preference never costs a success.
        0 turns it off.
    personal_space_cost : float
        What (s of arrival time) passing within ``personal_space`` of someone is worth
        avoiding: a plan that keeps the personal space is taken unless a plan that keeps
        only the safety buffer (and the uncertainty) arrives sooner by more than this.
        A soft cost: the robot does not detour round a person standing in its way, or
        wait long for a gap wide enough, to keep its distance.
    path_space : float
        Seconds of each walking person's predicted path the first search also keeps the
        robot's body off (:mod:`gfuzzy.navigation.pathspace`): it does not cross just in
        front of someone or wait in their way (CrowdNav++'s intrusion, 1.25 s), whenever
        a plan exists that does not; otherwise the relaxed search answers. 0 turns it off.
    path_space_cost : float
        What (s of arrival time) keeping off people's ways is worth: the plan that keeps the
        path space is taken unless one that does not arrives sooner by more than this.
    social_horizon : float
        Seconds of the plan during which the path space is kept (a plan's far future is
        replanned long before; predictions that far are too uncertain to yield to).
    slice : float
        Length (s) of a piece of prediction with one radius (the inflation grows by steps).
    stationary_hold : float
        A person standing still is kept where they stand this long (s) past the prediction
        horizon; a walking one is dropped there.
    time_budget : float
        Seconds one :meth:`Navigator.step` may take (on ``budget_clock``); the search
        stops at 75 % of it and the fallback answers.
    budget_clock : {"wall", "cpu"}
        The budget's clock: ``"wall"`` (default; what a robot has) or ``"cpu"``, the
        calling thread's CPU time, so that a benchmark's figures do not depend on what
        else runs on the machine (a loaded machine stretches the wall clock, not this).
    plan_slack : float
        Seconds beyond the static time to the goal that the search's horizon allows for
        waiting and detours (doubled once when that is not enough and time remains).
    connect_k : int
        How many nearest roadmap vertices the current pose (and the goal) connect to.
    stretch : float
        The search runs on the roadmap's spanner of this stretch (see ``PlanOptions``).
    evasion_headings : int
        Directions tried by the evasive motion (a differential drive's: headings on a grid
        fixed in the world, :func:`gfuzzy.navigation.drivenav.drive_evasion`).
    evasion_time : float
        Length (s) of the evasive motion returned, and of the look-ahead that scores it.
    cover : float
        A fallback trajectory lasts at least this long (s).
    goal_tolerance : float
        The goal is reached when the pose is this close to it (contract metric).
    backend : {"compiled", "reference"}
        The search's implementation, as :attr:`gfuzzy.PlanOptions.backend`: the same
        answers, the compiled one faster (so more replans finish inside the budget).
    commitment : float
        A differential drive only: seconds its last plan may arrive later than a fresh one
        and still be kept (while it keeps the fresh search's inflated gaps to everyone):
        a plan that changes its mind every period pays every turn it undoes. 0 turns it off.
    fan : bool
        A differential drive only: also search the two-leg motions out of the robot's pose
        (turn, straight, turn towards the goal, straight; :func:`gfuzzy.timespace.drive.fan`),
        which detour with few turns where the roadmap's lanes zigzag.
    full_speed : bool
        A disc robot only: run a fresh plan at ``vmax`` up to its first wait when that keeps
        the gaps its search kept (:func:`gfuzzy.navigation.brisk.brisk`; the search's whole
        steps run it 2-8 % slower). Off by default: on the crowd benchmarks it arrives
        0.1-0.4 s sooner but collides more often where the predictions are poor (the noisy
        half view: 10 collisions in 200 episodes against 7; 20 people crossing: 3 in 100
        against 2; docs/navigator-experiments.md, *The same, second pass*).
    drive_lookahead : float
        A differential drive only: seconds over which its evasive motions are scored (and
        driven, :func:`gfuzzy.navigation.drivenav.drive_evasion`); its escapes start with a
        turn in place, so contacts that a shorter look-ahead cannot see decide them.
    swerve_growth : float
        Further growth (m per s of prediction) of the predicted disc of a person whose
        straight walk meets someone else's within 3 s (:mod:`gfuzzy.navigation.swerve`):
        they are about to swerve, and may swerve towards the robot. 0 turns it off.
    fov : float
        A disc robot's field of view (degrees), centred on its direction of motion; below
        360 it looks, now and then, where it has not looked (:mod:`gfuzzy.navigation.lookout`).
    look_after : float
        Seconds a side may go unseen before the robot (``fov`` < 360) looks there.
    soft_search : bool
        One search that prices the personal space and the path space instead of the tiers
        that forbid them (:mod:`gfuzzy.navigation.softcost`). Off by default.
    intrusion_cost : float
        With ``soft_search``: seconds of arrival one second of the robot inside someone's
        personal space or way is worth (in their way only, when ``discomfort_cost`` is set).
    discomfort_cost : float or None
        With ``soft_search``: when set, seconds of arrival one second inside someone's
        personal space is worth, priced apart from their way (a step in both pays both).
    effort_levels : int
        How far the searches' effort may be cut after calls whose searches ran out of
        ``time_budget`` (:mod:`gfuzzy.navigation.effort`: 1, the path space dropped; each
        further level, ``plan_slack`` halved; restored once calls finish with room to
        spare). 0: full effort always; at most 8 (``plan_slack`` / 128).
    """

    dt: float = 0.1
    prediction_horizon: float = 5.0
    uncertainty_growth: float = 0.1
    reference_speed: float = 1.0
    safety_buffer: float = 0.05
    personal_space: float = 0.2
    personal_space_cost: float = 0.5
    path_space: float = 1.25
    path_space_cost: float = 5.0
    social_horizon: float = 4.0
    slice: float = 0.5
    stationary_hold: float = 30.0
    time_budget: float = 0.1
    budget_clock: str = "wall"
    plan_slack: float = 8.0
    connect_k: int = 8
    stretch: float = 1.05
    evasion_headings: int = 16
    evasion_time: float = 2.0
    cover: float = 1.0
    goal_tolerance: float = 1e-6
    backend: str = "compiled"
    commitment: float = 0.5
    fan: bool = True
    full_speed: bool = False
    drive_lookahead: float = 4.0
    swerve_growth: float = 0.0
    fov: float = 360.0
    look_after: float = 1.0
    soft_search: bool = False
    intrusion_cost: float = 2.0
    discomfort_cost: float | None = None
    effort_levels: int = 2

    def __post_init__(self):
        if self.budget_clock not in BUDGET_CLOCKS:
            raise InputError(f"budget_clock must be one of {', '.join(BUDGET_CLOCKS)}, got {self.budget_clock!r}")
        if self.backend not in BACKENDS:
            raise InputError(f"backend must be one of {', '.join(BACKENDS)}, got {self.backend!r}")
        for name in ("dt", "prediction_horizon", "reference_speed", "slice", "time_budget", "plan_slack", "evasion_time", "cover",
                     "drive_lookahead"):
            check_number(name, getattr(self, name))
        for name in ("uncertainty_growth", "safety_buffer", "personal_space", "personal_space_cost", "path_space",
                     "path_space_cost", "social_horizon", "stationary_hold", "goal_tolerance", "commitment",
                     "swerve_growth", "intrusion_cost"):
            check_number(name, getattr(self, name), strict=False)
        if self.discomfort_cost is not None:
            check_number("discomfort_cost", self.discomfort_cost, strict=False)
        if not isinstance(self.effort_levels, int) or isinstance(self.effort_levels, bool) or not 0 <= self.effort_levels <= 8:
            raise InputError(f"effort_levels must be a whole number from 0 to 8, got {self.effort_levels!r}")
        if self.connect_k < 1 or self.evasion_headings < 4:
            raise InputError("connect_k must be >= 1 and evasion_headings >= 4")
        check_number("stretch", self.stretch, 1.0, strict=False)
        check_number("look_after", self.look_after)
        if self.dt > self.prediction_horizon:  # no whole step to search: --dt 100 ran to its time limit
            raise InputError(f"dt (--dt) must be at most the prediction horizon ({self.prediction_horizon:g} s), got {self.dt:g}")
        if not 0 < self.fov <= 360:
            raise InputError(f"fov must be in (0, 360] degrees, got {self.fov}")
