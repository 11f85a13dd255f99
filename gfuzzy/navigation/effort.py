"""The searches' effort, adapted to how much of the time budget the calls need (issues 18, 19).

On a slow or busy computer the navigator's searches may not fit ``time_budget``: among 20
people on a machine three times slower than the one the defaults were tuned on, a call in
two or three ran out of time and the evasive motion answered (an episode of them ends when
someone walks into a robot that never had a plan). Most of a search's cost is the safety
of what it predicts; the first search also keeps off the people's ways (the path space's
ghosts: a disc ahead of every walker, :mod:`.pathspace`), a social cost that is not the
people's safety. So after a call whose searches ran out of time the next calls do less,
and they return to full effort once calls finish with room to spare:

* level 0: the options as given;
* level 1: no path space (``path_space`` 0: the first search without the ghosts, the
  people predicted as before);
* level ``i`` > 1: also ``plan_slack`` (the waiting and detour a search allows) scaled by
  ``SCALE ** (i - 1)``;

up to ``NavOptions.effort_levels`` (0 turns this off). The people's predictions (their
horizon, inflation and hold) are never cut: a search that looks less far ahead was
measured and dropped, it led a holonomic robot into the crossing's centre where no plan
was left (docs/navigator-experiments.md, *When the budget binds: the searches' effort cut*).

Only the searches see the reduced options (:meth:`Effort.searching`); the predictions'
inflation, the checks of a plan kept or run at full speed and the fallbacks keep the full
ones. A call raises the level when its searches ran out of time; ``RECOVER`` calls in a
row whose searches finished within ``ROOM`` of their share lower it by one. A return that
runs out of time within ``RECOVER`` calls doubles the calls needed before the next, up to
``RECOVER * BACKOFF``, so that a setting whose full effort never fits does not pay an
evasion every few calls; ``RECOVER`` calls at the returned level that fit reset it. Where the
budget never binds, nothing runs out of time and every answer is the full effort's.
"""

from __future__ import annotations

import contextlib
import math
from dataclasses import replace

from .navoptions import NavOptions

#: Each level beyond the first scales the searches' ``plan_slack`` by this factor.
SCALE = 0.5
#: A call whose searches took at most this share of their time had room: with one level
#: more effort they would likely still fit.
ROOM = 0.5
#: Calls with room in a row before one level more effort; each failed return doubles it,
#: up to ``BACKOFF`` times.
RECOVER, BACKOFF = 4, 8


def reduced(options: NavOptions, level: int) -> NavOptions:
    """``options`` for the searches at effort ``level`` (0: as given)."""
    if level == 0:
        return options
    return replace(options, path_space=0.0, plan_slack=options.plan_slack * SCALE ** (level - 1))


class Effort:
    """The level of effort of a navigator's searches, from the pressure of its calls.

    Parameters
    ----------
    options : NavOptions
        The navigator's; ``effort_levels`` is the most reduced level (0: always full).
    """

    def __init__(self, options: NavOptions):
        self.level = 0
        self._options = [reduced(options, i) for i in range(options.effort_levels + 1)]
        self._room = 0  # calls with room in a row at this level
        self._need = RECOVER  # calls with room needed before one level more effort
        self._trial = -1  # calls since the level was lowered, while on trial (-1: not on trial)

    @contextlib.contextmanager
    def searching(self, nav):
        """``nav.options`` are this level's while the searches run, the full ones after."""
        full = nav.options
        nav.options = self._options[self.level]
        try:
            yield
        finally:
            nav.options = full

    def record(self, out_of_time: bool, used: float, share: float) -> None:
        """Account for a call: ``out_of_time``, whether its searches ran out of time;
        ``used``, the budget's seconds from the call's start to the searches' end; ``share``,
        the searches' seconds (to their deadline)."""
        if out_of_time:
            if self._trial >= 0:  # back at more effort too soon: wait longer next time
                self._need = min(2 * self._need, RECOVER * BACKOFF)
            self.level = min(self.level + 1, len(self._options) - 1)
            self._room, self._trial = 0, -1
            return
        if self._trial >= 0:
            self._trial += 1
            if self._trial >= RECOVER:  # the returned level fits
                self._need, self._trial = RECOVER, -1
        if self.level == 0 or not math.isfinite(used) or used > ROOM * share:
            self._room = 0
            return
        self._room += 1
        if self._room >= self._need:
            self.level -= 1
            self._room, self._trial = 0, 0
