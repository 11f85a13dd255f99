"""Times `gfuzzy export`'s two writers on a synthetic 100 m x 100 m floor (100 obstacles:
long rotated walls, discs, polygons), against a cell-by-cell rasterisation in the same run.

    python tools/bench_export.py [--resolution 0.05]

Prints seconds per step and the ratio; say the machine's load (`uptime`) with the figures.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
import shapely  # noqa: E402

from gfuzzy.export.export import ExportOptions, export_mcap  # noqa: E402
from gfuzzy.export.mapexport import rasterise  # noqa: E402
from gfuzzy.scene.scene import Box, Disc, parse_scene  # noqa: E402


def floor(seed: int = 1):
    rng = np.random.default_rng(seed)
    obs = []
    for _ in range(34):
        obs.append({"box": {"center": rng.uniform(5, 95, 2).tolist(), "size": [float(rng.uniform(1, 30)), float(rng.uniform(0.05, 0.5))], "angle": float(rng.uniform(0, 3))}})
    for _ in range(33):
        obs.append({"disc": {"center": rng.uniform(5, 95, 2).tolist(), "radius": float(rng.uniform(0.05, 2))}})
    for _ in range(33):
        c, r = rng.uniform(10, 90, 2), rng.uniform(0.2, 5)
        obs.append({"polygon": [[float(c[0] + r * math.cos(a)), float(c[1] + r * math.sin(a))] for a in np.sort(rng.uniform(0, 2 * math.pi, 7))]})
    doc = {"version": 1, "name": "floor", "bounds": [0, 0, 100, 100], "robot": {"disc": 0.2, "vmax": 1}, "obstacles": obs}
    doc["movers"] = [{"name": f"m{i}", "disc": 0.3, "speed": 1.0, "mode": "loop", "path": rng.uniform(0, 100, (4, 2)).tolist()} for i in range(50)]
    return parse_scene(doc)


def cell_by_cell(scene, res):
    """The baseline: every cell against every obstacle (as tests/test_export.py's oracle)."""
    x0, y0, x1, y1 = scene.bounds
    w, h = math.ceil((x1 - x0) / res - 1e-9), math.ceil((y1 - y0) / res - 1e-9)
    occ = np.zeros((h, w), dtype=bool)
    xs = x0 + np.arange(w + 1) * res
    for k in range(h):  # a row at a time: bounded memory
        cells = shapely.box(xs[:-1], y0 + k * res, xs[1:], y0 + (k + 1) * res)
        for ob in scene.obstacles:
            if isinstance(ob, Disc):
                occ[k] |= shapely.distance(shapely.Point(ob.center), cells) < ob.radius
            else:
                shape = shapely.Polygon(ob.vertices()) if isinstance(ob, Box) else shapely.Polygon(ob.points)
                occ[k] |= shapely.relate_pattern(cells, shape, "T********")
    return occ[::-1]


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--resolution", type=float, default=0.1)
    args = ap.parse_args()
    scene = floor()
    t = time.perf_counter()
    grid = rasterise(scene, args.resolution)
    fast = time.perf_counter() - t
    t = time.perf_counter()
    slow_occ = cell_by_cell(scene, args.resolution)
    slow = time.perf_counter() - t
    same = bool(np.array_equal(grid.occupied, slow_occ))
    h, w = grid.shape
    print(f"rasterise {w} x {h} cells at {args.resolution:g} m: {fast:.2f} s; cell by cell {slow:.2f} s ({slow / fast:.1f}x); identical: {same}")
    rows = np.column_stack([np.linspace(0, 120, 200), np.linspace(1, 99, 200), np.linspace(1, 99, 200)])
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "f.mcap"
        t = time.perf_counter()
        report = export_mcap(scene, out, rows, options=ExportOptions(step=0.1))
        took = time.perf_counter() - t
        size = os.path.getsize(out)
    print(f"export_mcap 120 s at 10 Hz, 50 movers: {took:.2f} s, {size / 1e6:.1f} MB, {sum(report.counts.values())} messages")
    print(f"load: {os.getloadavg()[0]:.1f} (1-minute average) on {os.cpu_count()} cores")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
