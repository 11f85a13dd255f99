"""Benchmark of the GA refinement (gfuzzy.ga.refine_path) on a synthetic zig-zag corridor.

Prints the time of population 50 x 2000 generations with the early stop disabled, and with
the default patience, on a corridor with discs, boxes and one moving disc, with cheap numpy
clearance callables; plus before/after length, turning, minimum clearance and cost (lower is
better). The static run is untimed (times=None); the mover runs reuse the input's timing
(speed 1) and so also keep the refined path nowhere faster than the input.

Then, on the bundled scenes (with their bundled roadmaps): population 50 x 2000
generations with the early stop off on building-floor's corridor with the real FCL and
mover clearances (target: <= 2 s), and the before/after figures of `plan(refine=True)`
for every bundled query.

    python tools/bench_ga.py [--seed S] [--generations G] [--repeat R] [--skip-scenes]
                             [--reference REV]

``--reference REV`` also runs the GA of git revision REV (its single-file ``gfuzzy/ga.py``,
e.g. ``1a8460d``, before the GA package and its caches, or its ``gfuzzy/ga/`` package, e.g.
``747cfd3``, before the compiled kernels) on the same runs, in the same process, and prints
its time next to the current one, and whether both results are the same (path, chromosome,
fitness history, figures). Both use the current clearance callables; for the whole change
(callables included) on every bundled query, see ``tools/ga_snapshot.py``.
"""

from __future__ import annotations

import argparse
import importlib.util
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import gfuzzy.ga as current
from gfuzzy.ga import fitness_parts

ROBOT = 0.25
BOUNDS = (0.0, 0.0, 20.0, 4.0)
DISCS = np.array([[4.0, 1.2, 0.6], [9.0, 2.8, 0.7], [15.0, 1.5, 0.6]])
BOXES = np.array([[12.0, 0.6, 1.0, 1.2], [6.5, 3.4, 1.2, 1.2]])  # cx, cy, w, h (axis-aligned)
MOVER = dict(x=17.0, y0=0.5, y1=3.5, speed=0.8, radius=0.3)


def static_clearance(xy):
    """Clearance of the robot disc from the discs, boxes and bounds, (k, 2) -> (k,)."""
    x, y = xy[:, 0], xy[:, 1]
    xmin, ymin, xmax, ymax = BOUNDS
    c = np.minimum.reduce([x - xmin, xmax - x, y - ymin, ymax - y])
    d = np.hypot(x[:, None] - DISCS[:, 0], y[:, None] - DISCS[:, 1]) - DISCS[:, 2]
    q = np.abs(xy[:, None, :] - BOXES[:, :2]) - 0.5 * BOXES[:, 2:]
    box = np.hypot(np.maximum(q[..., 0], 0), np.maximum(q[..., 1], 0)) + np.minimum(q.max(-1), 0)
    return np.minimum(c, np.minimum(d.min(1), box.min(1))) - ROBOT


def mover_xy(t, phase):
    """A disc bouncing along x = 17 between y0 and y1."""
    span = MOVER["y1"] - MOVER["y0"]
    s = (MOVER["speed"] * t + phase) % (2 * span)
    y = MOVER["y0"] + np.where(s < span, s, 2 * span - s)
    return np.column_stack([np.full_like(y, MOVER["x"]), y])


def make_mover_clearance(phase):
    def mover_clearance(xy, t):
        m = mover_xy(t, phase)
        return np.hypot(*(xy - m).T) - MOVER["radius"] - ROBOT

    return mover_clearance


def zigzag(rng, n=12):
    """A roadmap-like path: random free vertices, left to right, with free segments."""
    pts = [np.array([0.6, 2.0])]
    for x in np.linspace(1.8, 18.2, n):
        for _ in range(1000):
            p = np.array([x + rng.uniform(-0.4, 0.4), rng.uniform(0.4, 3.6)])
            if fitness_parts([np.array([pts[-1], p])], ROBOT, static_clearance).feasible[0]:
                pts.append(p)
                break
    goal = np.array([19.4, 2.0])
    pts.append(goal)
    path = np.array(pts)
    if not fitness_parts([path], ROBOT, static_clearance).feasible[0]:
        return None
    return path


def scenario(seed):
    rng = np.random.default_rng(seed)
    while (path := zigzag(rng)) is None:
        pass
    times = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(path, axis=0).T))])  # speed 1
    for phase in np.linspace(0, 6, 61):
        mc = make_mover_clearance(phase)
        if fitness_parts(
            [path], ROBOT, static_clearance, mc, reference_path=path, reference_times=times
        ).feasible[0]:
            return path, times, mc
    raise RuntimeError("no mover phase leaves the input feasible")


