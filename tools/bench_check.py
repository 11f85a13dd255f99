"""What ``gfuzzy check`` costs on a box sliding along a row of abutting boxes, with and
without proving a rounding's overlap touching before measuring its depth.

    python tools/bench_check.py [--boxes 100] [--repeat 3]

A 0.6 x 0.4 box slides at vmax 0.5 along the top of ``--boxes`` abutting 0.1 m boxes
(one polygon after their union, a vertex every 0.1 m), in four ways: flush, 1e-12 m into
them, on rows every 0.07 s (the planner's grid), and the row turned 30 degrees (every
coordinate rounded). Prints, per case, the verdict and evaluations (the same with and
without) and the CPU seconds of each (best of --repeat): "measured" measures every overlap
(``overlap_depth(convex=False)``), "proven" first proves a box's overlap at most the
tolerance deep by its core (``gfuzzy/check/depth.py``, ``_within_tol``), and their ratio.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import gfuzzy.check.check as check
from gfuzzy.scene.scene import parse_scene

CASES = {  # name: (angle of the row, m into it, rows on the 0.07 s grid)
    "flush": (0.0, 0.0, False),
    "1e-12 m in": (0.0, 1e-12, False),
    "flush, 0.07 s rows": (0.0, 0.0, True),
    "turned 30 degrees": (math.pi / 6, 0.0, False),
}


def case(boxes: int, angle: float, into: float, grid: bool):
    """The scene and the rows of one slide."""
    c, s = math.cos(angle), math.sin(angle)
    along, side = np.array([c, s]), np.array([-s, c])
    origin = np.array([1.0, 4.0])
    obstacles = [
        {"box": {"center": (origin + (1.05 + 0.1 * i) * along).tolist(), "size": [0.1, 1.0], "angle": angle}}
        for i in range(boxes)
    ]
    scene = parse_scene({
        "version": 1, "name": "abutting", "bounds": [0, 0, 0.1 * boxes + 6, 0.1 * boxes + 6],
        "robot": {"box": [0.6, 0.4], "vmax": 0.5}, "movers": [], "queries": [], "obstacles": obstacles,
    })  # fmt: skip
    a = origin + 0.5 * along + (0.7 - into) * side
    length = 0.1 * boxes + 1.0
    duration = length / 0.5
    t = np.append(np.arange(0.0, duration, 0.07), duration) if grid else np.array([0.0, duration])
    xy = a + (t / duration)[:, None] * length * along
    return scene, np.column_stack([t, xy, np.full(len(t), angle)])


def timed(scene, rows, convex: bool, repeat: int):
    """(best CPU seconds, report) of checking ``rows``, the box proven convex or not."""
    keep = check._World.__init__

    def init(self, *a, **k):
        keep(self, *a, **k)
        self.convex = self.convex and convex

    check._World.__init__ = init
    try:
        best, rep = math.inf, None
        for _ in range(repeat):
            t = time.process_time()
            rep = check.check_trajectory(scene, rows)
            best = min(best, time.process_time() - t)
        return best, rep
    finally:
        check._World.__init__ = keep


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--boxes", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{'case':<20} {'verdict':<8} {'evaluations':>11} {'measured s':>10} {'proven s':>9} {'ratio':>6}")
    for name, (angle, into, grid) in CASES.items():
        scene, rows = case(args.boxes, angle, into, grid)
        old, a = timed(scene, rows, False, args.repeat)
        new, b = timed(scene, rows, True, args.repeat)
        same = (a.valid, a.evaluations) == (b.valid, b.evaluations)
        verdict = ("valid" if b.valid else "invalid") if same else "DIFFER"
        print(f"{name:<20} {verdict:<8} {b.evaluations:>11} {old:>10.2f} {new:>9.2f} {old / new:>6.1f}")


if __name__ == "__main__":
    main()
