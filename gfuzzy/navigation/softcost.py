"""One search that prices the time spent in people's ways (``NavOptions.soft_search``, issue 19).

The navigator's default keeps off people's ways (the ghosts of :mod:`.pathspace`) and
their personal space by *tiers* of searches that forbid them, each dropped when the plan
that keeps it arrives too late. :meth:`SoftCost._soft_plan` runs one search instead
(:func:`gfuzzy.timespace.soft_kernel.soft_search`): the people's discs with the safety
buffer and the uncertainty stay forbidden (the ``close`` tier's field), and every step the
robot's body spends where the first tier's field (the personal space and the ghosts) is
unsafe costs ``intrusion_cost`` seconds of arrival per second: the robot yields where
yielding is cheap and goes through where a detour or a wait would cost more.

Two rules keep a fixed price from dithering (navigator-experiments.md, "The priced search's
way out of dithering"): the last plan is kept while its priced cost, under the new
predictions, is as good as the fresh plan's (:meth:`SoftCost._priced_kept`); and when the
planned arrival keeps slipping later, the price is halved until it stops
(:meth:`SoftCost._price_slip`), as the tiers drop to *close* when keeping away costs too much.
"""

from __future__ import annotations

import math

import numpy as np

from ..errors import InputError, LimitError
from ..status import Status
from ..timespace.soft_kernel import soft_search
from ..timespace.spacetime import IntervalStore
from ..trajectory import Trajectory
from ..typed import FloatArray
from .drivenav import kept_plan
from .navtypes import GOAL_TAKEN, MOTION_SAMPLE, NavMode, _Searched
from .timedfield import _OutOfTime

__all__ = ["SoftCost", "SOFT_SHARE", "SLIP_WINDOW", "SLIP_LIMIT"]

#: Share of the search's time left that the priced search may use; when it runs out, the
#: safe-interval search among the same forbidden field answers (*close*) in the rest (the
#: priced search has a state per (point, step) and among 20 people runs out of time now and
#: then). In the arena at 5 s per s, 60 % left it out of time on one call in 25 and two
#: episodes of 60 collided after runs of close answers; 85 %: none (navigator-experiments.md).
SOFT_SHARE = 0.85
#: Seconds over which the answered plans' arrival is watched (:meth:`SoftCost._price_slip`).
SLIP_WINDOW = 3.0
#: Seconds the planned arrival may move later over ``SLIP_WINDOW`` (the robot losing more
#: than half the time it spends) before the price is halved; over a window where it does
#: not, a lowered price is doubled back, up to the set one.
SLIP_LIMIT = 1.5


class SoftCost:
    """The navigator's single priced search (a base of :class:`gfuzzy.navigation.navigator.Navigator`)."""

    _price_scale = 1.0  # the share of the set prices in force (halved while the arrival slips)
    _arrivals: tuple = ()  # (time, planned arrival) of the priced answers since the price last changed

    def _priced(self, t: float, pose: FloatArray, obs: FloatArray, deadline: float):
        """(plan, mode, search, inflation kept) of the priced search, within ``SOFT_SHARE`` of
        the time left; when it runs out, the safe-interval search among its forbidden field."""
        self._price_slip(t)
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
            return [(np.vstack([people, g_obs]), np.vstack([infl, g_infl]))], [self._price_scale * opts.intrusion_cost]
        return [(obs, infl), (g_obs, g_infl)], [self._price_scale * c for c in (opts.discomfort_cost, opts.intrusion_cost)]

    def _soft_plan(self, t: float, pose: FloatArray, obs: FloatArray, bare: FloatArray,
                   deadline: float) -> _Searched:  # fmt: skip
        """The plan of least ``arrival + intrusion_cost * seconds inside the personal space
        or a ghost`` (:meth:`_priced_zones`), the people's discs with the buffer and the
        uncertainty (inflated by ``bare``, without the personal space) forbidden."""
        opts = self.options
        start = self._search_start(pose, t, deadline)
        if isinstance(start, _Searched):
            return start
        graph, s_id, h0 = start
        self._exact_windows(graph)
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
                if not self._affords(self._clock(), detailed, deadline):
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
        return self._answered(res, graph, s_id, t, pose, detailed)

    def _price_slip(self, t: float) -> None:
        """Halve the prices when the planned arrival of the priced answers has moved later by
        more than ``SLIP_LIMIT`` s over the last ``SLIP_WINDOW`` s (a fixed price among a
        stream of people keeps paying in time: the arrival slips and the robot dithers); double
        a lowered price back, up to the set one, after a window where it did not slip."""
        past = [arrive for ta, arrive in self._arrivals if ta <= t - SLIP_WINDOW + 1e-9]
        if not past:
            return
        slipped = self._arrivals[-1][1] - past[-1] > SLIP_LIMIT
        if slipped or self._price_scale < 1.0:
            self._price_scale = self._price_scale / 2.0 if slipped else min(1.0, 2.0 * self._price_scale)
            self._arrivals = ()
        else:  # keep the last answer before the window as its reference
            self._arrivals = self._arrivals[len(past) - 1:]

    def _priced_kept(self, t: float, pose: FloatArray, obs: FloatArray, fresh: Trajectory, mode: NavMode):
        """(plan, mode): the last priced (or close) plan from ``t`` on (*kept*) when the robot
        is on it, it keeps the forbidden field's gaps from everyone seen now and its priced
        cost under the new predictions (:meth:`_priced_cost`) is no more than the fresh plan's;
        else ``fresh``. Without it a fresh search, spliced from a slightly different pose,
        undid the last plan's first move every period (0.4 m from a goal two people stood beside)."""
        if self._previous_mode in (NavMode.PLAN, NavMode.CLOSE):
            bare = self._inflation(pose, obs, personal=False)
            last = kept_plan(self, t, pose, obs, bare, fresh, math.inf)
            if last is not None:
                zones, prices = self._priced_zones(pose, obs)
                if self._priced_cost(last, t, zones, prices) <= self._priced_cost(fresh, t, zones, prices) + 1e-9:
                    fresh, mode = last, NavMode.KEPT
                    self._ahead = self._previous_ahead  # the vertices the kept plan heads for
        self._arrivals = (*self._arrivals, (t, fresh.t_end))
        return fresh, mode

    def _priced_cost(self, traj: Trajectory, t: float, zones: list, prices: list) -> float:
        """Seconds from ``t`` to ``traj``'s arrival plus each price times the seconds the robot
        spends inside its priced field ``zones`` [(rows, inflation)] (sampled every ``MOTION_SAMPLE``
        s, with the people walking on at constant velocity): the priced search's cost, re-evaluated."""
        times = t + np.arange(0.0, traj.t_end - t, MOTION_SAMPLE)
        cost = traj.t_end - t
        for (rows, infl), price in zip(zones, prices, strict=True):
            if len(rows) and price > 0:
                cost += price * MOTION_SAMPLE * float(self._short_along(traj, t, times, rows, infl).any(axis=1).sum())
        return cost
