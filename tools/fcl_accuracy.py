"""FCL's robot-to-obstacle distance against an exact reference (shapely), per request variant.

    python tools/fcl_accuracy.py [--cases 4000] [--seed 1] [--timing 300] [--near-reproducer 2000]
                                 [--robots disc box convex concave] [--obstacles disc box convex concave walls]

Random cases: a robot (disc, box, convex footprint, non-convex footprint) at a pose whose
exact distance to one obstacle (disc, rotated box, convex polygon: one prism, non-convex
polygon: triangulated, a map's walls: one BVH mesh) is drawn log-uniform in [1e-4, 3] m
(found by bisection along a random ray with shapely). For each variant of the FCL query the
error ``fcl - exact`` is collected (positive: FCL over the truth, which breaks a clearance
meant as a lower bound) and printed by distance band: the number of cases, how many are
over, the largest excess (m) and the largest excess relative to the distance. Then the cost
of one clearance query (CPU microseconds, best of three over ``--timing`` poses) per variant.

Variants (the broad phase is ``DynamicAABBTreeCollisionManager``, as in
``gfuzzy.collision.geometry``):

* ``default``: ``fcl.defaultDistanceCallback``: the manager calls it with (obstacle, robot).
* ``robot-first``: our callback computing ``fcl.distance(robot, obstacle)``.
* ``min-both``: the smaller of the two orders.
* ``gfuzzy``: what ``StaticGeometry`` measures (``gfuzzy.collision.fclmodel``'s distance
  model: boxes as convex prisms, a sphere against a flat mesh, discs in closed form; a map's
  walls are the same mesh as above, so there it is ``default``).
* ``signed`` / ``nearest``: the default callback with ``enable_signed_distance`` /
  ``enable_nearest_points``.
* ``indep``: ``gjk_solver_type=GST_INDEP``; python-fcl 0.7 passes it to the C++ request's
  third constructor argument, ``rel_err``: the solver stays libccd (the same answers).

The variants but ``gfuzzy`` ask the FCL objects of the collision model
(``fclmodel.static_objects``, ``robot_geometries``: boxes as ``fcl.Box``), which main measured
distances with until 2026-11-29. The
random cases rarely meet GJK's worst: ``--near-reproducer`` adds poses near a footprint's
pose (tests/test_geometry.py's) where an ``fcl.Box`` against a convex errs in both orders,
and compares the box as ``fcl.Box`` and as a convex prism.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import fcl
import numpy as np
import shapely

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from gfuzzy.collision.fclmodel import _walls, static_objects  # noqa: E402
from gfuzzy.collision.geometry import StaticGeometry, robot_geometries  # noqa: E402
from gfuzzy.collision.shapes import shape_of  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402

ROBOTS = ("disc", "box", "convex", "concave")
OBSTACLES = ("disc", "box", "convex", "concave", "walls")
BANDS = (0.0, 1e-3, 1e-2, 0.05, 0.2, 0.5, 1.0, 3.01)


def _star(rng, k: int) -> np.ndarray:
    """A random star-shaped polygon about the origin, k corners (often non-convex)."""
    ang = np.sort(rng.uniform(0, 2 * math.pi, k))
    r = rng.uniform(0.15, 1.0, k)
    return np.column_stack([r * np.cos(ang), r * np.sin(ang)])


def _convex(rng, scale: float) -> np.ndarray:
    """A random convex polygon (the hull of random points), counter-clockwise."""
    while True:
        hull = shapely.MultiPoint(rng.uniform(-scale, scale, (int(rng.integers(3, 12)), 2))).convex_hull
        if hull.geom_type == "Polygon" and hull.area > 0.05 * scale * scale:
            return np.asarray(shapely.geometry.polygon.orient(hull).exterior.coords)[:-1]


def _robot_doc(kind: str, rng) -> dict:
    if kind == "disc":
        return {"disc": float(rng.uniform(0.1, 0.6))}
    if kind == "box":
        return {"box": [float(rng.uniform(0.2, 1.2)), float(rng.uniform(0.1, 0.8))]}
    while True:
        pts = _convex(rng, 0.6) if kind == "convex" else _star(rng, int(rng.integers(4, 10)))
        if shapely.Polygon(pts).is_valid and shapely.Polygon(pts).area > 0.02:
            return {"footprint": np.round(pts, 6).tolist()}


def _obstacle(kind: str, rng):
    """(scene obstacle document or None, shapely reference, FCL objects when not from a scene)."""
    c = rng.uniform(-1, 1, 2)
    if kind == "disc":
        r = float(rng.uniform(0.05, 0.8))
        return {"disc": {"center": c.tolist(), "radius": r}}, (shapely.Point(c), r), None
    if kind == "box":
        size, ang = rng.uniform(0.05, 2.0, 2), float(rng.uniform(-math.pi, math.pi))
        doc = {"box": {"center": c.tolist(), "size": size.tolist(), "angle": ang}}
        ref = shapely.affinity.rotate(shapely.box(*(c - size / 2), *(c + size / 2)), ang, use_radians=True)
        return doc, (ref, 0.0), None
    if kind in ("convex", "concave"):
        while True:
            pts = _convex(rng, 1.0) if kind == "convex" else _star(rng, int(rng.integers(5, 12))) * 1.5
            poly = shapely.Polygon(pts + c)
            if poly.is_valid and poly.area > 0.05:
                return {"polygon": np.round(pts + c, 6).tolist()}, (shapely.Polygon(np.round(pts + c, 6)), 0.0), None
    lo = rng.uniform(-2, 1.5, (4, 2))
    rects = np.column_stack([lo, lo + rng.uniform(0.05, 1.0, (4, 2))])
    ref = shapely.union_all([shapely.box(*r) for r in rects])
    return None, (ref, 0.0), [fcl.CollisionObject(_walls(rects), fcl.Transform())]


def _truth(robot, shape, ref, pose) -> float:
    """The exact distance: ``ref`` is (a shapely geometry, a radius grown round it)."""
    geom, grown = ref
    if robot.shape == "disc":
        return float(geom.distance(shapely.Point(pose[:2]))) - grown - robot.radius
    return float(geom.distance(shapely.Polygon(shape.outline(np.asarray(pose)[None])[0]))) - grown


def _pose_at(robot, shape, ref, target: float, rng):
    """A pose whose exact distance to ``ref`` is ``target`` (bisection along a ray), or None."""
    heading = float(rng.uniform(-math.pi, math.pi))
    phi = float(rng.uniform(0, 2 * math.pi))
    anchor = np.asarray(ref[0].representative_point().coords[0])
    u = np.array([math.cos(phi), math.sin(phi)])

    def at(t):
        p = anchor + t * u
        return (p[0], p[1]) if robot.shape == "disc" else (p[0], p[1], heading)

    lo, hi = 0.0, target + 6.0
    if _truth(robot, shape, ref, at(lo)) >= target:
        return None
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if _truth(robot, shape, ref, at(mid)) < target:
            lo = mid
        else:
            hi = mid
    pose = at(hi)
    return pose, _truth(robot, shape, ref, pose)


def _robot_first(o1, o2, cdata):
    """The manager's callback with the pair reversed: (robot, obstacle)."""
    if cdata.done:
        return True, cdata.result.min_distance
    fcl.distance(o2, o1, cdata.request, cdata.result)
    return cdata.result.min_distance <= 0, cdata.result.min_distance


