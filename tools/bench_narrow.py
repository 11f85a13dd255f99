"""Narrow passages: success rate and build time over seeds and door widths, with and
without the free-space repair, printed side by side.

    python tools/bench_narrow.py                    # disc doors and box slots, 10 seeds
    python tools/bench_narrow.py --kind disc --seeds 20 --slack 0.01 0.02 0.03
    python tools/bench_narrow.py --kind box --box-slack 0.03 0.02 0.01

The scene: a 6 x 4 m room split by a 0.2 m wall with one door at its middle; the query
goes from (1, 1) to (5, 3) (a box robot starts and ends across the door, heading pi/2,
so it must turn to pass). A disc robot of radius 0.3 with clearance 0.05 meets doors
leaving it ``slack`` metres per side (door = 2 (r + c + slack)); a 1.0 x 0.5 box meets
slots 0.5 + 2 ``box-slack`` wide. Each row builds one roadmap per seed with default
settings (-n 200) and answers the query:

* ``uniform``: OMPL's uniform sampler, no repair, queries not linked through the free
  space (plain PRM);
* ``before``: the passage sampler, no repair, no links: the behaviour before the free
  space (run the same tool on an older checkout for the older sampler's figures);
* ``no-repair``: the passage sampler without the repair, queries linked through the free
  space (what a roadmap file written before the repair gets);
* ``repair``: the default (passage sampler + free-space repair + links for discs);
* ``uniform+repair``: OMPL's uniform sampler with the repair and links (the repair alone).

``--picture OUT.png`` draws instead the repair at work (docs/img/narrow-door.png): a door
with 2 cm per side, uniform PRM (seed 3) leaving two components, the vertices the repair
added, and the answer through the door.

Columns: solved / seeds, the mean and max roadmap build time, the vertices the repair added
(mean), and the roadmap's components (mean). Every solved answer is checked by
``gfuzzy.check.check``; a failed check is printed. Quote ``uptime`` with the figures.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.planner.planner import Planner  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402

#: mode -> (RoadmapOptions overrides, queries linked through the free space)
MODES = {
    "uniform": ({"repair": False, "sampler": "uniform"}, False),
    "before": ({"repair": False}, False),
    "no-repair": ({"repair": False}, True),
    "repair": ({"repair": True}, True),
    "uniform+repair": ({"repair": True, "sampler": "uniform"}, True),
}


def door_scene(width: float, robot: dict):
    y0, y1 = 2 - width / 2, 2 + width / 2
    return parse_scene(
        {
            "version": 1,
            "name": "door",
            "bounds": [0, 0, 6, 4],
            "robot": robot,
            "obstacles": [
                {"box": {"center": [3, y0 / 2], "size": [0.2, y0]}},
                {"box": {"center": [3, (4 + y1) / 2], "size": [0.2, 4 - y1]}},
            ],
        }
    )


def run_case(scene, start, goal, mode: str, seeds: int, n: int) -> dict:
    overrides, link = MODES[mode]
    solved = failed_checks = 0
    times, added, comps = [], [], []
    for seed in range(1, seeds + 1):
        t = time.perf_counter()
        rm = build_roadmap(scene, RoadmapOptions(vertices=n, seed=seed, **overrides))
        times.append(time.perf_counter() - t)
        added.append(rm.info.repair.get("added_vertices", 0))
        comps.append(rm.info.components)
        planner = Planner(scene, rm)
        if not link and hasattr(planner, "_fs"):  # no free space for the query: as before it
            planner._fs.append(None)
        res = planner.plan(start, goal)
        if res.status == "solved":
            if check_trajectory(scene, res.trajectory.waypoints).valid:
                solved += 1
            else:
                failed_checks += 1
    return {
        "solved": solved,
        "bad": failed_checks,
        "mean_s": sum(times) / len(times),
        "max_s": max(times),
        "added": sum(added) / len(added),
        "components": sum(comps) / len(comps),
    }


def picture(out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    from gfuzzy.render import draw
    from gfuzzy.roadmap.freespace import free_space

    scene = door_scene(0.74, {"disc": 0.3, "vmax": 1.0, "clearance": 0.05})
    plain = build_roadmap(scene, RoadmapOptions(seed=3, sampler="uniform", repair=False))
    rm = build_roadmap(scene, RoadmapOptions(seed=3, sampler="uniform"))
    res = Planner(scene, rm).plan([1.0, 1.0], [5.0, 3.0])
    n = rm.options.vertices
    wp = res.trajectory.waypoints
    fig, ax = draw._figure(scene, 8.0, False, 3)
    draw._draw_obstacles(ax, scene)
    draw._draw_roadmap(ax, rm)
    for k, reg in enumerate(free_space(scene).regions):
        for ring in [reg.exterior, *reg.interiors]:
            x, y = ring.xy
            ax.plot(x, y, color="tab:green", lw=1.0, ls="--", label="free space (robot centre)" if k == 0 else None)
    added = rm.vertices[n:]
    ax.plot(added[:, 0], added[:, 1], "o", color="tab:red", ms=5, zorder=6, label="added by the repair")
    draw._draw_queries(ax, scene)
    draw._draw_trajectory(ax, fig, scene, wp, None, 6)
    ax.set_title(
        f"door 0.74 m, disc r 0.3 + clearance 0.05 (2 cm per side): uniform PRM, {n} vertices, "
        f"{plain.info.components} components;\nthe free-space repair adds "
        f"{rm.info.repair['added_vertices']} vertices: 1 component, solved in {wp[-1, 0] - wp[0, 0]:.2f} s",
        fontsize=9,
    )
    ax.legend(loc="upper left", fontsize=7)
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kind", choices=("disc", "box", "both"), default="both")
    ap.add_argument("--seeds", type=int, default=10)
    ap.add_argument("-n", "--vertices", type=int, default=200)
    ap.add_argument("--slack", type=float, nargs="+", default=[0.05, 0.03, 0.02, 0.01, 0.005])
    ap.add_argument("--box-slack", type=float, nargs="+", default=[0.03, 0.02, 0.01])
    ap.add_argument("--modes", nargs="+", choices=list(MODES), default=list(MODES))
    ap.add_argument("--picture", metavar="OUT.png", help="draw the repair at work instead")
    args = ap.parse_args()
    if args.picture:
        picture(args.picture)
        return 0
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"# {args.seeds} seeds, -n {args.vertices}, load average {load:.2f}")
    print(f"{'robot':<22} {'door':>6} {'slack':>6} {'mode':<14} {'solved':>7} {'mean s':>7} {'max s':>7} {'added':>6} {'comps':>6}")
    cases = []
    if args.kind in ("disc", "both"):
        robot = {"disc": 0.3, "vmax": 1.0, "clearance": 0.05}
        for s in args.slack:
            cases.append(("disc 0.3 + c 0.05", 2 * (0.35 + s), s, robot, [1.0, 1.0], [5.0, 3.0]))
    if args.kind in ("box", "both"):
        robot = {"box": [1.0, 0.5], "vmax": 1.0}
        for s in args.box_slack:
            cases.append(("box 1.0 x 0.5", 0.5 + 2 * s, s, robot, [1.0, 1.0, math.pi / 2], [5.0, 3.0, math.pi / 2]))
    for name, width, slack, robot, start, goal in cases:
        scene = door_scene(width, robot)
        for mode in args.modes:
            if "box" in robot and mode in ("no-repair", "repair", "uniform+repair"):
                continue  # the free space is for discs: the same as "before"
            r = run_case(scene, start, goal, mode, args.seeds, args.vertices)
            bad = f"  ({r['bad']} FAILED CHECK)" if r["bad"] else ""
            print(
                f"{name:<22} {width:6.3f} {slack:6.3f} {mode:<14} {r['solved']:>3}/{args.seeds:<3} "
                f"{r['mean_s']:7.2f} {r['max_s']:7.2f} {r['added']:6.1f} {r['components']:6.1f}{bad}",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
