"""Who walked into whom: each mover's first contact with the robot in a navigate run.

    python tools/nav_contacts.py SCENE RUN.json [RUN.json ...] [--fov 90] [--occlusion]

For every executed trajectory (``gfuzzy navigate -o RUN.json``, run on SCENE) prints how much
of the robot's motion was outside its field of view (a cone of ``--fov`` degrees about its
heading; a disc robot's view follows its motion, so this is for a box or footprint robot),
and for each mover that overlapped the robot: when, how deep, the robot's and the mover's
speeds toward each other 0.1 s before the contact, the angle between the robot's motion and
its heading then, and whether the sensor (the cone, and with ``--occlusion`` the walls) let
the robot see the mover in the 3 s before. docs/navigator.md (*Limits*, the populated small
house with a narrow noisy view) reports what it found there.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.collision.geometry import mover_distance  # noqa: E402
from gfuzzy.navigation.sensing import Sensor, SensorOptions  # noqa: E402
from gfuzzy.poses import wrap_angle  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.trajectory import Trajectory, load_trajectory  # noqa: E402

#: Sampling of the run (s), the speeds' window (s), how long before a contact "seen" looks back (s).
STEP, WINDOW, BEFORE = 0.05, 0.25, 3.0


def contacts(scene, waypoints, fov: float = 360.0, occlusion: bool = False) -> tuple[float, list]:
    """(share of the robot's motion outside its view, [dict per first contact])."""
    w = np.asarray(waypoints, dtype=float)
    traj = Trajectory(w, scene.robot.circumradius)
    ts = np.arange(w[0, 0], w[-1, 0] - WINDOW, STEP)
    if not len(ts):
        return 0.0, []
    p0, p1 = traj.at(ts), traj.at(ts + WINDOW)
    vel = (p1[:, :2] - p0[:, :2]) / WINDOW
    moving = np.hypot(vel[:, 0], vel[:, 1]) > 0.1
    heading = p0[:, 2] if p0.shape[1] == 3 else np.arctan2(vel[:, 1], vel[:, 0])
    off = np.abs(wrap_angle(np.arctan2(vel[:, 1], vel[:, 0]) - heading))
    blind = float((moving & (off > math.radians(fov) / 2)).sum() / max(moving.sum(), 1))
    sensor = Sensor(scene, SensorOptions(fov=fov, occlusion=occlusion))
    found = []
    for mv in scene.movers:
        xy, present = mv.state(ts)
        gap = mover_distance(scene.robot, p0, mv.shape, mv.radius, mv.size, xy)
        gap = np.where(present, np.asarray(gap, dtype=float).reshape(-1), np.inf)
        hit = np.nonzero(gap < 0)[0]
        if not hit.size:
            continue
        k = int(hit[0])
        j = max(k - 2, 0)
        ahead, _ = mv.state(ts[j : j + 1] + WINDOW)
        rel = xy[j] - p0[j, :2]
        u = rel / max(float(np.hypot(*rel)), 1e-9)
        back = range(max(0, k - int(round(BEFORE / STEP))), k)
        seen = any(sensor.visible(p0[i], float(heading[i]), np.array([[*xy[i], 0, 0, mv.extent]]))[0] for i in back)
        found.append({
            "mover": mv.name, "t": float(ts[k]), "deepest": float(gap.min()),
            "robot_closing": float(np.dot(vel[j], u)), "mover_closing": float(-np.dot((ahead[0] - xy[j]) / WINDOW, u)),
            "off_heading_deg": math.degrees(off[j]) if moving[j] else 0.0, "seen": bool(seen),
        })  # fmt: skip
    return blind, found


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("runs", nargs="+")
    ap.add_argument("--fov", type=float, default=360.0)
    ap.add_argument("--occlusion", action="store_true")
    args = ap.parse_args()
    scene = load_scene(args.scene)
    total = unseen = closing = 0
    for run in args.runs:
        blind, found = contacts(scene, load_trajectory(run).waypoints, args.fov, args.occlusion)
        print(f"{run}: motion outside the view {blind:.2f}, {len(found)} mover(s) overlapped")
        for c in found:
            print(f"  {c['mover']:10s} at {c['t']:7.2f} s, {-c['deepest']:.2f} m deep: robot closing "
                  f"{c['robot_closing']:+.2f} m/s ({c['off_heading_deg']:.0f} deg off its heading), mover closing "
                  f"{c['mover_closing']:+.2f} m/s, {'seen' if c['seen'] else 'not seen'} in the {BEFORE:g} s before")
            total, unseen, closing = total + 1, unseen + (not c["seen"]), closing + (c["robot_closing"] > 0.1)
    print(f"{total} contact(s): {unseen} with a mover not seen before, {closing} with the robot driving toward it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