def _min_both(o1, o2, cdata):
    if cdata.done:
        return True, cdata.result.min_distance
    fcl.distance(o1, o2, cdata.request, cdata.result)
    fcl.distance(o2, o1, cdata.request, cdata.result)
    return cdata.result.min_distance <= 0, cdata.result.min_distance


VARIANTS = {
    "default": (fcl.defaultDistanceCallback, {}),
    "robot-first": (_robot_first, {}),
    "min-both": (_min_both, {}),
    "signed": (fcl.defaultDistanceCallback, {"enable_signed_distance": True}),
    "nearest": (fcl.defaultDistanceCallback, {"enable_nearest_points": True}),
    "indep": (fcl.defaultDistanceCallback, {"gjk_solver_type": fcl.GJKSolverType.GST_INDEP}),
}


def _query(manager, robot_objs, pose, callback, request) -> float:
    yaw = float(pose[2]) if len(pose) == 3 else 0.0
    tf = fcl.Transform(np.array([math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)]), np.array([pose[0], pose[1], 0.0]))
    out = math.inf
    for ob in robot_objs:
        ob.setTransform(tf)
        data = fcl.DistanceData(request=request)
        manager.distance(ob, data, callback)
        out = min(out, data.result.min_distance)
    return out


def _case(rng, rk: str, ok: str):
    """One robot and obstacle: (robot, its FCL objects, a manager of the obstacle, reference)."""
    doc, ref, objs = _obstacle(ok, rng)
    scene = parse_scene(
        {"version": 1, "name": "acc", "bounds": [-20, -20, 20, 20], "robot": {**_robot_doc(rk, rng), "vmax": 1.0},
         "obstacles": [doc] if doc else [], "queries": []},
        "acc.yaml",
    )
    objs = objs or static_objects(scene)
    manager = fcl.DynamicAABBTreeCollisionManager()
    manager.registerObjects(objs)
    manager.setup()
    robot_objs = [fcl.CollisionObject(g, fcl.Transform()) for g in robot_geometries(scene.robot)]
    geo = StaticGeometry(scene) if doc else None
    return scene.robot, robot_objs, manager, ref, geo


