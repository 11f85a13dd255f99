"""Differential drive vs holonomic on the same scene, roadmap and query.

    python tools/bench_unicycle.py                                  # building floor, 5 repeats
    python tools/bench_unicycle.py scenes/building-floor-unicycle.yaml --repeat 9

For each query of the unicycle scene (``kinematics: unicycle``) it answers the query twice
on the scene's bundled roadmap: as the scene says (a differential drive) and with the robot
made holonomic (the same shape, vmax, movers, poses). It prints the durations, both delay
factors, and the query times (the median of ``--repeat`` warm queries, after one cold one
that builds the unicycle's lanes and rings and compiles the kernels), and the ratios the
issue's targets are about:

* delay factor: the unicycle's ``delay_factor`` is measured against its own static
  roadmap distance (lanes plus turns at full rate); ``duration ratio`` compares the two
  durations directly (= the ratio of delay factors on one common roadmap distance);
* query time: warm unicycle query / warm holonomic query.

Every answer is checked (``check_trajectory``: the speed bound, collisions and, for the
unicycle, the row rule). Quote the load (``uptime``) with the figures.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.planner.planner import Planner, PlanOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def holonomic(scene):
    """The same scene with a holonomic robot (a disc's poses lose their heading)."""
    robot = replace(scene.robot, kinematics="holonomic", wmax=None, reverse=False)
    if robot.shape == "disc":
        queries = tuple(replace(q, start=q.start[:2], goal=q.goal[:2]) for q in scene.queries)
    else:
        queries = scene.queries
    return replace(scene, robot=robot, queries=queries)


def run(scene, roadmap, repeat: int):
    planner = Planner(scene, roadmap)
    out = []
    for q in scene.queries:
        t = time.perf_counter()
        cold_res = planner.plan(q.start, q.goal, q.t0, PlanOptions(), hold=q.hold)
        cold = time.perf_counter() - t
        warm = []
        for _ in range(repeat):
            t = time.perf_counter()
            res = planner.plan(q.start, q.goal, q.t0, PlanOptions(), hold=q.hold)
            warm.append(time.perf_counter() - t)
        assert res.duration == cold_res.duration
        rep = check_trajectory(scene, res.trajectory.waypoints, q) if res.solved else None
        out.append((q, res, cold, statistics.median(warm), rep))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*", default=[str(ROOT / "scenes" / "building-floor-unicycle.yaml")])
    ap.add_argument("--repeat", type=int, default=5, help="warm queries per answer (the median is shown)")
    args = ap.parse_args(argv)
    for path in args.scenes:
        uni = load_scene(path)
        if not uni.robot.unicycle:
            print(f"{path}: not a unicycle scene", file=sys.stderr)
            return 2
        rm = load_roadmap(ROOT / "roadmaps" / f"{uni.name}.json", uni)
        hol = holonomic(uni)
        a, b = run(hol, rm, args.repeat), run(uni, rm, args.repeat)
        print(f"{uni.name}: {len(rm.vertices)} roadmap vertices; robot {uni.robot.shape}, "
              f"turning <= {uni.robot.turn_rate:.3g} rad/s, reverse {uni.robot.reverse}")  # fmt: skip
        print(f"{'query':<12} {'model':<10} {'duration':>9} {'rd':>7} {'delay':>7} {'cold ms':>8} {'warm ms':>8}  check")
        for (q, rh, ch, wh, kh), (_, ru, cu, wu, ku) in zip(a, b, strict=True):
            for model, r, c, w, k in (("holonomic", rh, ch, wh, kh), ("unicycle", ru, cu, wu, ku)):
                dur = f"{r.duration:9.2f}" if r.solved else f"{r.status.value:>9}"
                delay = f"{r.delay_factor:7.3f}" if r.solved else f"{'-':>7}"
                verdict = "-" if k is None else ("valid" if k.valid else f"INVALID: {k.reason}")
                print(f"{q.name:<12} {model:<10} {dur} {r.roadmap_distance:7.2f} {delay} {c * 1e3:8.0f} {w * 1e3:8.1f}  {verdict}")
            if rh.solved and ru.solved:
                print(f"{'':<12} ratios: duration {ru.duration / rh.duration:.3f}, delay factor "
                      f"{ru.delay_factor / rh.delay_factor:.3f}, warm query time {wu / wh:.2f}")  # fmt: skip
                turn = np.abs((np.diff(ru.trajectory.waypoints[:, 3]) + np.pi) % (2 * np.pi) - np.pi).sum()
                print(f"{'':<12} the unicycle turns {turn:.2f} rad in place")
    return 0


if __name__ == "__main__":
    sys.exit(main())
