"""Static certification on SLAM maps: the distance transform's steps against FCL's.

    python tools/bench_certify.py [--motions 400] [--seed 1] [SCENE ...]

For each scene (default: the bundled map scenes small-house, tb3-arena, depot) it draws
``--motions`` seeded straight motions between valid poses (0.2-3 m, heading changes up to
1 rad; a disc robot's poses without heading) and certifies each twice, in the same run:

* ``motion_clearance(a, b) >= 0``: sphere tracing by FCL's clearance at every step (what
  ``motion_free`` did before);
* ``motion_free(a, b)``: the same tracing, stepping by the map's distance-transform bound
  (``StaticGeometry.disc_bound``) wherever it leaves more than 2 cm, FCL nearer the walls;

and turns in place (``gfuzzy.timespace.drive.turn_free``, 16 headings at each start)
with and without the bound's shortcut. Prints the decisions that differ (they must not),
the FCL queries and the CPU seconds of each, and their ratios.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.poses import wrap_angle  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.timespace import drive  # noqa: E402

DEFAULT = ["small-house.yaml", "tb3-arena.yaml", "depot.yaml"]


def motions(geo: StaticGeometry, n: int, seed: int):
    rng = np.random.default_rng(seed)
    xmin, ymin, xmax, ymax = geo.scene.bounds
    dof = geo.robot.dof
    pool = np.c_[rng.uniform(xmin, xmax, 40 * n), rng.uniform(ymin, ymax, 40 * n), rng.uniform(-math.pi, math.pi, 40 * n)]
    starts = pool[geo.valid(pool[:, :dof])][:n]
    step = rng.normal(size=(len(starts), 2))
    step *= (rng.uniform(0.2, 3.0, len(starts)) / np.hypot(*step.T))[:, None]
    ends = np.c_[starts[:, :2] + step, wrap_angle(starts[:, 2] + rng.uniform(-1.0, 1.0, len(starts)))]
    return starts, ends


def timed(fn, items):
    c0 = time.process_time()
    out = [fn(*it) for it in items]
    return out, time.process_time() - c0


def bench(path: Path, n: int, seed: int) -> None:
    scene = load_scene(path)
    geo = StaticGeometry(scene)
    dof = scene.robot.dof
    starts, ends = motions(geo, n, seed)
    pairs = [(list(a[:dof]), list(b[:dof])) for a, b in zip(starts, ends, strict=True)]
    geo.clearance1(pairs[0][0])  # the distance transform, built once
    geo.disc_bound(*pairs[0][0][:2])
    c0 = geo.calls
    full, t_full = timed(lambda a, b: geo.motion_clearance(a, b) >= 0, pairs)
    q_full, c0 = geo.calls - c0, geo.calls
    quick, t_quick = timed(geo.motion_free, pairs)
    q_quick = geo.calls - c0
    differ = sum(f != q for f, q in zip(full, quick, strict=True))
    print(f"{scene.name} ({scene.robot.shape} robot, {len(pairs)} motions, {sum(quick)} free):")
    print(f"  motions: FCL tracing {t_full * 1e3:.0f} ms, {q_full} FCL queries; with the map's bound "
          f"{t_quick * 1e3:.0f} ms, {q_quick} queries; speed-up {t_full / max(t_quick, 1e-9):.2f}x, "
          f"queries {q_full / max(q_quick, 1):.2f}x; decisions differing: {differ}")
    if scene.robot.shape == "disc":
        return
    heads = np.linspace(-math.pi, math.pi, 16, endpoint=False)
    turns = [(float(a[0]), float(a[1]), float(a[2]), float(wrap_angle(h - a[2]))) for a in starts for h in heads]
    bound = geo.disc_bound

    def traced(x, y, h, dh):  # turn_free without the disc bound's shortcut
        geo.disc_bound = lambda *_: -math.inf
        try:
            return drive.turn_free(geo, x, y, h, dh)
        finally:
            del geo.disc_bound

    c0 = geo.calls
    slow, t_slow = timed(traced, turns)
    q_slow, c0 = geo.calls - c0, geo.calls
    fast, t_fast = timed(lambda *a: drive.turn_free(geo, *a), turns)
    q_fast = geo.calls - c0
    assert geo.disc_bound == bound
    differ = sum(s != f for s, f in zip(slow, fast, strict=True))
    print(f"  turns in place ({len(turns)}, {sum(fast)} free): traced {t_slow * 1e3:.0f} ms, {q_slow} queries; "
          f"with the bound {t_fast * 1e3:.0f} ms, {q_fast} queries; speed-up {t_slow / max(t_fast, 1e-9):.2f}x; "
          f"decisions differing: {differ}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", default=[str(ROOT / "scenes" / s) for s in DEFAULT])
    ap.add_argument("--motions", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    for s in args.scenes:
        bench(Path(s), args.motions, args.seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
