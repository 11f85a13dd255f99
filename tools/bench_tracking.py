"""Benchmark of unicycle path tracking under three speed profiles.

For each path (synthetic S-curve, zig-zag, corner, hairpin, arc; plus the paths
planned on the bundled scenes when gfuzzy.planner.planner and a roadmap file are there)
a unicycle tracks it with adaptive pure pursuit under:

* constant vmax (ramps at both ends only),
* the fuzzy speed limit with the expert rules (gfuzzy/data/rules_expert.txt),
* the fuzzy speed limit with the learned rules (gfuzzy/data/rules_learned.txt).

Prints max and mean lateral error, max commanded |omega|, bound violations and
traversal time, and writes out/bench_tracking.png (paths, speed profiles, and a
bar chart of the figures).

A differential drive's plan (the bundled ``kinematics: unicycle`` scenes) turns in place at
its corners: pure pursuit does not apply. Its section plans each query with and without the
speed layer and tracks the timed plan with gfuzzy.learning.drivetracking (a trajectory
tracker driving v and w within the robot's bounds): position, lateral and heading errors,
the plan's own bound violations, arrival.

    python tools/bench_tracking.py [--no-scenes] [--out out/bench_tracking.png]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from gfuzzy.fuzzy import fuzzy
from gfuzzy.learning import tracking
from gfuzzy.status import Status

ROOT = Path(__file__).resolve().parent.parent
SYNTHETIC = ("s_curve", "zigzag", "corner", "hairpin", "arc")


def scene_paths(root: Path = ROOT, time_limit: float = 20.0) -> list[tuple[str, np.ndarray]]:
    """Paths planned on ``scenes/*.yaml``, one per query; empty when the planner,
    a scene's roadmap file or a solution is missing (this part is optional)."""
    out: list[tuple[str, np.ndarray]] = []
    files = sorted((root / "scenes").glob("*.yaml"))
    if not files:
        return out
    try:
        from gfuzzy.planner.planner import PlanOptions, plan
        from gfuzzy.roadmap.roadmap import default_roadmap_path, load_roadmap
        from gfuzzy.scene.scene import load_scene
    except Exception as exc:  # the planner is another stage's work; skip quietly
        print(f"(scene paths skipped: {type(exc).__name__}: {exc})")
        return out
    for file in files:
        try:
            scene = load_scene(file)
            if scene.robot.unicycle:  # turns in place: drive_rows() tracks it in time
                continue
            rm_file = default_roadmap_path(scene, root / "roadmaps")
            if not rm_file.exists():
                print(f"(scene {scene.name}: no roadmap file {rm_file.name}, skipped)")
                continue
            roadmap = load_roadmap(rm_file, scene)
            for q in scene.queries:
                res = plan(
                    scene, roadmap, q.start, q.goal, q.t0, PlanOptions(time_limit=time_limit)
                )
                if res.trajectory is None:
                    continue
                xy = np.asarray(res.trajectory.poses)[:, :2]
                keep = np.concatenate(([True], np.linalg.norm(np.diff(xy, axis=0), axis=1) > 1e-9))
                if keep.sum() >= 2:
                    out.append((f"{scene.name}/{q.name}", xy[keep]))
        except Exception as exc:
            print(f"(scene {file.name} skipped: {type(exc).__name__}: {exc})")
    return out


def drive_rows(root: Path = ROOT, time_limit: float = 60.0) -> list[tuple[str, str, object, np.ndarray]]:
    """(scene/query, plan, robot, rows) of every bundled differential drive's query, planned
    by the search alone ("search") and with the speed layer ("layered" when it applied to the
    whole path, "part" when some legs keep the search's pace: their amax is not the layer's)."""
    from gfuzzy.planner.planner import PlanOptions, plan
    from gfuzzy.roadmap.roadmap import default_roadmap_path, load_roadmap
    from gfuzzy.scene.scene import load_scene

    out = []
    for file in sorted((root / "scenes").glob("*.yaml")):
        scene = load_scene(file)
        rm_file = default_roadmap_path(scene, root / "roadmaps")
        if not scene.robot.unicycle or not rm_file.exists():
            continue
        roadmap = load_roadmap(rm_file, scene)
        for q in scene.queries:
            for label, layer in (("search", False), ("layered", True)):
                res = plan(scene, roadmap, q.start, q.goal, q.t0, PlanOptions(time_limit=time_limit, speed_layer=layer))
                if res.trajectory is None or (layer and not res.speed_report.applied):
                    why = res.speed_report.reason if layer and res.speed_report else res.status
                    print(f"({scene.name}/{q.name} {label}: not tracked: {why})")
                    continue
                if layer and not res.speed_report.whole:
                    label = "part"
                out.append((f"{scene.name}/{q.name}", label, scene.robot, res.trajectory.waypoints))
    return out


def drive_section() -> None:
    """Track the differential drives' plans and print one row per plan."""
    from gfuzzy.learning.drivetracking import DriveGains, track_drive
    from gfuzzy.settings import AMAX_PER_VMAX

    print(f"\ndifferential drive: a trajectory tracker (Kanayama) on the timed plan, dt {DriveGains().dt} s")
    head = (f"{'query':<36}{'plan':<9}{'plan s':>7}{'arrive':>8}{'max pos':>8}{'max lat':>8}{'mean lat':>9}"
            f"{'max head':>9}{'plan viol':>10}{'cmd viol':>9}")  # fmt: skip
    print(head)
    print("-" * len(head))
    for name, label, robot, rows in drive_rows():
        amax = robot.amax if robot.amax is not None else AMAX_PER_VMAX * robot.vmax
        limits = tracking.UnicycleLimits(vmax=robot.vmax, omega_max=robot.turn_rate, amax=amax,
                                         alpha_max=amax / robot.circumradius)  # fmt: skip
        r = track_drive(rows, limits, reverse=robot.reverse)
        arrive = f"{r.arrival_time:8.2f}" if r.status is Status.SOLVED else "   never"
        print(
            f"{name:<36}{label:<9}{rows[-1, 0] - rows[0, 0]:>7.2f}{arrive}{r.max_position_error:>8.3f}"
            f"{r.max_lateral_error:>8.3f}{r.mean_lateral_error:>9.4f}{r.max_heading_error:>9.3f}"
            f"{r.plan_violations.steps:>10d}{r.violations.steps:>9d}"
        )


def run(paths, limits, profiles):
    rows = []
    for name, p in paths:
        for label, make in profiles:
            prof = make(p)
            t0 = time.perf_counter()
            r = tracking.track(p, prof, limits)
            ms = 1e3 * (time.perf_counter() - t0)
            rows.append(dict(path=name, profile=label, result=r, profile_sv=prof, ms=ms))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--no-scenes", action="store_true")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench_tracking.png")
    args = ap.parse_args()

    limits = tracking.UnicycleLimits()
    synth = tracking.synthetic_paths()
    paths = [(k, synth[k]) for k in SYNTHETIC]
    if not args.no_scenes:
        paths += scene_paths()
    expert, learned = fuzzy.expert_rules(), fuzzy.learned_rules()
    profiles = [
        ("constant", lambda p: tracking.constant_profile(p, limits.vmax, limits.amax)),
        ("expert", lambda p: fuzzy.speed_limit(p, limits.vmax, limits.amax, expert)),
        ("learned", lambda p: fuzzy.speed_limit(p, limits.vmax, limits.amax, learned)),
    ]
    rows = run(paths, limits, profiles)

    print(
        f"limits: vmax {limits.vmax} m/s, omega_max {limits.omega_max} rad/s, "
        f"amax {limits.amax} m/s^2, alpha_max {limits.alpha_max} rad/s^2; dt {tracking.TrackingOptions().dt} s"
    )
    head = f"{'path':<35}{'profile':<10}{'length':>7}{'time s':>8}{'max err':>9}{'mean err':>9}{'max|w|cmd':>10}{'viol':>6}{'sim ms':>8}"
    print(head)
    print("-" * len(head))
    for row in rows:
        r = row["result"]
        length = row["profile_sv"][0][-1]
        flag = "" if r.status is Status.SOLVED else " (timeout)"
        print(
            f"{row['path']:<34} {row['profile']:<10}{length:>7.2f}{r.traversal_time:>8.2f}"
            f"{r.max_lateral_error:>9.3f}{r.mean_lateral_error:>9.3f}{r.max_abs_omega_cmd:>10.2f}"
            f"{r.violations.steps:>6d}{row['ms']:>8.1f}{flag}"
        )
    print("-" * len(head))
    for label, _ in profiles:
        rs = [row["result"] for row in rows if row["profile"] == label]
        print(
            f"{'mean':<35}{label:<10}{'':>7}{np.mean([r.traversal_time for r in rs]):>8.2f}"
            f"{np.mean([r.max_lateral_error for r in rs]):>9.3f}{np.mean([r.mean_lateral_error for r in rs]):>9.3f}"
            f"{np.mean([r.max_abs_omega_cmd for r in rs]):>10.2f}{np.mean([r.violations.steps for r in rs]):>6.1f}"
        )
    plot(rows, paths, [label for label, _ in profiles], args.out)
    print(f"\nwrote {args.out}")
    if not args.no_scenes:
        drive_section()


def plot(rows, paths, labels, out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"constant": "tab:red", "expert": "tab:blue", "learned": "tab:green"}
    show = [name for name, _ in paths][:5]
    fig, axes = plt.subplots(3, len(show), figsize=(3.6 * len(show), 9.5), squeeze=False)
    for col, name in enumerate(show):
        p = dict(paths)[name]
        ax = axes[0, col]
        ax.plot(p[:, 0], p[:, 1], "k-", lw=2.5, alpha=0.3, label="path")
        for row in rows:
            if row["path"] == name:
                xy = row["result"].xy
                ax.plot(
                    xy[:, 0],
                    xy[:, 1],
                    "-",
                    lw=1,
                    color=colours.get(row["profile"]),
                    label=row["profile"],
                )
        ax.set_aspect("equal")
        ax.set_title(name)
        if col == 0:
            ax.legend(fontsize=7)
        ax = axes[1, col]
        for row in rows:
            if row["path"] == name:
                s, v = row["profile_sv"]
                ax.plot(s, v, color=colours.get(row["profile"]), lw=1.2)
        ax.set_xlabel("s [m]")
        if col == 0:
            ax.set_ylabel("speed limit [m/s]")
        ax = axes[2, col]
        for row in rows:
            if row["path"] == name:
                r = row["result"]
                ax.plot(r.t, r.lateral_error, color=colours.get(row["profile"]), lw=1)
        ax.set_xlabel("t [s]")
        if col == 0:
            ax.set_ylabel("lateral error [m]")
    fig.tight_layout()
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=90)
    plt.close(fig)


if __name__ == "__main__":
    main()
