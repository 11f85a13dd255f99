"""The speed layer of a differential drive: durations, accelerations, turning rates.

For every query of the bundled ``kinematics: unicycle`` scenes, planned by the search alone
and with ``--speed-layer``: the duration, whether the layer applied (and why not), the
corners of the path before and after it is straightened, and, measured from the rows (mean
speeds of neighbouring row pairs), the largest linear acceleration, angular acceleration,
speed and |w|. ``applied``: ``yes`` (the whole path layered), ``part`` (some legs at the
search's pace, where no timing of the whole layered path exists among the movers: their
rows are in the maxima), ``no``. The same scenes without their movers are added (``/static``): the layer's
cost alone, with no waiting for movers.

    python tools/bench_drive_speed.py [--seed S]
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from gfuzzy.planner.planner import PlanOptions, plan
from gfuzzy.roadmap.roadmap import default_roadmap_path, load_roadmap
from gfuzzy.scene.scene import load_scene

ROOT = Path(__file__).resolve().parent.parent


def row_figures(w: np.ndarray) -> tuple[float, float, float, float]:
    """(max |v|, max |w|, max linear acceleration, max angular acceleration) of the rows:
    each row pair's mean forward speed and turning rate, and their changes between
    neighbouring row pairs of one kind over the mean of their durations."""
    dt = np.diff(w[:, 0])
    d = np.diff(w[:, 1:3], axis=0)
    dh = (np.diff(w[:, 3]) + np.pi) % (2 * np.pi) - np.pi
    v = (np.cos(w[:-1, 3]) * d[:, 0] + np.sin(w[:-1, 3]) * d[:, 1]) / dt
    om = dh / dt
    moving = np.hypot(d[:, 0], d[:, 1]) > 1e-12
    mid = 0.5 * (dt[1:] + dt[:-1])
    acc = np.abs(np.diff(v)) / mid
    alpha = np.abs(np.diff(om)) / mid
    lin = acc[moving[1:] | moving[:-1]]
    ang = alpha[~moving[1:] | ~moving[:-1]]
    return float(np.abs(v).max()), float(np.abs(om).max()), float(lin.max(initial=0.0)), float(ang.max(initial=0.0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    head = (f"{'query':<44}{'plan':<9}{'applied':<9}{'dur s':>7}{'profile':>8}{'corners':>9}{'max v':>7}"
            f"{'max|w|':>7}{'max a':>8}{'max alpha':>10}{'plan s':>7}")  # fmt: skip
    print(head)
    print("-" * len(head))
    for file in sorted((ROOT / "scenes").glob("*.yaml")):
        scene = load_scene(file)
        rm_file = default_roadmap_path(scene, ROOT / "roadmaps")
        if not scene.robot.unicycle or not rm_file.exists():
            continue
        roadmap = load_roadmap(rm_file, scene)
        for variant, sc in (("", scene), ("/static", dataclasses.replace(scene, movers=()))):
            for q in sc.queries:
                name = f"{sc.name}{variant}/{q.name}"
                for label, layer in (("search", False), ("layered", True)):
                    t = time.perf_counter()
                    res = plan(sc, roadmap, q.start, q.goal, q.t0, PlanOptions(speed_layer=layer, seed=args.seed))
                    secs = time.perf_counter() - t
                    if not res.solved:
                        print(f"{name:<44}{label:<9}unsolved")
                        continue
                    rep = res.speed_report
                    applied = "-" if rep is None else ("part" if rep.hasty else "yes" if rep.applied else "no")
                    prof = f"{rep.profile_seconds:8.2f}" if rep is not None and rep.profile_seconds else f"{'':8}"
                    corners = f"{rep.corners['before']}->{rep.corners['after']}" if rep is not None and rep.corners else ""
                    vm, wm, am, alm = row_figures(res.trajectory.waypoints)
                    print(f"{name:<44}{label:<9}{applied:<9}{res.trajectory.duration:>7.2f}{prof}{corners:>9}"
                          f"{vm:>7.3f}{wm:>7.3f}{am:>8.2f}{alm:>10.2f}{secs:>7.2f}")  # fmt: skip
                    if rep is not None and not rep.applied:
                        print(f"{'':<44}  ({rep.reason})")
                    if rep is not None and rep.hasty:
                        h = rep.hasty
                        print(f"{'':<44}  ({h['legs']} of {h['of']} legs, {h['length']:.2f} of {h['total']:.2f} m, "
                              "at the search's pace: their rows break amax)")  # fmt: skip
        r = scene.robot
        amax = r.amax if r.amax is not None else 2 * r.vmax
        print(f"({scene.name}: vmax {r.vmax}, wmax {r.turn_rate:.3g}, amax {amax}, amax/r {amax / r.circumradius:.3g})")


if __name__ == "__main__":
    main()
