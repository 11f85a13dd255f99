"""The crowd benchmark's table (``tools/bench_crowd.py``), its episodes on the runner's Dask
cluster.

CrowdNav's circle crossing (ORCA humans who ignore the robot) with the navigator, the
oracle and CrowdNav's ORCA robot on the same episodes, for 5 and 10 humans, plus the two
bundled pedestrian replays. ``python tools/bench_crowd.py --episodes 100 --workers 2``
is the longer run of ``docs/navigator.md``.
"""

from __future__ import annotations

import contextlib
import io

from .common import ROOT

EPISODES = 30
HUMANS = (5, 10)


def run(ctx) -> str:
    import sys

    sys.path.insert(0, str(ROOT / "tools"))
    import bench_crowd

    from gfuzzy.crowd import episodes
    from gfuzzy.navigator import NavOptions

    options = NavOptions()
    policies = ["navigator", "oracle", "orca"]
    rm = bench_crowd.empty_roadmap(400, ctx.seed)
    rows = []
    for K in HUMANS:
        seeds = [ctx.seed + 1000 * K + i for i in range(EPISODES)]
        results = episodes(ctx.client, rm, K, seeds, options, policies)
        rows.extend(bench_crowd.summarize(K, results, policies))
    replay = io.StringIO()
    with contextlib.redirect_stdout(replay):
        scenes = [str(ROOT / "scenes" / f"{n}.yaml") for n in ("eth-crossing", "zara-crowd")]
        bench_crowd.replays(scenes, options, 400, ctx.seed)
    head = (
        "## The crowd benchmark (navigation without knowing the movers' future)\n\n"
        f"CrowdNav's circle-crossing protocol (Chen et al., ICRA 2019; `gfuzzy/crowd.py`): K ORCA "
        f"humans cross a circle of radius 4 and ignore the robot; the robot (disc 0.3, vmax 1) "
        f"goes from (0, -4) to (0, 4) within 25 s, replanning every 0.25 s; a collision is decided "
        f"exactly between samples. {EPISODES} episodes per K (seeds {ctx.seed + 1000 * HUMANS[0]}.. "
        f"and {ctx.seed + 1000 * HUMANS[1]}..), one Dask task each, a 400-vertex roadmap. Policies "
        f"on the same episodes: the navigator (`gfuzzy.Navigator`, default `NavOptions`), the "
        f"oracle (`gfuzzy.plan` told the humans' true future: a lower bound on time) and "
        f"CrowdNav's ORCA robot (it assumes the humans yield; they do not). Columns: success, "
        f"collision and timeout rates, mean time to goal, mean of time / oracle per episode, mean "
        f"and smallest minimum separation (m), replan latency p50 / p95 / max (ms; measured in "
        f"the workers, two of them on the two cores), the navigator's modes (plans, fallbacks).\n\n"
        f"For scale, CrowdNav reports ORCA at 0.43 success / 0.57 collision and its learned "
        f"policies (SARL, LM-SARL) at 0.99-1.00 success in about 10.5 s. Targets: 5 humans success "
        f">= 0.99, collision <= 0.01; 10 humans success >= 0.95, collision <= 0.03; time <= 1.15 x "
        f"the oracle; replan p95 <= 100 ms.\n\n"
    )
    header = (
        f"{'K':>2} {'policy':<10} {'n':>4} {'succ':>6} {'coll':>6} {'tout':>6} {'time':>7} "
        f"{'t/orac':>7} {'sep':>6} {'minsep':>7}  {'p50ms':>6} {'p95ms':>6} {'maxms':>6}"
    )
    table = "```\n" + header + "\n" + "\n".join(rows) + "\n```\n"
    replays = (
        "\nThe bundled pedestrian replays (real ETH and UCY tracks) through the same loop, each "
        "answer checked against the real tracks with `gfuzzy.check_trajectory`; `oracle` is "
        "`gfuzzy.plan` told the tracks:\n\n```\n" + replay.getvalue().strip() + "\n```\n"
    )
    return head + table + replays
