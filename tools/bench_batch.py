"""Batch benchmark: the same batch on 1 and on 2 local Dask workers.

    python tools/bench_batch.py                  # every bundled query, --refine, x1
    python tools/bench_batch.py --repeat 2 --no-refine

The batch is every query of every bundled scene (each scene's saved roadmap), with the GA
refinement by default so that each query is worth shipping to a worker (without it most
bundled queries plan in 10-30 ms and the batch is over in a second). ``--repeat R`` runs
each scene R times. Each worker count gets a fresh LocalCluster; the figures are the
wall-clock time of ``run_batch`` (cluster start excluded and printed apart), and the ratio
1-worker / 2-workers measured in the same run. The rows of both runs must agree (timings
aside): that is checked and printed too.

Target (issue 13): 2 workers faster than 1 on the same batch. On a 2-core machine shared
with other work the ratio stays below 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.planner.planner import PlanOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import load_roadmap  # noqa: E402
from gfuzzy.runs.batch import BatchOptions, local_cluster, run_batch  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402


def bundled(repeat: int):
    pairs = []
    for path in sorted((ROOT / "scenes").glob("*.yaml")):
        scene = load_scene(path)
        rm = load_roadmap(ROOT / "roadmaps" / f"{scene.name}.json", scene)
        pairs += [(scene, rm)] * repeat
    return pairs


def timed(workers: int, pairs, options):
    t = time.perf_counter()
    with local_cluster(workers) as client:
        started = time.perf_counter() - t
        client.run(lambda: __import__("gfuzzy.planner.planner") and None)  # imports done before timing
        res = run_batch(client, pairs, options)
    return started, res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-refine", action="store_true")
    args = ap.parse_args()
    pairs = bundled(args.repeat)
    options = BatchOptions(plan=PlanOptions(refine=not args.no_refine))
    n = sum(len(s.queries) for s, _ in pairs)
    print(f"{n} queries ({len(pairs)} scenes), refine={not args.no_refine}")
    out = {}
    for k in (1, 2):
        started, res = timed(k, pairs, options)
        busy = sum(r.planning_seconds or 0.0 for r in res.rows)
        out[k] = res
        print(
            f"{k} worker(s): {res.seconds:6.2f} s wall (cluster start {started:.2f} s), "
            f"{busy:.2f} s of planning, {res.errors} error rows"
        )
    ratio = out[1].seconds / out[2].seconds
    print(f"1 worker / 2 workers: {ratio:.2f}x")

    def key(r):
        return (r.scene, r.query, r.status, r.duration, r.delay_factor, r.check)

    same = [key(a) for a in out[1].rows] == [key(b) for b in out[2].rows]
    print(f"rows agree between 1 and 2 workers (timings aside): {same}")


if __name__ == "__main__":
    main()
