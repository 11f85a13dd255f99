"""Measure how close a trajectory comes to static obstacles, the bounds and the movers.

    python tools/clearances.py SCENE TRAJ.json [--hold SECONDS] [--samples N]

Prints the smallest distance (metres) from the robot's body to the static obstacles, to the
bounds and to any present mover, over the trajectory (and the hold at the goal), sampled
densely in time; the distances are the true ones, whatever clearances the scene asks for
(``gfuzzy check`` is the exact verifier; this is the figure to report).
"""

from __future__ import annotations

import argparse

import numpy as np
import shapely

from gfuzzy.check.check import _World
from gfuzzy.collision.geometry import mover_distance
from gfuzzy.scene.scene import load_scene
from gfuzzy.trajectory import load_trajectory


def measure(scene, waypoints, hold: float = 0.0, samples: int = 100_001) -> dict:
    """Smallest distances to obstacles, bounds and movers (dense samples in time)."""
    w = np.array(waypoints, dtype=float)
    if hold > 0:
        w = np.vstack([w, np.r_[w[-1, 0] + hold, w[-1, 1:]]])
    if w.shape[1] == 4:
        w[:, 3] = np.unwrap(w[:, 3])  # interpolate headings along the shorter arc
    t = np.linspace(w[0, 0], w[-1, 0], samples)
    p = np.column_stack([np.interp(t, w[:, 0], w[:, k]) for k in range(1, w.shape[1])])
    world = _World(scene.with_clearances(0.0, 0.0))
    geoms = world.robot_geoms(p)
    static = np.full(len(t), np.inf)
    if world.static is not None:
        static = world._shape_distance(geoms, world.static, True)
    for centre, radius in world.discs:
        static = np.minimum(static, world._shape_distance(geoms, shapely.Point(centre), False) - radius)
    movers = np.inf
    for mv in scene.movers:
        xy, present = mv.state(t)
        if present.any():
            d = mover_distance(scene.robot, p, mv.shape, mv.radius, mv.size, xy)
            movers = min(movers, float(d[present].min()))
    return {"static": float(static.min()), "bounds": float(world.bounds_clearance(p).min()), "movers": movers}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scene")
    ap.add_argument("trajectory")
    ap.add_argument("--hold", type=float, default=0.0)
    ap.add_argument("--samples", type=int, default=100_001)
    args = ap.parse_args()
    scene = load_scene(args.scene)
    tf = load_trajectory(args.trajectory)
    m = measure(scene, tf.waypoints, args.hold, args.samples)
    print(f"{args.trajectory}: static {m['static']:.4f} m, bounds {m['bounds']:.4f} m, movers {m['movers']:.4f} m")


if __name__ == "__main__":
    main()
