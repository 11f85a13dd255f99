"""The navigator among walking people on a user's map, through imperfect sensors.

    python tools/bench_populated.py [SCENE] [--people 10] [--seeds 1 2 3 4] [--vertices 400]
                                    [--sensing exact estimated noise fov noise-fov noise-fov-occlusion]
                                    [--max-time 120]

For each seed, ``gfuzzy populate``'s walking people (ORCA among the static obstacles, at 1
m/s, who ignore the robot) are added to SCENE (default: the bundled small house, a SLAM map
and a footprint robot at 0.6 m/s), and every query of the scene is driven by the navigator
(``navsim.simulate``, its budget on CPU time so that the load does not decide) once per
sensing, on a roadmap of ``--vertices`` vertices (seed 1, the static scene's). Each executed
run is checked (``gfuzzy.check``). Prints one row per run (status, arrival, smallest gap,
the check's verdict) and, per sensing, the runs valid of those made.

Sensing (``SensorOptions``): ``exact`` the true velocities; ``estimated`` from positions one
period apart (``gfuzzy navigate``'s default); ``noise`` 0.05 m on positions; ``fov`` a
180-degree view; ``noise-fov`` both; ``noise-fov-occlusion`` both, walls hiding people.
The figures of docs/navigator.md (*Limits*, the small house) are this tool's defaults.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy import NavOptions  # noqa: E402
from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.navigation.navsim import simulate  # noqa: E402
from gfuzzy.navigation.populate import PopulateOptions, populate  # noqa: E402
from gfuzzy.navigation.sensing import SensorOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402

SENSING = {
    "exact": dict(velocity="exact"),
    "estimated": dict(),
    "noise": dict(noise=0.05),
    "fov": dict(fov=180.0),
    "noise-fov": dict(noise=0.05, fov=180.0),
    "noise-fov-occlusion": dict(noise=0.05, fov=180.0, occlusion=True),
}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?", default=str(ROOT / "scenes" / "small-house.yaml"))
    ap.add_argument("--people", type=int, default=10)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3, 4])
    ap.add_argument("--vertices", type=int, default=400)
    ap.add_argument("--sensing", nargs="+", choices=list(SENSING), default=list(SENSING))
    ap.add_argument("--max-time", type=float, default=120.0, help="a run gives up this long after t0 (s)")
    args = ap.parse_args()
    base = load_scene(args.scene)
    if not base.queries:
        print(f"{args.scene}: the scene has no queries to drive", file=sys.stderr)
        return 2
    c0 = time.process_time()
    roadmap = build_roadmap(base, RoadmapOptions(vertices=args.vertices, seed=1))
    print(f"{base.name}: {len(base.queries)} queries, {args.people} people per seed, roadmap of "
          f"{args.vertices} vertices ({time.process_time() - c0:.1f} s CPU)")
    valid = {s: [0, 0] for s in args.sensing}
    for seed in args.seeds:
        people = populate(base, PopulateOptions(people=args.people, seed=seed))
        scene = replace(base, movers=tuple(base.movers) + tuple(people.movers))
        for q in scene.queries:
            for name in args.sensing:
                sensor = SensorOptions(seed=1, **SENSING[name])
                run = simulate(scene, roadmap, q.start, q.goal, max_time=args.max_time,
                               options=NavOptions(budget_clock="cpu"), sensor=sensor)
                rep = check_trajectory(scene, run.trajectory.waypoints)
                valid[name][0] += bool(rep.valid)
                valid[name][1] += 1
                verdict = "valid" if rep.valid else rep.reason.split(" (")[0]
                print(f"  seed {seed} {q.name:24s} {name:20s} {run.status.value:8s} "
                      f"{run.trajectory.waypoints[-1, 0]:6.1f} s  gap {run.min_separation:+.3f} m  {verdict}", flush=True)
    print("runs valid:")
    for name, (ok, n) in valid.items():
        print(f"  {name:20s} {ok} of {n}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
