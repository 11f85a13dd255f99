"""Keeping the last plan through the predictions' wobble (a disc robot's).

Every period the navigator predicts each person walking on at the velocity observed now,
and a fresh search picks the soonest plan under that prediction. People's velocities
change a little from period to period (they swerve round each other, speed up, slow
down), the predictions a few seconds ahead move by a few tenths of a metre, and the fresh
plan often goes another way that arrives no sooner than the last plan did: the robot
zig-zags (docs/navigator-experiments.md, *The crossing's time, fourth pass*).

:func:`steady_plan` keeps the last plan over a fresh one that arrives no sooner, as long
as it keeps the gaps it was made with (and off the ways people are about to walk, with the
path space) from everyone walking on both at their velocity now and at their velocity
averaged over the navigator's last few calls (:class:`RecentWalks`: a prediction that
changes less from one period to the next).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment  # at import: not inside a step's budget

from ..trajectory import Trajectory
from ..typed import FloatArray
from .drivenav import _if_safe

__all__ = ["RecentWalks", "steady_plan", "RECENT_GATE"]

#: Largest distance (m) between where a person of the last call, walked on to now, is
#: and a person observed now for the two to be taken as the same person.
RECENT_GATE = 0.5


class RecentWalks:
    """Each observed person's velocity averaged over the last ``calls`` observations.

    Observations carry no identity: each row of a call is taken to be the person of the
    last call whose position, walked on at their velocity to now, is nearest (an optimal
    assignment within :data:`RECENT_GATE`); a row with no such person starts afresh.
    Velocities not known yet (a person seen once, reported standing) are not averaged in.
    """

    def __init__(self, calls: int):
        self.calls = max(int(calls), 1)
        self._t: float | None = None
        self._xy = np.zeros((0, 2))
        self._vel = np.zeros((0, 2))
        self._hist = np.zeros((0, self.calls, 2))

    def update(self, t: float, obs: FloatArray, unknown=None) -> FloatArray:
        """Take the observations ``obs`` (k, >=4) made at ``t`` (``unknown``: (k,) bool or
        None, whose velocity is not known); return (k, 2) each person's mean velocity over
        the last ``calls`` observations (their velocity now when none is known)."""
        obs = np.asarray(obs, dtype=float)
        k = len(obs)
        known = np.ones(k, dtype=bool) if unknown is None else ~np.asarray(unknown, dtype=bool).reshape(-1)
        hist = np.full((k, self.calls, 2), np.nan)
        if k and len(self._xy) and self._t is not None:
            then = self._xy + self._vel * (t - self._t)
            cost = np.hypot(*(obs[:, None, :2] - then[None, :, :]).transpose(2, 0, 1))
            rows, cols = linear_sum_assignment(np.where(cost <= RECENT_GATE, cost, 1e6))
            ok = cost[rows, cols] <= RECENT_GATE
            hist[rows[ok], :-1] = self._hist[cols[ok], 1:]
        hist[known, -1] = obs[known, 2:4]
        self._t, self._xy, self._vel, self._hist = t, obs[:, :2].copy(), obs[:, 2:4].copy(), hist
        seen = ~np.isnan(hist[:, :, 0])
        count = seen.sum(axis=1)
        total = np.where(seen[..., None], hist, 0.0).sum(axis=1)
        return np.where(count[:, None] > 0, total / np.maximum(count, 1)[:, None], obs[:, 2:4])


def steady_plan(nav, t: float, pose: FloatArray, obs: FloatArray, walks: FloatArray, infl: FloatArray,
                fresh: Trajectory) -> Trajectory | None:  # fmt: skip
    """The navigator's last plan from ``t`` on, when it arrives no later than ``fresh`` and
    keeps the inflated gap ``infl`` (k, S) it was made with (and, with the path space, off
    the ways people are about to walk) from everyone of ``obs`` (k, 5) walking on both at
    their velocity now and at their recent velocity ``walks`` (k, 2); None otherwise (or
    when the robot is not on it)."""
    prev = nav._previous
    if prev is None or prev.t_end <= t + 1e-9 or prev.t_end > fresh.t_end + 1e-9:
        return None
    steady = obs.copy()
    steady[:, 2:4] = walks
    kept = None
    for people in (obs, steady):
        kept = _if_safe(nav, prev, t, pose, people, infl)
        if kept is None:
            return None
        if nav.options.path_space > 0:
            rows, g_infl = nav._path_ghosts(pose, people)
            end = min(kept.t_end, t + nav.options.prediction_horizon)
            if len(rows) and not nav._keeps_gaps(kept, t, end, rows, g_infl):
                return None
    return kept