def load_reference(rev: str):
    """The GA of git revision ``rev``, imported as ``gfuzzy._ga_reference``: its single-file
    ``gfuzzy/ga.py`` (e.g. ``1a8460d``) or its ``gfuzzy/ga/`` package (e.g. ``747cfd3``). Its
    relative imports of the rest of gfuzzy resolve in the current package."""
    root = Path(__file__).resolve().parent.parent

    def show(path: str) -> str:
        return subprocess.run(
            ["git", "show", f"{rev}:{path}"], cwd=root, capture_output=True, text=True, check=True
        ).stdout

    def module(name: str, src: str, origin: str, package: bool = False):
        spec = importlib.util.spec_from_loader(name, loader=None, is_package=package)
        mod = importlib.util.module_from_spec(spec)
        mod.__package__ = name if package else name.rpartition(".")[0]
        sys.modules[name] = mod  # dataclasses look their module up there
        exec(compile(src, f"{rev}:{origin}", "exec"), mod.__dict__)
        return mod

    files = subprocess.run(
        ["git", "ls-tree", "--name-only", rev, "gfuzzy/ga/"], cwd=root, capture_output=True, text=True, check=True
    ).stdout.split()
    if not files:
        return module("gfuzzy._ga_reference", show("gfuzzy/ga.py"), "gfuzzy/ga.py")
    names = {Path(f).stem for f in files if f.endswith(".py")}
    pkg = "gfuzzy._ga_reference"
    spec = importlib.util.spec_from_loader(pkg, loader=None, is_package=True)
    mod = importlib.util.module_from_spec(spec)
    mod.__path__ = []
    sys.modules[pkg] = mod
    # each module imports only the ones before it (docs/ga.md); unknown ones go last
    order = ["options", "coding", "fitness", "kernels", "operators", "lattice", "refine"]
    for name in [n for n in order if n in names] + sorted(names - set(order) - {"__init__"}):
        setattr(mod, name, module(f"{pkg}.{name}", show(f"gfuzzy/ga/{name}.py"), f"gfuzzy/ga/{name}.py"))
    exec(compile(show("gfuzzy/ga/__init__.py"), f"{rev}:gfuzzy/ga/__init__.py", "exec"), mod.__dict__)
    return mod


def same_result(a, b) -> bool:
    """Both GA results are the same, bit for bit (timings aside)."""
    arrays = ("path", "chromosome", "fitness_history")
    scalars = ("generations", "improved", "fitness_before", "fitness_after", "length_before",
               "length_after", "smoothness_before", "smoothness_after", "clearance_before",
               "clearance_after")  # fmt: skip
    return all(np.array_equal(getattr(a, k), getattr(b, k)) for k in arrays) and all(
        getattr(a, k) == getattr(b, k) or (getattr(a, k) != getattr(a, k) and getattr(b, k) != getattr(b, k))
        for k in scalars
    )  # fmt: skip


def timed_runs(module, repeat: int, call: tuple, generations: int, patience, seed: int):
    """(result, best wall s, best cpu s) of ``repeat`` calls of ``module.refine_path(*call)``
    with the module's own GAOptions."""
    wall = cpu = None
    opts = module.GAOptions(generations=generations, patience=patience)
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        res = module.refine_path(*call, opts, seed=seed)
        w, c = time.perf_counter() - t0, time.process_time() - c0
        wall, cpu = (w, c) if wall is None else (min(wall, w), min(cpu, c))
    return res, wall, cpu


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--generations", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--skip-scenes", action="store_true")
    ap.add_argument("--reference", metavar="REV", help="also time the GA of this git revision")
    args = ap.parse_args(argv)
    ref = load_reference(args.reference) if args.reference else None
    path, times, mc = scenario(args.seed)
    print(
        f"zig-zag corridor: {len(path)} vertices, robot radius {ROBOT}, 3 discs, 2 boxes, 1 mover"
    )
    print(
        f"{'run':<30}{'wall s':>7}{'cpu s':>7}{'gens':>6}  {'length':>15}  {'turning rad':>13}  "
        f"{'min clear':>13}  {'cost':>13}"
    )
    runs = [
        ("static, patience off", None, None, None),
        ("static + mover, patience off", times, mc, None),
        ("static + mover, patience 200", times, mc, 200),
    ]
    for name, tt, mover, patience in runs:
        call = (path, tt, ROBOT, static_clearance, mover)
        res, wall, cpu = timed_runs(current, args.repeat, call, args.generations, patience, args.seed)
        print(
            f"{name:<30}{wall:7.2f}{cpu:7.2f}{res.generations:6d}  "
            f"{res.length_before:6.2f} -> {res.length_after:5.2f}  "
            f"{res.smoothness_before:5.2f} -> {res.smoothness_after:4.2f}  "
            f"{res.clearance_before:5.3f} -> {res.clearance_after:5.3f}  "
            f"{res.fitness_before:5.3f} -> {res.fitness_after:5.3f}"
        )
        if ref is not None:
            r_res, r_wall, r_cpu = timed_runs(
                ref, args.repeat, call, args.generations, patience, args.seed
            )
            print(
                f"{'  reference ' + args.reference:<30}{r_wall:7.2f}{r_cpu:7.2f}"
                f"{r_res.generations:6d}  same result: {same_result(res, r_res)}"
            )
    print("times: best of --repeat runs with the same seed")
    if not args.skip_scenes:
        bundled(args.seed, args.generations, ref, args.reference, args.repeat)


