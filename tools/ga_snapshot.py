"""Record, and compare against a record, every GA result of the GA benchmark's runs.

Same seed, same result, bit for bit: a speed-up of the GA must not change any answer. This
script runs the synthetic zig-zag corridor runs of ``tools/bench_ga.py``, the GA on
building-floor's corridor (population 50 x 2000 generations, early stop off, the real FCL
and mover clearances of :func:`gfuzzy.planner.stages._clearance_functions`), and ``plan(refine=True)``
on every bundled query, capturing every :class:`~gfuzzy.ga.GAResult` that
``gfuzzy.ga.refine_path`` returns and the final trajectories and reports. ``save`` pickles
them; ``compare`` runs the same again and reports every difference (exit 1 if any).

    python tools/ga_snapshot.py save FILE [--generations G]
    python tools/ga_snapshot.py compare FILE

Typical use: ``save`` on the revision before a change (e.g. in a ``git worktree`` of it),
``compare`` after.
"""

from __future__ import annotations

import argparse
import pickle
import sys
from pathlib import Path

import numpy as np

import gfuzzy.ga

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from tools import bench_ga  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
GA_FIELDS = ("path", "chromosome", "fitness_history", "generations", "improved", "fitness_before",
             "fitness_after", "length_before", "length_after", "smoothness_before", "smoothness_after",
             "clearance_before", "clearance_after", "trajectory")  # fmt: skip
CODING_FIELDS = ("start", "goal", "knots", "normals", "steps", "levels")


def ga_record(res) -> dict:
    """The comparable fields of a GAResult (its coding's arrays included)."""
    rec = {k: getattr(res, k) for k in GA_FIELDS}
    if res.coding is not None:
        rec.update({f"coding.{k}": getattr(res.coding, k) for k in CODING_FIELDS})
    return rec


def _strip_seconds(value):
    """A report dict without its wall-clock figures (they differ run to run)."""
    if isinstance(value, dict):
        return {k: _strip_seconds(v) for k, v in value.items() if not k.endswith("seconds")}
    return value


def collect(generations: int, seed: int = 0) -> dict:
    """Every recorded result by name."""
    out: dict = {}
    path, times, mc = bench_ga.scenario(seed)
    for name, tt, mover, patience in (("static", None, None, None), ("mover", times, mc, None),
                                      ("mover-patience", times, mc, 200)):  # fmt: skip
        opts = gfuzzy.ga.GAOptions(generations=generations, patience=patience)
        res = gfuzzy.ga.refine_path(path, tt, bench_ga.ROBOT, bench_ga.static_clearance, mover, opts, seed=seed)
        out[f"zigzag/{name}"] = ga_record(res)

    from gfuzzy.planner.planner import Planner, PlanOptions
    from gfuzzy.planner.stages import StageContext, _clearance_functions, _dedupe
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.scene.scene import load_scene

    def setup(p):
        scene = load_scene(p)
        return scene, Planner(scene, load_roadmap(ROOT / "roadmaps" / f"{scene.name}.json", scene))

    scene, planner = setup(ROOT / "scenes" / "building-floor.yaml")
    q = scene.queries[0]
    res = planner.plan(q.start, q.goal, q.t0)
    ctx = StageContext(planner.scene, planner.geometry)
    _, static, segment, mover = _clearance_functions(ctx, _dedupe(res.trajectory.poses))
    for knots in (12, 24):
        ga = gfuzzy.ga.refine_path(
            res.trajectory.poses[:, :2], res.trajectory.times, scene.robot.circumradius, static, mover,
            gfuzzy.ga.GAOptions(n_knots=knots, generations=generations, patience=None), seed=seed,
            static_segment=segment,
        )  # fmt: skip
        out[f"building-floor/corridor-{knots}"] = ga_record(ga)

    # every GAResult the planner's stages see, through a recording wrapper
    seen: list = []
    original = gfuzzy.ga.refine_path

    def recording(*args, **kwargs):
        r = original(*args, **kwargs)
        seen.append(ga_record(r))
        return r

    gfuzzy.ga.refine_path = recording
    try:
        for p in sorted((ROOT / "scenes").glob("*.yaml")):
            scene, planner = setup(p)
            for q in scene.queries:
                seen.clear()
                r = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=seed))
                rec = {"status": r.status.value, "ga": list(seen)}
                if r.solved:
                    rec["waypoints"] = r.trajectory.waypoints
                    rec["refine"] = _strip_seconds(r.refine_report.to_dict() if r.refine_report else None)
                out[f"plan/{scene.name}/{q.name}"] = rec
    finally:
        gfuzzy.ga.refine_path = original
    return out


def differences(a, b, where: str = "") -> list[str]:
    """Where ``a`` and ``b`` differ, exactly (NaN equals NaN)."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{where}/{k}: only in one" for k in sorted(set(a) ^ set(b), key=str)]
        for k in a:
            if k in b:
                out += differences(a[k], b[k], f"{where}/{k}")
        return out
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return [f"{where}: {len(a)} vs {len(b)} items"]
        return [d for i, (x, y) in enumerate(zip(a, b, strict=True)) for d in differences(x, y, f"{where}[{i}]")]
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        x, y = np.asarray(a), np.asarray(b)
        same = x.shape == y.shape and x.dtype.kind == y.dtype.kind
        same = same and np.array_equal(x, y, equal_nan=x.dtype.kind == "f")
        return [] if same else [f"{where}: arrays differ"]
    if a is None or b is None:
        return [] if a is b else [f"{where}: {a!r} vs {b!r}"]
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return []
    return [] if a == b and type(a) is type(b) else [f"{where}: {a!r} vs {b!r}"]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("action", choices=("save", "compare"))
    ap.add_argument("file", type=Path)
    ap.add_argument("--generations", type=int, default=2000)
    args = ap.parse_args(argv)
    if args.action == "save":
        data = {"generations": args.generations, "results": collect(args.generations)}
        args.file.write_bytes(pickle.dumps(data))
        print(f"saved {len(data['results'])} records to {args.file}")
        return 0
    saved = pickle.loads(args.file.read_bytes())
    now = collect(saved["generations"])
    diffs = differences(saved["results"], now)
    for d in diffs:
        print(d)
    print(f"{len(saved['results'])} records, {len(diffs)} differences")
    return 1 if diffs else 0


if __name__ == "__main__":
    sys.exit(main())