def measure(cases: int, seed: int, robots=ROBOTS, obstacles=OBSTACLES) -> dict:
    rng = np.random.default_rng(seed)
    requests = {name: (cb, fcl.DistanceRequest(**kw)) for name, (cb, kw) in VARIANTS.items()}
    rows = []  # (robot kind, obstacle kind, truth, {variant: fcl - truth})
    drawn = 0
    while len(rows) < cases:
        rk, ok = robots[drawn % len(robots)], obstacles[(drawn // len(robots)) % len(obstacles)]
        drawn += 1
        robot, robot_objs, manager, ref, geo = _case(rng, rk, ok)
        shape = shape_of(robot)
        for _ in range(5):
            found = _pose_at(robot, shape, ref, float(math.exp(rng.uniform(math.log(1e-4), math.log(3.0)))), rng)
            if found is None:
                continue
            pose, truth = found
            errs = {n: _query(manager, robot_objs, pose, cb, req) - truth for n, (cb, req) in requests.items()}
            if geo is None:
                errs["gfuzzy"] = errs["default"]
            else:
                geo._place(pose)
                errs["gfuzzy"] = geo._obstacle_distance(pose) - truth
            rows.append((rk, ok, truth, errs))
    return {"rows": rows}


def report(rows) -> None:
    truth = np.array([r[2] for r in rows])
    for name in [*VARIANTS, "gfuzzy"]:
        err = np.array([r[3][name] for r in rows])
        print(f"\n{name}: {len(err)} cases, over the truth {int(np.sum(err > 0))}, max over {err.max():.3g} m")
        print(f"  {'band (m)':>16} {'n':>5} {'over':>5} {'>1e-6':>6} {'max over':>10} {'max over/d':>10} {'min (under)':>11}")
        for lo, hi in zip(BANDS[:-1], BANDS[1:], strict=True):
            m = (truth >= lo) & (truth < hi)
            if m.any():
                e = err[m]
                print(f"  {lo:7.3g}-{hi:<8.3g} {m.sum():5d} {int(np.sum(e > 0)):5d} {int(np.sum(e > 1e-6)):6d} "
                      f"{e.max():10.3g} {np.max(e / truth[m]):10.3g} {e.min():11.3g}")
        worst = int(np.argmax(err))
        print(f"  worst: robot {rows[worst][0]}, obstacle {rows[worst][1]}, distance {truth[worst]:.4g}")
        kinds = {}
        for (rk, ok, _, errs) in rows:
            kinds[(rk, ok)] = max(kinds.get((rk, ok), -math.inf), errs[name])
        print("  max over by (robot, obstacle): " + ", ".join(f"{rk}/{ok} {v:.2g}" for (rk, ok), v in sorted(kinds.items()) if v > 1e-9))


def timing(n: int, seed: int) -> None:
    """Microseconds per clearance query by variant, on a footprint among 30 triangulated
    and convex polygons (best of three passes over ``n`` poses)."""
    rng = np.random.default_rng(seed)
    obstacles = []
    for _ in range(30):
        c = rng.uniform(-8, 8, 2)
        pts = (_convex(rng, 0.6) if rng.random() < 0.5 else _star(rng, 7)) + c
        if shapely.Polygon(pts).is_valid:
            obstacles.append({"polygon": np.round(pts, 6).tolist()})
    for rk in ("disc", "box", "concave"):
        scene = parse_scene({"version": 1, "name": "t", "bounds": [-20, -20, 20, 20], "robot": {**_robot_doc(rk, rng), "vmax": 1.0},
                             "obstacles": obstacles, "queries": []}, "t.yaml")
        manager = fcl.DynamicAABBTreeCollisionManager()
        manager.registerObjects(static_objects(scene))
        manager.setup()
        robot_objs = [fcl.CollisionObject(g, fcl.Transform()) for g in robot_geometries(scene.robot)]
        poses = rng.uniform([-8, -8, -math.pi], [8, 8, math.pi], (n, 3))
        line = []
        for name, (cb, kw) in VARIANTS.items():
            req = fcl.DistanceRequest(**kw)
            best = math.inf
            for _ in range(3):
                t = time.process_time()
                for p in poses:
                    _query(manager, robot_objs, p, cb, req)
                best = min(best, time.process_time() - t)
            line.append(f"{name} {1e6 * best / n:.0f}")
        geo = StaticGeometry(scene)
        dof = 2 if rk == "disc" else 3
        best = math.inf
        for _ in range(3):
            t = time.process_time()
            for p in poses:
                geo._place(p[:dof])
                geo._obstacle_distance(p[:dof])
            best = min(best, time.process_time() - t)
        line.append(f"gfuzzy {1e6 * best / n:.0f}")
        print(f"  {rk} robot ({len(robot_objs)} piece(s)), 30 polygons: " + ", ".join(line) + " us/query")


REPRO_FOOTPRINT = [[0.23097, 0.095671], [0.268794, 0.421604], [-0.401701, 0.627942], [-0.46194, 0.191342],
                   [-0.92388, -0.382683], [-0.382683, -0.92388], [0.382683, -0.92388], [0.92388, -0.382683]]  # fmt: skip
REPRO_POSE = (3.10898464, 2.71349682, 2.26967394)


def near_reproducer(n: int, seed: int) -> None:
    """The footprint 0.6 m from a box (``REPRO_*``), ``n`` poses within about 1 cm and 0.01
    rad: how often, and by how much, FCL is over the exact distance, the box an ``fcl.Box``
    (main before 2026-11-29) or a convex prism (now)."""
    from gfuzzy.collision.shapes import HEIGHT, convex_prism

    box = {"box": {"center": [2, 2], "size": [0.4, 1.2], "angle": 0.4}}
    scene = parse_scene({"version": 1, "name": "r", "bounds": [-2, -2, 6, 6], "robot": {"footprint": REPRO_FOOTPRINT, "vmax": 1.0},
                         "obstacles": [box], "queries": []}, "r.yaml")
    ob = scene.obstacles[0]
    ref = (shapely.Polygon(ob.vertices()), 0.0)
    half = np.array([math.cos(ob.angle / 2), 0.0, 0.0, math.sin(ob.angle / 2)])
    kinds = {"fcl.Box": fcl.CollisionObject(fcl.Box(*ob.size, 2 * HEIGHT), fcl.Transform(half, np.array([*ob.center, 0.0]))),
             "prism": fcl.CollisionObject(convex_prism(ob.vertices()), fcl.Transform())}
    robot_objs = [fcl.CollisionObject(g, fcl.Transform()) for g in robot_geometries(scene.robot)]
    shape = shape_of(scene.robot)
    rng = np.random.default_rng(seed)
    poses = np.asarray(REPRO_POSE) + rng.normal(0.0, 0.01, (n, 3))
    truths = np.array([_truth(scene.robot, shape, ref, p) for p in poses])
    for kind, obj in kinds.items():  # the box alone, as FCL objects
        manager = fcl.DynamicAABBTreeCollisionManager()
        manager.registerObjects([obj])
        manager.setup()
        line = []
        for name in ("default", "robot-first", "min-both"):
            cb, kw = VARIANTS[name]
            err = np.array([_query(manager, robot_objs, p, cb, fcl.DistanceRequest(**kw)) for p in poses]) - truths
            line.append(f"{name} over 1e-6: {int(np.sum(err > 1e-6))}, max {err.max():.3g} m")
        print(f"  {kind}: " + "; ".join(line))
    geo = StaticGeometry(scene)
    err = np.array([geo._place(p) or geo._obstacle_distance(p) for p in poses]) - truths
    print(f"  gfuzzy (StaticGeometry): over 1e-6: {int(np.sum(err > 1e-6))}, max {err.max():.3g} m")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--timing", type=int, default=300, help="poses timed per variant (0: no timing)")
    ap.add_argument("--near-reproducer", type=int, default=2000, help="poses near the reproducer (0: none)")
    ap.add_argument("--robots", nargs="+", choices=ROBOTS, default=ROBOTS)
    ap.add_argument("--obstacles", nargs="+", choices=OBSTACLES, default=OBSTACLES)
    args = ap.parse_args()
    if args.near_reproducer:
        print(f"{args.near_reproducer} poses near the reproducer (a footprint 0.6 m from a box):")
        near_reproducer(args.near_reproducer, args.seed)
    if args.cases:
        report(measure(args.cases, args.seed, tuple(args.robots), tuple(args.obstacles))["rows"])
    if args.timing:
        print("\ncost of one clearance query:")
        timing(args.timing, args.seed)


if __name__ == "__main__":
    main()
