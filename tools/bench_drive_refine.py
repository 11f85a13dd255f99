"""How often the GA's refinement (or the speed layer) of a differential drive's path is kept.

For the bundled ``kinematics: unicycle`` scenes and, as unseen cases, the bundled box and
footprint scenes driven as differential drives (``kinematics: unicycle`` added, nothing
else changed), every query is planned with ``--refine``; one row per query gives what the
refinement did (applied, or its reason), and the totals count how many refined paths were
thrown away because a segment or a turn in place could not be certified statically.

    python tools/bench_drive_refine.py [--bundled NAME ...] [--unseen NAME ...] [-n VERTICES]
        [--seed S] [--stage refine|speed]

``--stage speed`` runs ``--speed-layer`` instead and counts where it applied: to the whole
path (``applied``) or, where no timing of the whole layered path exists among the movers,
with some legs at the search's pace (``partial``, with their count and length).

Run it with another checkout first on PYTHONPATH to measure that code ("before").
"""

from __future__ import annotations

import argparse
import time
from collections import Counter
from pathlib import Path

import yaml

from gfuzzy.planner.planner import PlanOptions, plan
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, load_roadmap
from gfuzzy.scene.scene import load_scene, parse_scene

ROOT = Path(__file__).resolve().parent.parent
BUNDLED = ("building-floor-unicycle", "tb3-arena-unicycle")
UNSEEN = ("building-floor", "depot", "footprint-office", "small-house", "warehouse-mesh")


def _scenes(names_bundled, names_unseen):
    for name in names_bundled:
        scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
        yield "bundled", scene, load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene)
    for name in names_unseen:
        path = ROOT / "scenes" / f"{name}.yaml"
        doc = yaml.safe_load(path.read_text())
        doc["robot"]["kinematics"] = "unicycle"
        doc["name"] = f"{name}-drive"
        scene = parse_scene(doc, file=str(path), folder=path.parent)
        yield "unseen", scene, None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-n", type=int, default=300, help="roadmap vertices of the unseen cases")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--bundled", nargs="*", default=list(BUNDLED))
    ap.add_argument("--unseen", nargs="*", default=list(UNSEEN))
    ap.add_argument("--stage", choices=("refine", "speed"), default="refine")
    args = ap.parse_args()
    speed = args.stage == "speed"
    counts: Counter = Counter()
    print(f"{'scene/query':<44}{'kind':<8}{args.stage:<10}{'s':>6}  reason")
    for kind, scene, roadmap in _scenes(args.bundled, args.unseen):
        if roadmap is None:
            roadmap = build_roadmap(scene, RoadmapOptions(vertices=args.n, seed=args.seed))
        for q in scene.queries:
            t = time.perf_counter()
            opts = PlanOptions(refine=not speed, speed_layer=speed, seed=args.seed, time_limit=120)
            res = plan(scene, roadmap, q.start, q.goal, q.t0, opts)
            if not res.solved:
                print(f"{scene.name + '/' + q.name:<44}{kind:<8}{'unsolved':<10}{time.perf_counter() - t:>6.1f}")
                continue
            rep = res.speed_report if speed else res.refine_report
            reason = rep.reason
            if speed and rep.applied:
                reason = f"{rep.before['duration']:.2f} -> {rep.after['duration']:.2f} s, corners {rep.corners}"
            if speed and rep.applied and rep.hasty:
                h = rep.hasty
                verdict = "partial"
                reason += f", {h['legs']} of {h['of']} legs ({h['length']:.2f} of {h['total']:.2f} m) at the search's pace"
            elif rep.applied:
                verdict = "applied"
            elif "certified" in reason:
                verdict = "rejected"
            elif "found nothing" in reason or "straight segment" in reason:
                verdict = "nothing"
            else:
                verdict = "other"
            counts[verdict] += 1
            ga = time.perf_counter() - t if speed else rep.ga_seconds or 0.0
            print(f"{scene.name + '/' + q.name:<44}{kind:<8}{verdict:<10}{ga:>6.1f}  {reason}")
    total = sum(counts.values())
    print(f"\nsolved queries ({args.stage}): {total}; " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items())))


if __name__ == "__main__":
    main()
