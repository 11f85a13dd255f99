"""What one step of the navigator did (:class:`NavStep`) and how it answered (:class:`NavMode`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from ..typed import FloatArray

if TYPE_CHECKING:
    from ..timespace.spacetime import SpaceTimeGraph
    from ..trajectory import Trajectory

__all__ = ["NavMode", "NavStep", "MOTION_SAMPLE", "sample_loss"]

#: Seconds between two samples at which a motion is checked against people walking on at
#: constant velocity (the fallbacks, a kept plan); :func:`sample_loss` bounds the rest.
MOTION_SAMPLE = 0.05

#: Why a search did not run: the goal is unsafe at every step it could be reached.
GOAL_TAKEN = "the goal is taken at every step within the horizon (someone stands on it, with these margins)"


def sample_loss(robot_speed, person_speed):
    """What the gap between the robot and a person can lose between two samples
    :data:`MOTION_SAMPLE` apart: no point of the robot moves faster than ``robot_speed``
    (the speed bound counts turning at the circumscribed radius) nor the person faster
    than ``person_speed``, so the gap changes by at most their sum times half the interval
    (float or array, broadcast)."""
    return (robot_speed + person_speed) * MOTION_SAMPLE / 2


class NavMode(str, Enum):
    """How one :meth:`Navigator.step` answered (a ``str``: ``NavMode.PLAN == "plan"``)."""

    PLAN = "plan"  # a fresh search
    CLOSE = "close"  # a fresh search without the personal space (buffer and uncertainty kept)
    RELAXED = "relaxed"  # a fresh search without the buffer, personal space and uncertainty
    DIRECT = "direct"  # straight to the goal nearby, checked finely
    PREVIOUS = "previous"  # the last plan, still clear
    KEPT = "kept"  # a fresh search answered, but the last plan was as good (a unicycle's) or much sooner: kept
    ROUTE = "route"  # a differential drive's static route: no plan in time, nobody near
    EVASIVE = "evasive"  # the statically free straight motion with the latest contact
    GOAL = "goal"  # already at the goal
    LOOK = "look"  # a short slow motion that turns a disc robot's view to a side it has not seen

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class NavStep:
    """What one :meth:`Navigator.step` did (``Navigator.last``).

    Attributes
    ----------
    mode : NavMode
        ``"plan"`` (a fresh search), ``"close"`` (a fresh search without the personal
        space: it came sooner by more than ``personal_space_cost``, or the first found
        none), ``"relaxed"`` (a fresh search without the safety
        buffer, the personal space and the uncertainty), ``"direct"`` (straight to the goal nearby, checked
        finely), ``"previous"`` (the last plan, still clear), ``"route"`` (a differential
        drive's static route when no plan came in time and nobody is near), ``"evasive"``, ``"goal"``,
        ``"kept"`` (a fresh search answered, and the last plan was kept: a differential
        drive's as safe and at most ``NavOptions.commitment`` seconds later, a disc's as safe
        as when it was made and arriving much sooner), ``"look"``
        (a short slow motion turning a narrow view to a side not seen: ``NavOptions.fov``).
    seconds : float
        Time of the call on the budget's clock (``NavOptions.budget_clock``).
    message : str
        Why the search did not answer, when it did not.
    predicted : (k, 5) float
        The observations used, ``[x, y, vx, vy, inflated radius at t]``.
    detailed : int
        People predicted in detail for the search: those who can come within reach of
        where the robot can be before their prediction ends (the others cannot matter).
    out_of_time : bool
        The search ran out of ``time_budget`` before it answered (the answer is then a
        fallback's: ``"direct"``, ``"previous"``, ``"route"`` or ``"evasive"``).
    """

    mode: NavMode
    seconds: float
    message: str = ""
    predicted: FloatArray = field(default_factory=lambda: np.zeros((0, 5)), compare=False)
    detailed: int = 0
    out_of_time: bool = False


@dataclass(frozen=True)
class _Searched:
    """What one search of :meth:`Navigator.step` found (the trajectory, or why not), and the
    spliced graph, kept for a second search from the same pose."""

    trajectory: Trajectory | None
    message: str = ""
    detailed: int = 0
    out_of_time: bool = False
    graph: SpaceTimeGraph | None = None
    start: int = -1
    ahead: list = field(default_factory=list)
    #: (interval store, people rows, inflation, relevant mask) of the search's last field, for
    #: a later search from the same pose whose field is no more cautious (:func:`~gfuzzy.navigation.prediction.prior_store`)
    safety: tuple | None = field(default=None, compare=False, repr=False)
