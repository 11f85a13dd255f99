"""Roadmap build benchmark: time and collision checks for 200 / 1000 / 5000 vertices.

    python tools/bench_roadmap.py [SCENE] [--sizes 200 1000 5000] [--seed 1]

Prints, per size: wall time (best of --repeat builds), PRM validity calls, certification
calls, edges, components, and the ratio of the time to a baseline measured in the same
run: OMPL's uniform sampler growing the same number of vertices without certification
(what a plain OMPL PRM costs on this machine). Target (issue 2): 1000 vertices on
building-floor in <= 1.5 s on the project's 2-core machine.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from gfuzzy.collision.geometry import StaticGeometry
from gfuzzy.roadmap.roadmap import RoadmapOptions, _Builder, _seed_ompl, build_roadmap
from gfuzzy.scene.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def plain_prm_seconds(scene, n: int, seed: int) -> float:
    """Baseline: OMPL PRM with the uniform sampler, no certification."""
    geometry = StaticGeometry(scene)
    opts = RoadmapOptions(vertices=n, seed=seed, sampler="uniform")
    _seed_ompl(seed)
    t = time.perf_counter()
    b = _Builder(scene, opts, geometry)
    b.grow(n, None)
    b.export()
    b.close()
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "scenes" / "building-floor.yaml"))
    ap.add_argument("--sizes", nargs="+", type=int, default=[200, 1000, 5000])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    scene = load_scene(args.scene)
    print(f"scene {scene.name}: {scene.robot.shape} robot, {len(scene.obstacles)} obstacles")
    print(f"{'vertices':>8} {'seconds':>8} {'grow s':>7} {'validity':>9} {'certify':>8} {'edges':>7} {'dropped':>7} {'comp':>4} {'plain PRM s':>11} {'ratio':>6}")
    for n in args.sizes:
        best = None
        for _ in range(args.repeat if n <= 1000 else 1):
            t = time.perf_counter()
            rm = build_roadmap(scene, RoadmapOptions(vertices=n, seed=args.seed))
            el = time.perf_counter() - t
            if best is None or el < best[0]:
                best = (el, rm)
        el, rm = best
        base = plain_prm_seconds(scene, n, args.seed)
        i = rm.info
        print(
            f"{n:>8} {el:>8.3f} {i.grow_seconds:>7.3f} {i.validity_calls:>9} {i.certify_calls:>8} "
            f"{len(rm.edges):>7} {i.edges_dropped:>7} {i.components:>4} {base:>11.3f} {el / base:>6.2f}"
        )


if __name__ == "__main__":
    main()