FIGURES = (("length", ".2f"), ("smoothness", ".2f"), ("min_clearance", ".3f"), ("duration", ".2f"))


def _pair(before: dict, after: dict, key: str, fmt: str) -> str:
    if key not in before:
        return f"{'-':>15}"
    return f"{format(before[key], fmt):>6} -> {format(after[key], fmt):<6}"


def bundled(seed: int, generations: int, ref=None, rev: str | None = None, repeat: int = 1) -> None:
    from gfuzzy.planner.planner import Planner, PlanOptions
    from gfuzzy.planner.stages import _clearance_functions, _dedupe
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.scene.scene import load_scene

    root = Path(__file__).resolve().parent.parent
    scenes = sorted((root / "scenes").glob("*.yaml"))

    def setup(path):
        scene = load_scene(path)
        return scene, Planner(scene, load_roadmap(root / "roadmaps" / f"{scene.name}.json", scene))

    scene, planner = setup(root / "scenes" / "building-floor.yaml")
    q = scene.queries[0]
    res = planner.plan(q.start, q.goal, q.t0)
    _, static, segment, mover = _clearance_functions(planner, _dedupe(res.trajectory.poses))
    def corridor(module):
        return module.refine_path(
            res.trajectory.poses[:, :2], res.trajectory.times, scene.robot.circumradius, static, mover,
            module.GAOptions(generations=generations, patience=None), seed=seed, static_segment=segment,
        )  # fmt: skip

    def timed(module):
        """The result and the wall times of ``repeat`` runs."""
        walls = []
        for _ in range(repeat):
            t0 = time.perf_counter()
            out = corridor(module)
            walls.append(time.perf_counter() - t0)
        return out, walls

    def spread(walls) -> str:
        return f"{min(walls):.2f} s" if len(walls) == 1 else f"{min(walls):.2f}-{max(walls):.2f} s ({len(walls)} runs)"

    ga, walls = timed(current)
    print(
        f"\nbuilding-floor corridor, population 50 x {ga.generations} generations, patience off: "
        f"{spread(walls)} (improved: {ga.improved}, best cost {ga.fitness_history[-1]:.4g})"
    )
    if ref is not None:
        r_ga, r_walls = timed(ref)
        print(f"  reference {rev}: {spread(r_walls)}, same result: {same_result(ga, r_ga)}")
    print(
        f"\n{'scene/query':<36}{'applied':>8}{'ms':>7}  {'length':>15}  {'turning rad':>14}  "
        f"{'min clear':>15}  {'duration':>15}  note"
    )
    for path in scenes:
        scene, planner = setup(path)
        for q in scene.queries:
            t0 = time.perf_counter()
            res = planner.plan(q.start, q.goal, q.t0, PlanOptions(refine=True, seed=seed))
            ms = (time.perf_counter() - t0) * 1000
            if not res.solved:
                print(f"{scene.name + '/' + q.name:<36}{'-':>8}{ms:7.0f}  ({res.status.value})")
                continue
            info = res.refine_report.to_dict()
            b = info.get("before", {})
            a = info.get("after", b)

            cols = "  ".join(_pair(b, a, key, fmt) for key, fmt in FIGURES)
            print(f"{scene.name + '/' + q.name:<36}{str(info['applied']):>8}{ms:7.0f}  {cols}  {info.get('reason', '')}")


if __name__ == "__main__":
    main()
