"""Map benchmark: a warehouse-size occupancy grid against the same racks drawn as polygons.

    python tools/bench_map.py [--vertices 3000] [--seed 1] [--queries 5] [--robot box|footprint|disc]

Generates (seeded) a 1000 x 1700-pixel map at 0.03 m (30 x 51 m): outer walls, 6 x 6 rack
blocks whose faces SLAM saw (a 2-pixel outline) and whose insides it did not (unknown, gray),
a large unexplored region (unknown) in the north-east and a loading bay, and a few
speckles (single occupied pixels, 2e-5 of the free cells: SLAM artefacts; at 4e-4 the
box robot's straight PRM edges hit one every few metres and the roadmap falls apart into
components, as it should: a speckle is an obstacle). The hand-drawn scene has the same racks and
regions as box obstacles (no speckles). Both get the same robot and the same four forklift
movers in the aisles.

Prints, for each scene: the load and collision-model time, the roadmap build time (wall
and this process's CPU time: on a loaded machine the CPU time is what the build costs) at
``--vertices`` vertices, its components, and the planning time of ``--queries`` queries
between seeded free points far apart (mean and max, after one warm-up query). Targets
(issue 17): build <= 20 s at 3000 vertices, each query <= 0.5 s.

With ``--robot disc`` (radius 0.3) the roadmap is joined through the exactly computed free
space (:mod:`gfuzzy.roadmap.freespace`); its computation is then also timed both ways, cut
into tiles (the default) and at once, each in a child process whose peak memory is read from
the system, on the warehouse (whose straight racks make few rectangles) and on a real SLAM
map made large: Nav2's depot map (``scenes/maps/depot.pgm``) repeated 3 x 4 times, 1812 x
1228 cells (90.6 x 61.4 m), whose ragged walls make 15,932 rectangles.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.planner.planner import Planner, PlanOptions  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402

RES = 0.03
W, H = 1000, 1700  # columns (x), rows (y)
FREE, OCC, UNKNOWN = 254, 0, 205


def warehouse(seed: int):
    """Pixels (H, W) uint8, row 0 the top, and the blocked boxes [x0, y0, x1, y1] in metres
    (rack blocks and unknown regions) that the hand-drawn scene uses."""
    rng = np.random.default_rng(seed)
    img = np.full((H, W), FREE, dtype=np.uint8)
    boxes = []

    def fill(x0, y0, x1, y1, value, outline=False):
        c0, c1 = int(round(x0 / RES)), int(round(x1 / RES))
        r0, r1 = H - int(round(y1 / RES)), H - int(round(y0 / RES))  # rows from the top
        img[r0:r1, c0:c1] = value
        if outline:
            img[r0:r1, c0:c1] = UNKNOWN
            img[r0 : r0 + 2, c0:c1] = OCC
            img[r1 - 2 : r1, c0:c1] = OCC
            img[r0:r1, c0 : c0 + 2] = OCC
            img[r0:r1, c1 - 2 : c1] = OCC
        boxes.append((c0 * RES, (H - r1) * RES, c1 * RES, (H - r0) * RES))

    # racks: 6 columns of 6 blocks, 1.5 m deep, 5.4 m long, aisles 3 m wide, cross aisles 2.4 m
    for i in range(6):
        for k in range(6):
            x0 = 2.4 + i * 4.5
            y0 = 3.0 + k * 7.8
            if x0 > 19.0 and y0 > 33.0:
                continue  # the unexplored region covers these
            fill(x0, y0, x0 + 1.5, y0 + 5.4, OCC, outline=True)
    fill(19.5, 33.6, 30.0, 51.0, UNKNOWN)  # unexplored north-east
    fill(0.0, 0.0, 6.0, 1.2, UNKNOWN)  # a closed loading bay (unknown)
    # speckle noise in the free space (SLAM artefacts), not in the hand-drawn scene
    noise = (rng.random((H, W)) < 0.00002) & (img == FREE)
    img[noise] = OCC
    # walls: 3 pixels
    img[:3, :] = OCC
    img[-3:, :] = OCC
    img[:, :3] = OCC
    img[:, -3:] = OCC
    return img, boxes


def movers_yaml() -> str:
    rows = []
    for n, x in enumerate((3.45 + 3.0 / 2 + 0.75, 12.45 + 0.75 + 1.5, 16.95 + 2.25, 7.95 + 2.25)):
        rows.append(
            f"  - {{name: F{n + 1}, box: [0.6, 1.0], speed: 0.8, path: [[{x:.2f}, 2.0], [{x:.2f}, 32.0]], "
            f"mode: bounce, offset: {4.0 * n:.1f}}}"
        )
    return "movers:\n" + "\n".join(rows) + "\n"


def robot_yaml(kind: str) -> str:
    if kind == "disc":
        return "robot: {disc: 0.3, vmax: 1.0}\n"
    if kind == "footprint":
        return "robot: {footprint: [[0.45, 0.3], [-0.35, 0.3], [-0.35, -0.3], [0.45, -0.3]], vmax: 1.0}\n"
    return "robot: {box: [0.8, 0.6], vmax: 1.0}\n"


def write_scenes(folder: Path, seed: int, robot: str) -> tuple[Path, Path, float]:
    img, boxes = warehouse(seed)
    from PIL import Image

    Image.fromarray(img).save(folder / "warehouse.pgm")
    (folder / "warehouse.yaml").write_text(
        f"image: warehouse.pgm\nresolution: {RES}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    head = "version: 1\n"
    grid = folder / "grid.yaml"
    grid.write_text(head + "name: wh-grid\n" + robot_yaml(robot) + "obstacles:\n  - map: {file: warehouse.yaml}\n" + movers_yaml())
    obs = "".join(
        f"  - box: {{center: [{(x0 + x1) / 2:.4f}, {(y0 + y1) / 2:.4f}], size: [{x1 - x0:.4f}, {y1 - y0:.4f}]}}\n"
        for x0, y0, x1, y1 in boxes
    )
    wall = 3 * RES
    poly = folder / "polygons.yaml"
    poly.write_text(
        head + "name: wh-polygons\n" + f"bounds: [{wall}, {wall}, {W * RES - wall}, {H * RES - wall}]\n"
        + robot_yaml(robot) + "obstacles:\n" + obs + movers_yaml()
    )  # fmt: skip
    occupied = float(np.mean(img == OCC))
    return grid, poly, occupied


def queries(scene, n: int, seed: int):
    """n pairs of valid poses at least 20 m apart (seeded)."""
    rng = np.random.default_rng(seed + 1000)
    geo = StaticGeometry(scene)
    xmin, ymin, xmax, ymax = scene.bounds
    pairs = []
    while len(pairs) < n:
        a = np.array([rng.uniform(xmin, xmax), rng.uniform(ymin, ymax), rng.uniform(-np.pi, np.pi)])
        b = np.array([rng.uniform(xmin, xmax), rng.uniform(ymin, ymax), rng.uniform(-np.pi, np.pi)])
        if np.hypot(*(a[:2] - b[:2])) >= 20 and geo.is_valid(a) and geo.is_valid(b):
            dof = scene.robot.dof
            pairs.append((tuple(a[:dof]), tuple(b[:dof])))
    return pairs


def run(path: Path, vertices: int, seed: int, n_queries: int) -> dict:
    t = time.perf_counter()
    scene = load_scene(path)
    StaticGeometry(scene)
    load = time.perf_counter() - t
    t, cpu = time.perf_counter(), time.process_time()
    roadmap = build_roadmap(scene, RoadmapOptions(vertices=vertices, seed=seed))
    build, build_cpu = time.perf_counter() - t, time.process_time() - cpu
    planner = Planner(scene, roadmap)
    pairs = queries(scene, n_queries + 1, seed)
    planner.plan(pairs[0][0], pairs[0][1], 0.0, PlanOptions())  # warm-up: kernels, caches
    times, cpus, statuses = [], [], []
    for a, b in pairs[1:]:
        t, cpu = time.perf_counter(), time.process_time()
        res = planner.plan(a, b, 0.0, PlanOptions())
        times.append(time.perf_counter() - t)
        cpus.append(time.process_time() - cpu)
        statuses.append(str(res.status.value))
    return {
        "load": load, "build": build, "build_cpu": build_cpu, "q_cpu": float(np.max(cpus)), "edges": len(roadmap.edges), "components": roadmap.info.components,
        "q_mean": float(np.mean(times)), "q_max": float(np.max(times)), "statuses": statuses,
    }  # fmt: skip


def depot_tiled(folder: Path) -> Path:
    """A scene around the bundled depot map repeated 3 x 4 times (a disc robot of radius 0.3)."""
    from PIL import Image

    img = np.asarray(Image.open(ROOT / "scenes" / "maps" / "depot.pgm"))
    Image.fromarray(np.tile(img, (4, 3))).save(folder / "depot12.pgm")
    (folder / "depot12.yaml").write_text(
        "image: depot12.pgm\nmode: trinary\nresolution: 0.05\norigin: [0.0, 0.0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.25\n"
    )
    path = folder / "depot12-scene.yaml"
    path.write_text("version: 1\nname: depot12\nrobot: {disc: 0.3, vmax: 1.0}\nobstacles:\n  - map: {file: depot12.yaml}\n")
    return path


def _free_space_child(path: str, tile_rects: int, out) -> None:
    import resource

    from gfuzzy.roadmap import freespace

    freespace.TILE_RECTS = tile_rects
    scene = load_scene(path)
    cpu = time.process_time()
    fs = freespace.free_space(scene)
    cpu = time.process_time() - cpu
    area = sum(g.area for g in fs.regions)
    out.put((cpu, len(fs.regions), area, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024))


def free_space_ways(path: Path) -> None:
    """The map's free space cut into tiles (the default) and at once: CPU time, regions, peak memory."""
    import multiprocessing as mp

    from gfuzzy.roadmap import freespace

    ctx = mp.get_context("fork")
    rows = []
    for name, tiles in (("tiles", freespace.TILE_RECTS), ("at once", 10**12)):
        q = ctx.Queue()
        p = ctx.Process(target=_free_space_child, args=(str(path), tiles, q))
        p.start()
        rows.append((name, *q.get()))
        p.join()
    for name, cpu, n, area, mb in rows:
        print(f"free space, {name:<8} {cpu:7.2f} s CPU  {n} regions  area {area:.6f} m2  peak {mb:.0f} MB")
    print(f"free space: tiles / at once = {rows[0][1] / rows[1][1]:.2f} of the CPU time, "
          f"{rows[0][4] / rows[1][4]:.2f} of the peak memory")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--queries", type=int, default=5)
    ap.add_argument("--robot", choices=("box", "footprint", "disc"), default="box")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        grid, poly, occupied = write_scenes(Path(tmp), args.seed, args.robot)
        print(f"warehouse {W} x {H} px at {RES} m ({W * RES:.0f} x {H * RES:.0f} m), {occupied:.1%} occupied; "
              f"{args.robot} robot; load {os.getloadavg()[0]:.1f}")  # fmt: skip
        print(f"{'scene':<10} {'load+model s':>12} {'build s':>8} {'cpu s':>6} {'edges':>7} {'comp':>5} "
              f"{'query mean s':>12} {'max s':>6} {'max cpu s':>9}  statuses")  # fmt: skip
        for name, path in (("map", grid), ("polygons", poly)):
            r = run(path, args.vertices, args.seed, args.queries)
            print(f"{name:<10} {r['load']:>12.2f} {r['build']:>8.2f} {r['build_cpu']:>6.2f} {r['edges']:>7} "
                  f"{str(r['components']):>5} {r['q_mean']:>12.3f} {r['q_max']:>6.3f} {r['q_cpu']:>9.3f}  "
                  f"{' '.join(r['statuses'])}")  # fmt: skip
        if args.robot == "disc":
            print("the warehouse map:")
            free_space_ways(grid)
            print("Nav2's depot map repeated 3 x 4 (1812 x 1228 cells):")
            free_space_ways(depot_tiled(Path(tmp)))


if __name__ == "__main__":
    main()
