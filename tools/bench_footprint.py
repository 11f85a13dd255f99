"""What a footprint robot costs against the box of the same size, in one run.

    python tools/bench_footprint.py [--vertices 200] [--repeat 3]

On scenes/footprint-office.yaml, with its robot replaced in turn by: the box bounding the
U (0.8 x 0.9), the same box written as a 4-point footprint, the U itself (3 convex pieces)
and an L (2 pieces). Prints, per robot: roadmap build seconds (best of --repeat), FCL calls,
edges and components, then each query's planning milliseconds (best of --repeat, compiled
search, no stages) and status. The ratios to the box are what to read: a footprint's
clearance asks FCL once per convex piece.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from gfuzzy.planner.planner import Planner
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene

ROOT = Path(__file__).resolve().parent.parent

ROBOTS = {
    "box 0.8 x 0.9": {"box": [0.8, 0.9]},
    "box as footprint": {"footprint": [[0.4, -0.45], [0.4, 0.45], [-0.4, 0.45], [-0.4, -0.45]]},
    "U (3 pieces)": None,  # the scene's own
    "L (2 pieces)": {"footprint": [[0.4, -0.45], [0.4, 0.45], [0.0, 0.45], [0.0, -0.05], [-0.4, -0.05], [-0.4, -0.45]]},
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    base = load_scene(ROOT / "scenes" / "footprint-office.yaml")
    print(f"{'robot':<18} {'build s':>8} {'ratio':>6} {'FCL calls':>10} {'edges':>6} {'comp':>4}   queries (ms, status)")
    ref = None
    for name, robot in ROBOTS.items():
        raw = dict(base.raw)
        if robot is not None:
            keep = {k: v for k, v in raw["robot"].items() if k not in ("disc", "box", "footprint")}
            raw["robot"] = {**keep, **robot}
        scene = parse_scene(raw) if robot is not None else base
        best, rm = None, None
        for _ in range(args.repeat):
            t = time.perf_counter()
            rm = build_roadmap(scene, RoadmapOptions(vertices=args.vertices, seed=1))
            dt = time.perf_counter() - t
            best = dt if best is None else min(best, dt)
        ref = best if ref is None else ref
        info = rm.info.to_dict()
        planner = Planner(scene, rm)
        cells = []
        for q in scene.queries:
            ms = None
            for _ in range(args.repeat):
                t = time.perf_counter()
                res = planner.plan(q.start, q.goal, q.t0)
                d = 1000 * (time.perf_counter() - t)
                ms = d if ms is None else min(ms, d)
            cells.append(f"{q.name} {ms:.0f} {res.status.value}")
        calls = info["validity_calls"] + info["certify_calls"]
        print(f"{name:<18} {best:8.2f} {best / ref:6.2f} {calls!s:>10} {len(rm.edges):6d} {info.get('components', '?')!s:>4}   " + ", ".join(cells))


if __name__ == "__main__":
    main()
