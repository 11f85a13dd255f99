"""Figures behind the advice on `-n`, `--dt` and `--horizon` (docs/planner.md, "Choosing settings").

    python tools/bench_settings.py                  # building-floor and zara-crowd
    python tools/bench_settings.py --repeat 5

For each roadmap size (-n 100, 200, 500, 1000, seed 1) it prints the build time, the
answer's duration, delay factor and the query time (median of --repeat runs of a kept
``Planner``); then, on the 200-vertex roadmap, the same for dt 0.035, 0.07 and 0.14, and
for a few horizons. Figures are seconds on the machine it runs on; compare rows of one
run with each other, not with another machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.planner.planner import Planner, PlanOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402


def query_row(planner, q, options, repeat):
    times, res = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        res = planner.plan(q.start, q.goal, q.t0, options)
        times.append(time.perf_counter() - t)
    ms = 1000 * statistics.median(times)
    if not res.solved:
        return f"{res.status.value:>9} {'':>8} {ms:8.0f}"
    return f"{res.duration:9.2f} {res.delay_factor:8.3f} {ms:8.0f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--scenes", nargs="+", default=["building-floor", "zara-crowd"])
    args = ap.parse_args(argv)
    for name in args.scenes:
        scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
        q = scene.queries[0]
        print(f"\n{name}, query {q.name}")
        print(f"{'setting':>22} {'build s':>8} {'duration':>9} {'delay':>8} {'query ms':>8}")
        roadmaps = {}
        for n in (100, 200, 500, 1000):
            t = time.perf_counter()
            rm = build_roadmap(scene, RoadmapOptions(vertices=n, seed=1))
            build = time.perf_counter() - t
            roadmaps[n] = rm
            row = query_row(Planner(scene, rm), q, PlanOptions(), args.repeat)
            print(f"{'-n ' + str(n):>22} {build:8.2f} {row}")
        planner = Planner(scene, roadmaps[200])
        for dt in (0.035, 0.07, 0.14):
            row = query_row(planner, q, PlanOptions(dt=dt), args.repeat)
            print(f"{'-n 200 --dt ' + str(dt):>22} {'':>8} {row}")
        for horizon in (10.0, 20.0, 40.0, None):
            row = query_row(planner, q, PlanOptions(horizon=horizon), args.repeat)
            label = "-n 200 --horizon " + ("auto" if horizon is None else f"{horizon:g}")
            print(f"{label:>22} {'':>8} {row}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
