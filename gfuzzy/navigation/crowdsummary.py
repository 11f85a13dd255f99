"""The table of ``gfuzzy crowd``: one row per policy over a run's episodes
(:func:`summarize`, :class:`PolicySummary`), aggregated as CrowdNav and CrowdNav++ do."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .crowd import Episode, Outcome

__all__ = ["PolicySummary", "summarize"]


@dataclass(frozen=True)
class PolicySummary:
    """One row of ``gfuzzy crowd``'s table: a policy over a run's episodes."""

    policy: str
    episodes: int
    success: float
    collision: float
    timeout: float
    time: float
    discomfort: float
    intrusion: float
    min_separation: float
    replan_p50: float
    replan_p95: float
    replan_max: float
    modes: tuple = ()


def summarize(runs: list[list[Episode]], policy: str) -> PolicySummary:
    """The table's row of ``policy``: rates over episodes, mean time to goal over the
    successes, the discomfort frequency as a share of all the episodes' steps (CrowdNav's
    aggregation), the intrusion ratio as the mean of the episodes' ratios
    (:attr:`Episode.intrusion_ratio`, CrowdNav++'s ``rl/evaluation.py``), the mean of the
    episodes' smallest separations, and the quantiles of every decision's wall-clock
    time."""
    eps = [e for run in runs for e in run if e.policy == policy]
    n = len(eps)
    if n == 0:
        return PolicySummary(policy, 0, *([math.nan] * 10))
    steps = sum(e.social.steps for e in eps)
    lat = np.concatenate([e.replan_seconds for e in eps]) if eps else np.zeros(0)
    times = [e.time for e in eps if e.reached]
    seps = [e.min_separation for e in eps if math.isfinite(e.min_separation)]
    modes: dict = {}
    for e in eps:
        for m, v in e.modes:
            modes[m] = modes.get(m, 0) + v
    q = (lambda p: float(np.quantile(lat, p))) if lat.size else (lambda p: math.nan)
    return PolicySummary(
        policy, n, sum(e.reached for e in eps) / n, sum(e.collision for e in eps) / n,
        sum(e.outcome == Outcome.TIMEOUT for e in eps) / n, float(np.mean(times)) if times else math.nan,
        sum(e.social.discomfort_steps for e in eps) / steps if steps else 0.0,
        float(np.mean([e.intrusion_ratio for e in eps])),
        float(np.mean(seps)) if seps else math.nan, q(0.5), q(0.95), float(lat.max()) if lat.size else math.nan,
        tuple(sorted(modes.items())),
    )  # fmt: skip
