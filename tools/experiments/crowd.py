"""The crowd benchmark's table (``tools/bench_crowd.py``), its episodes on the runner's Dask
cluster.

A shorter run of the settings of issue 19 (``gfuzzy crowd``'s engine): CrowdNav's circle
crossing with 5 and 20 humans who ignore or see the robot, and CrowdNav++'s arena, plus
the two bundled pedestrian replays through ``gfuzzy navigate`` with estimated velocities.
``python tools/bench_crowd.py --episodes 300 --workers 2`` is the longer run of
``docs/navigator.md``.
"""

from __future__ import annotations

import contextlib
import io

from .common import ROOT

EPISODES = 30
SETTINGS = ("circle-5-invisible", "circle-5-visible", "circle-20-visible", "circle-20-invisible", "arena")


def run(ctx) -> str:
    import sys

    sys.path.insert(0, str(ROOT / "tools"))
    import bench_crowd

    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        for name in SETTINGS:
            bench_crowd.run_setting(name, EPISODES, ctx.seed, ctx.client)
        bench_crowd.replays(ctx.seed)
    head = (
        "## The crowd benchmark (navigation without knowing the movers' future)\n\n"
        f"The settings of issue 19 through `gfuzzy crowd`'s engine, {EPISODES} episodes each (one Dask "
        "task per episode): CrowdNav's circle crossing (Chen et al. 2019) with ORCA humans who ignore "
        "the robot or see it (the robot is an ORCA agent to them), and CrowdNav++'s arena (Liu et al. "
        "2023: 20 humans, random and changing goals, 5 m sensing, 50 s). Columns: success, collision "
        "and timeout rates, mean time to goal, discomfort frequency (gap < 0.2 m), intrusion ratio, "
        "mean smallest separation (m), replan p50 / p95 (ms, in the workers), the navigator's modes. "
        "Then the bundled pedestrian replays through `gfuzzy navigate` (estimated velocities), each "
        "checked.\n\n"
    )
    return head + "```\n" + out.getvalue().strip() + "\n```\n"
