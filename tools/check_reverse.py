"""Why Figure 12's `reverse` variants at mover speeds 1.6-2.0 answer `no_path`.

    python tools/check_reverse.py [--speeds 1.6 1.8 2.0] [--sizes 1000 3000]

For each speed: the planner's answer on the bundled roadmap with the default
horizon, then an independent check of that verdict, a breadth-first search over every
(point, step) of the same graph (the whole roadmap, no spanner, no safe intervals, no
heuristic, no time windows; the same safety table), to the same horizon; then the planner on
denser roadmaps (grown from one seed) with the default horizon and with 600 s.

If the breadth-first search reaches the goal where the planner said `no_path`, the planner
is wrong; if neither does, the verdict is the roadmap's (its points and the time grid), and
denser roadmaps say whether more vertices open a way.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml
from scipy.sparse import csr_matrix, identity

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tools"))

from experiments.fig12 import variant  # noqa: E402

from gfuzzy.planner.planner import Planner, PlanOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, grow_roadmaps, load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.timespace.movers import MoverField  # noqa: E402


def brute_force(planner: Planner, q, dt: float, horizon: int) -> int | None:
    """First step at which the goal is reachable (move along an edge piece or wait, every
    (point, step) safe), by frontier sets; None within ``horizon`` steps."""
    start, goal = np.asarray(q.start, float), np.asarray(q.goal, float)
    qg = planner.prepare(goal, PlanOptions(dt=dt, stretch=1.0)).splice(planner, start)  # the whole roadmap
    graph, s_id, g_id = qg.graph, qg.s_id, qg.g_id
    field = MoverField(planner.scene, q.t0, dt, horizon, planner.robot.vmax)
    field.compiled = True
    unsafe = field.unsafe(graph.poses)
    n = len(graph.poses)
    step = csr_matrix((np.ones(len(graph.neighbors)), graph.neighbors, graph.indptr), shape=(n, n))
    step = (step.T + identity(n, format="csr")).tocsr()  # from a node to its neighbours, or stay
    reach = np.zeros(n)
    reach[s_id] = not unsafe[s_id, 0]
    for t in range(1, horizon + 1):
        reach = ((step @ reach) > 0) & ~unsafe[:, t]
        if reach[g_id]:
            return t
        if not reach.any():
            return None
        reach = reach.astype(float)
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--speeds", type=float, nargs="+", default=[1.6, 1.8, 2.0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1000, 3000])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    doc = yaml.safe_load((ROOT / "scenes" / "building-floor.yaml").read_text())
    base = load_scene(ROOT / "scenes" / "building-floor.yaml")
    bundled = load_roadmap(ROOT / "roadmaps" / "building-floor.json", base)
    t = time.perf_counter()
    grown = grow_roadmaps(base, sorted(args.sizes), RoadmapOptions(seed=args.seed))
    print(f"grew roadmaps of {sorted(args.sizes)} vertices (seed {args.seed}) in {time.perf_counter() - t:.1f} s")
    with tempfile.TemporaryDirectory() as tmp:
        for speed in args.speeds:
            d = variant(doc, "reverse", speed)
            path = Path(tmp) / f"{d['name']}.yaml"
            path.write_text(yaml.safe_dump(d, sort_keys=False))
            scene = load_scene(path)
            q = scene.queries[0]
            planner = Planner(scene, bundled)
            res = planner.plan(q.start, q.goal, q.t0)
            opts = PlanOptions()
            steps = planner._max_steps(opts, res.roadmap_distance, q.t0, 0)
            found = brute_force(planner, q, opts.dt, steps)
            bf = "no path" if found is None else f"reaches the goal at {found * opts.dt:.2f} s"
            print(f"\nspeed {speed:g}: planner on the bundled {len(bundled.vertices)}-vertex roadmap: "
                  f"{res.status.value}; breadth-first search over every (point, step) to "
                  f"{steps * opts.dt:.1f} s: {bf}")  # fmt: skip
            for rm in grown:
                for horizon in (None, 600.0):
                    r = Planner(scene, rm).plan(q.start, q.goal, q.t0, PlanOptions(horizon=horizon))
                    ans = f"solved, {r.duration:.2f} s" if r.solved else r.status.value
                    print(f"  {len(rm.vertices):>5} vertices, horizon {'default' if horizon is None else f'{horizon:g} s':>7}: {ans}")


if __name__ == "__main__":
    main()
