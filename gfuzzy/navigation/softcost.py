"""One search that prices the time spent in people's ways (``NavOptions.soft_search``, issue 19).

The navigator's default keeps off people's ways (the ghosts of :mod:`.pathspace`) and
their personal space by *tiers* of searches that forbid them, each dropped when the plan
that keeps it arrives too late. :meth:`SoftCost._soft_plan` runs one search instead
(:func:`gfuzzy.timespace.soft_kernel.soft_search`): the people's discs with the safety
buffer and the uncertainty stay forbidden (the ``close`` tier's field), and every step the
robot's body spends where the first tier's field (the personal space and the ghosts) is
unsafe costs ``intrusion_cost`` seconds of arrival per second: the robot yields where
yielding is cheap and goes through where a detour or a wait would cost more.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, LimitError
from ..status import Status
from ..timespace.soft_kernel import soft_search
from ..timespace.spacetime import IntervalStore
from ..timespace.timespace import timed_rows
from ..trajectory import Trajectory
from ..typed import FloatArray
from .navtypes import GOAL_TAKEN, NavMode, _Searched
from .timedfield import _OutOfTime

__all__ = ["SoftCost", "SOFT_SHARE"]

#: Share of the search's time left that the priced search may use; when it runs out, the
#: safe-interval search among the same forbidden field answers (*close*) in the rest (the
#: priced search has a state per (point, step) and among 20 people runs out of time now and
#: then). In the arena at 5 s per s, 60 % left it out of time on one call in 25 and two
#: episodes of 60 collided after runs of close answers; 85 %: none (navigator-experiments.md).
SOFT_SHARE = 0.85


class SoftCost:
    """The navigator's single priced search (a base of :class:`gfuzzy.navigation.navigator.Navigator`)."""

    def _priced(self, t: float, pose: FloatArray, obs: FloatArray, deadline: float):
        """(plan, mode, search, inflation kept) of the priced search, within ``SOFT_SHARE`` of
        the time left; when it runs out, the safe-interval search among its forbidden field."""
        bare = self._inflation(pose, obs, personal=False)
        now = self._clock()
        found = self._soft_plan(t, pose, obs, bare, now + SOFT_SHARE * max(deadline - now, 0.0))
        if found.trajectory is None and found.out_of_time and self._clock() < deadline:
            close = self._search(t, pose, obs, bare, deadline, found)
            return close.trajectory, NavMode.CLOSE, close, bare
        return found.trajectory, NavMode.PLAN, found, bare

    def _priced_zones(self, pose: FloatArray, obs: FloatArray) -> tuple[list, list]:
        """([(rows, inflation)] of the priced fields, [their prices in steps per step]): the
        people with the personal space and their ghosts as one field priced ``intrusion_cost``;
        with ``discomfort_cost`` set, the people with the personal space priced that and the
        ghosts alone priced ``intrusion_cost``. The ghosts have no escape window (forbidden,
        a robot in someone's way had to be given time to step out; priced, it pays for every
        step it stays)."""
        opts = self.options
        infl = self._inflation(pose, obs)
        # no escape window (pathspace.ghost_window): a robot in someone's way pays from the first step
        g_obs, g_infl = (self._path_ghosts(pose, obs, escape=False) if opts.path_space > 0
                         else (np.zeros((0, 7)), np.zeros((0, infl.shape[1]))))  # fmt: skip
        if opts.discomfort_cost is None:
            people = np.column_stack([obs, np.zeros(len(obs)), np.full(len(obs), math.inf)])
            return [(np.vstack([people, g_obs]), np.vstack([infl, g_infl]))], [opts.intrusion_cost]
        return [(obs, infl), (g_obs, g_infl)], [opts.discomfort_cost, opts.intrusion_cost]

    def _soft_plan(self, t: float, pose: FloatArray, obs: FloatArray, bare: FloatArray,
                   deadline: float) -> _Searched:  # fmt: skip
        """The plan of least ``arrival + intrusion_cost * seconds inside the personal space
        or a ghost`` (:meth:`_priced_zones`), the people's discs with the buffer and the
        uncertainty (inflated by ``bare``, without the personal space) forbidden."""
        opts = self.options
        graph, s_id = self._splice(pose, t, deadline)
        if graph is None:
            return _Searched(None, s_id)
        h0 = float(graph.heuristic[s_id])
        if not math.isfinite(h0):
            return _Searched(None, "the goal is not reachable on the roadmap", graph=graph, start=s_id)
        priced, prices = self._priced_zones(pose, obs)
        stores = tuple(IntervalStore(graph) for _ in range(1 + len(priced)))
        slack = (opts.plan_slack + opts.prediction_horizon) / opts.dt
        detailed = 0
        try:
            for _ in range(2):
                steps = int(math.ceil(h0 + slack))
                hk = self._relevant(pose, obs, bare, steps * opts.dt)
                keep = [self._relevant(pose, o, i, steps * opts.dt) for o, i in priced]
                detailed = int(hk.sum() + sum(k.sum() for k in keep))
                if self._clock() + detailed * self._person_seconds > deadline:
                    return _Searched(None, "time budget spent before the search", detailed, True, graph, s_id)
                hard = self._field(t, obs[hk], bare[hk], steps, deadline)
                stores[0].set_horizon(hard, pool=True)
                if len(stores[0].get(self._g_id)[0]) == 0:  # as the safe-interval search's _goal_taken
                    return _Searched(None, GOAL_TAKEN, detailed, False, graph, s_id)
                soft = [self._field(t, o[k], i[k], steps, deadline) for (o, i), k in zip(priced, keep, strict=True)]
                res = soft_search(graph, hard, soft, s_id, self._g_id, prices, deadline, stores, self._clock)
                if res.status != Status.NO_PATH or not res.horizon_hit or self._clock() > deadline:
                    break
                slack *= 2.0
        except _OutOfTime:
            return _Searched(None, "time budget spent on the predicted people's safety", detailed, True, graph, s_id)
        except (InputError, LimitError) as exc:
            return _Searched(None, f"search refused: {exc}", graph=graph, start=s_id)
        if res.status != Status.SOLVED:
            return _Searched(None, res.message, detailed, res.status == Status.TIMEOUT, graph, s_id)
        rows, _ = timed_rows(res.nodes, res.steps, graph.poses, t, opts.dt)
        self._ahead = [(t + st * opts.dt, nd) for nd, st in zip(res.nodes, res.steps, strict=True) if nd < self._nv]
        rows[0, 1:] = pose
        rows[-1, 1:] = self.goal
        return _Searched(Trajectory(rows, self.robot.circumradius), "", detailed, False, graph, s_id, self._ahead)
