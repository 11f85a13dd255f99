"""What a planner that knows the humans' future achieves in the crowd, by roadmap size.

    python tools/oracle_bound.py                                   # 5 humans, unicycle, 60 episodes
    python tools/oracle_bound.py --humans 20 --episodes 100 --vertices 400 2000
    python tools/oracle_bound.py --kinematics holonomic --humans 20
    python tools/oracle_bound.py --humans 20 --vertices 400 --dt 0.07 0.03   # the time step's part

The ``oracle`` policy of ``gfuzzy crowd`` (``gfuzzy.plan`` told the true future of humans
who ignore the robot, followed in the benchmark's closed loop) on the crowd's roadmap
built with each ``--vertices``: its success, collision and timeout rates and mean time to
the goal, the same episodes (seed 1) for every size. It is a bound for any navigator
that plans on such a roadmap (a navigator does not know the future); that a denser
roadmap does not raise it says the bound is not the roadmap's sparsity. ``--dt`` plans
on other time steps (the planner's default 0.07): for a differential drive a finer step
solves episodes a coarser one does not (its turns take whole steps). It also lists the
episodes the oracle does not solve.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.roadmap.roadmap import build_roadmap  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--humans", type=int, default=5)
    ap.add_argument("--kinematics", choices=("holonomic", "unicycle"), default="unicycle")
    ap.add_argument("--reverse", action="store_true", help="a unicycle that may drive backwards")
    ap.add_argument("--episodes", type=int, default=60)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--vertices", type=int, nargs="+", default=[400, 1000, 2000])
    ap.add_argument("--dt", type=float, nargs="+", default=[0.07], help="the oracle's time steps (s)")
    args = ap.parse_args(argv)
    setting = C.CrowdSetting(humans=args.humans, kinematics=args.kinematics, reverse=args.reverse)
    print(f"circle crossing, {args.humans} humans who ignore the robot, {args.kinematics}"
          f"{' (reverse)' if args.reverse else ''}, {args.episodes} episodes, seed {args.seed}")
    print(f"{'vertices':>8} {'dt':>5} {'success':>8} {'collide':>8} {'timeout':>8} {'time s':>7} {'cpu s':>6}  unsolved")
    for n in args.vertices:
        roadmap = build_roadmap(C.crowd_scene(setting), replace(C._roadmap_options(setting), vertices=n))
        for dt in args.dt:
            _row(setting, roadmap, n, dt, args)
    return 0


def _row(setting, roadmap, n: int, dt: float, args) -> None:
    """One line of the table: the oracle on ``roadmap`` (``n`` vertices) at time step ``dt``."""
    c0 = time.process_time()
    runs = [C.run_episode(setting, roadmap, args.seed, i, ["oracle"], oracle_dt=dt)[0] for i in range(args.episodes)]
    out = np.array([[r.reached, r.collision] for r in runs], dtype=bool)
    times = [r.time for r in runs if r.reached]
    missed = [r.seed for r in runs if not r.reached]  # the episode numbers
    print(f"{n:>8} {dt:>5.2f} {out[:, 0].mean():>8.3f} {out[:, 1].mean():>8.3f} {1 - out.any(axis=1).mean():>8.3f} "
          f"{np.mean(times) if times else float('nan'):>7.2f} {time.process_time() - c0:>6.0f}  {missed}", flush=True)


if __name__ == "__main__":
    raise SystemExit(main())
