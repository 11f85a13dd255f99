"""The ``gfuzzy`` command line (README.md and docs/formats.md).

Exit statuses: 0 success, 1 a valid request with a negative answer (no path, invalid
trajectory, missed expectation), 2 bad input. Bad input prints exactly one line on stderr
naming the file and the place in it, and writes nothing.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
from dataclasses import replace
from pathlib import Path

from .errors import InputError, LimitError, SceneError

__all__ = ["main"]

EXIT_OK, EXIT_NO, EXIT_BAD = 0, 1, 2


class BadInput(Exception):
    """A bad command line or file; its message is the one line printed."""


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2 (argparse prints usage + error)
        raise BadInput(f"{self.prog}: {message} (see {self.prog} --help)")


def _say(msg: str, stream=None) -> None:
    stream = stream or sys.stderr
    stream.write(msg + "\n")
    stream.flush()


def _progress(label: str):
    """A progress callback that draws on stderr only when it is a terminal."""
    if not sys.stderr.isatty():
        return None

    def cb(count: int, total: int) -> None:
        sys.stderr.write(f"\r{label}: {count}/{total}")
        sys.stderr.flush()
        if count >= total:
            sys.stderr.write("\n")

    return cb


# ------------------------------------------------------------------ shared steps


def _load_scene(path):
    from .scene import load_scene

    return load_scene(path)


def _roadmap_for(scene, args, quiet=False):
    """The roadmap a plan/regress run uses: --roadmap, -n/--seed, or the default file."""
    from .roadmap import RoadmapOptions, build_roadmap, load_roadmap

    if getattr(args, "roadmap", None):
        return load_roadmap(args.roadmap, scene)
    if args.vertices is not None or args.seed is not None:
        try:
            opts = RoadmapOptions(
                vertices=args.vertices if args.vertices is not None else RoadmapOptions.vertices,
                seed=args.seed if args.seed is not None else RoadmapOptions.seed,
            )
        except InputError as exc:
            raise BadInput(f"-n/--seed: {exc}") from None
        saved = _default_roadmap(scene, quiet=True)
        if saved is not None and saved.options == opts:  # the saved file is this very roadmap
            return saved
        return build_roadmap(scene, opts, progress=_progress("roadmap"))
    found = _default_roadmap(scene, quiet)
    if found is not None:
        return found
    same_shapes = _roadmap_of_other_clearance(scene)
    if same_shapes is not None:  # --clearance: the saved roadmap's options, the new clearance
        if not quiet:
            _say(
                f"note: robot.clearance={scene.robot.clearance:g} changes the roadmap; building one "
                f"like the saved one ({same_shapes.vertices} vertices, seed {same_shapes.seed})"
            )
        return build_roadmap(scene, same_shapes, progress=_progress("roadmap"))
    if not quiet:
        _say(
            f"note: no roadmap file for {scene.name!r}; building one with "
            f"{RoadmapOptions.vertices} vertices (save one with `gfuzzy roadmap`)"
        )
    return build_roadmap(scene, RoadmapOptions(), progress=_progress("roadmap"))


def _check_roadmap_flags(args) -> None:
    """Refuse bad -n/--seed values up front, as :func:`_roadmap_for` would later."""
    from .roadmap import RoadmapOptions

    if args.vertices is None and args.seed is None:
        return
    try:
        RoadmapOptions(
            vertices=args.vertices if args.vertices is not None else RoadmapOptions.vertices,
            seed=args.seed if args.seed is not None else RoadmapOptions.seed,
        )
    except InputError as exc:
        raise BadInput(f"-n/--seed: {exc}") from None


def _roadmap_of_other_clearance(scene):
    """The options of a saved roadmap built for the same shapes with another static
    clearance (a ``--clearance`` override), or None."""
    from .roadmap import default_roadmap_path, load_roadmap

    if not scene.shape_hash:
        return None
    scene_dir = Path(scene.source).resolve().parent
    for path in (default_roadmap_path(scene), default_roadmap_path(scene, scene_dir.parent / "roadmaps")):
        try:
            rm = load_roadmap(path) if path.is_file() else None
        except SceneError:
            continue
        if rm is not None and rm.scene_hash == scene.shape_hash:
            return rm.options
    return None


def _default_roadmap(scene, quiet=False):
    """The roadmap file built for ``scene`` in roadmaps/ (here, or beside the scene's
    folder), if there is one that matches it."""
    from .roadmap import default_roadmap_path, load_roadmap

    scene_dir = Path(scene.source).resolve().parent
    for path in (default_roadmap_path(scene), default_roadmap_path(scene, scene_dir.parent / "roadmaps")):
        if path.is_file():
            try:
                return load_roadmap(path, scene)
            except SceneError as exc:
                if not quiet and not _clearance_only(path, scene):
                    _say(f"note: not using {path}: {exc.message}")
    return None


def _apply_overrides(scene, args):
    """The scene with the command line's robot overrides (``--clearance``,
    ``--mover-clearance``) applied; the scene itself when there are none.

    A new static clearance changes the scene's static hash, so a saved roadmap built
    without it no longer matches and another is built (said on stderr).
    """
    clearance = getattr(args, "clearance", None)
    mover_clearance = getattr(args, "mover_clearance", None)
    if clearance is None and mover_clearance is None:
        return scene
    for flag, value in (("--clearance", clearance), ("--mover-clearance", mover_clearance)):
        if value is not None and not (math.isfinite(value) and value >= 0):
            raise BadInput(f"{flag}: must be a non-negative finite number, got {value:g}")
    try:
        return scene.with_clearances(clearance, mover_clearance)
    except InputError as exc:
        raise BadInput(f"--clearance/--mover-clearance: {exc}") from None


def _clearance_only(path, scene) -> bool:
    """True when the roadmap file at ``path`` differs from ``scene`` only by the static
    clearance (said once, by :func:`_roadmap_for`)."""
    from .roadmap import load_roadmap

    try:
        return bool(scene.shape_hash) and load_roadmap(path).scene_hash == scene.shape_hash
    except SceneError:
        return False


def _plan_options(args):
    from .planner import PlanOptions

    try:
        return PlanOptions(
            dt=args.dt,
            refine=args.refine,
            speed_layer=args.speed_layer,
            time_limit=args.time_limit,
            horizon=args.horizon,
            weight=args.weight,
            stretch=args.stretch,
            seed=args.ga_seed,
        )
    except ValueError as exc:  # PlanOptions' checks (named after the command: plan shares these flags with regress)
        raise BadInput(f"gfuzzy {getattr(args, 'command', None) or 'plan'}: {exc}") from None


def _pose(values, dof, flag):
    if values is None:
        return None
    want = "x y" if dof == 2 else "x y heading"
    if len(values) != dof:
        raise BadInput(f"{flag}: expected {dof} numbers ({want}) for this robot, got {len(values)}")
    try:
        out = [float(v) for v in values]
    except ValueError:
        raise BadInput(f"{flag}: expected numbers ({want}), got {' '.join(values)}") from None
    if not all(math.isfinite(v) for v in out):
        raise BadInput(f"{flag}: numbers must be finite")
    return out


def _out_path(path, allowed):
    suffix = Path(path).suffix.lower()
    if suffix not in allowed:
        raise BadInput(f"{path}: output must end in {' or '.join(allowed)}")
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise BadInput(f"{path}: folder {parent} does not exist")
    return Path(path)


# ------------------------------------------------------------------ commands


def cmd_roadmap(args) -> int:
    from .roadmap import RoadmapOptions, build_roadmap, default_roadmap_path

    scene = _load_scene(args.scene)
    out = _out_path(args.output, (".json",)) if args.output else default_roadmap_path(scene)
    try:
        opts = RoadmapOptions(vertices=args.vertices, seed=args.seed, neighbors=args.neighbors)
    except InputError as exc:
        raise BadInput(f"gfuzzy roadmap: {exc}") from None
    rm = build_roadmap(scene, opts, progress=_progress("roadmap"))
    rm.save(out)
    info = rm.info
    _say(
        f"{out}: {len(rm.vertices)} vertices, {len(rm.edges)} edges, "
        f"{info['components']} component(s), {info['seconds']:.2f} s, "
        f"{info['validity_calls'] + info['certify_calls']} collision checks",
        sys.stdout,
    )
    return EXIT_OK


def _query_from_args(scene, args):
    from .scene import Query

    dof = scene.robot.dof
    start = _pose(args.start, dof, "--start")
    goal = _pose(args.goal, dof, "--goal")
    if args.query and (start or goal):
        raise BadInput("gfuzzy plan: give either --query or --start/--goal, not both")
    if start is not None or goal is not None:
        if start is None or goal is None:
            raise BadInput("gfuzzy plan: --start and --goal go together")
        t0 = args.t0 if args.t0 is not None else 0.0
        if not math.isfinite(t0):
            raise BadInput("--t0: must be finite")
        return Query("cli", tuple(start), tuple(goal), t0, hold=_hold(args, 0.0))
    if args.t0 is not None:
        raise BadInput("gfuzzy plan: --t0 goes with --start/--goal (a scene query has its own t0)")
    if args.query:
        try:
            q = scene.query(args.query)
        except KeyError as exc:
            raise BadInput(f"{scene.source}: queries: {exc.args[0]}") from None
    elif not scene.queries:
        raise BadInput(f"{scene.source}: queries: the scene has no queries; give --start and --goal")
    else:
        q = scene.queries[0]
    hold = _hold(args, q.hold)
    return q if hold == q.hold else replace(q, hold=hold)


def _hold(args, default: float) -> float:
    """``--hold`` (seconds parked at the goal), or the query's own."""
    hold = getattr(args, "hold", None)
    if hold is None:
        return default
    if not (math.isfinite(hold) and hold >= 0):
        raise BadInput(f"--hold: must be a non-negative finite number, got {hold:g}")
    return float(hold)


def cmd_plan(args) -> int:
    from .geometry import StaticGeometry
    from .planner import Planner, PlanResult, Status, query_problem

    scene = _apply_overrides(_load_scene(args.scene), args)
    query = _query_from_args(scene, args)
    out = _out_path(args.output, (".json", ".csv")) if args.output else None
    options = _plan_options(args)
    problem = query_problem(StaticGeometry(scene), query.start, query.goal)
    if problem:  # answered without a roadmap (the robot may fit nowhere at all)
        result = PlanResult(Status.INVALID_QUERY, None, problem, vmax=scene.robot.vmax)
    else:
        roadmap = _roadmap_for(scene, args)
        try:
            result = Planner(scene, roadmap).plan(query.start, query.goal, query.t0, options, hold=query.hold)
        except LimitError as exc:  # a request beyond the memory bounds (dt far too fine)
            raise BadInput(f"gfuzzy plan: {exc}") from None
    tf = result.to_file(scene.name, query.name)
    if out is not None:
        _write_answer(tf, out)
    line = f"{scene.name} {query.name}: {result.status.value}"
    if result.solved:
        line += (
            f" duration {result.duration:.2f} s, roadmap distance {result.roadmap_distance:.2f},"
            f" delay factor {result.delay_factor:.3f}, planned in {result.planning_seconds * 1000:.0f} ms"
        )
    else:
        line += f" ({result.message})"
    _say(line, sys.stdout)
    for key, label in (("refine", "GA refinement"), ("speed_layer", "speed layer")):
        info = result.stats.get(key)
        if info is not None:
            _say(f"  {label}: {_stage_summary(info)}", sys.stdout)
    if result.amax_honoured is False:
        _say(f"note: {result.stats['amax_note']}")
    return EXIT_OK if result.solved else EXIT_NO


def _write_answer(tf, out: Path) -> None:
    """Write OUT.json, or OUT.csv and OUT.json beside it, and say on stderr what changed.

    The JSON is written whatever the status (it holds the status). The CSV has no status
    column, so an unsolved answer, which has no rows, removes an older OUT.csv: a
    controller reading that path must not drive a stale trajectory.
    """
    json_path = out.with_suffix(".json")
    tf.save(json_path)
    _say(f"wrote {json_path}")
    if out.suffix.lower() != ".csv":
        return
    if tf.waypoints is not None:
        tf.save(out)
        _say(f"wrote {out}")
    elif out.is_file() or out.is_symlink():
        out.unlink()
        _say(f"removed {out}: the answer is {tf.status}, without rows, and a CSV has no status to say so")


def _stage_summary(info: dict) -> str:
    if not info.get("applied"):
        return f"not applied: {info.get('reason', '')}"
    b, a = info.get("before", {}), info.get("after", {})
    parts = []
    for key, unit in (("length", "m"), ("smoothness", "rad turning"), ("min_clearance", "m clearance"),
                      ("mean_speed", "m/s mean speed"), ("duration", "s")):  # fmt: skip
        if key in b and key in a:
            parts.append(f"{b[key]:.2f} -> {a[key]:.2f} {unit}")
    if "stops" in info:
        parts.append(f"{info['stops']} stop(s)")
    return "applied: " + ", ".join(parts)


def cmd_check(args) -> int:
    from .check import check_trajectory
    from .trajectory import load_trajectory

    scene = _apply_overrides(_load_scene(args.scene), args)
    tf = load_trajectory(args.trajectory)
    if tf.status != "solved":
        _say(f"{args.trajectory}: status is {tf.status}: there is no trajectory to check")
        return EXIT_NO
    query = None
    if tf.query:
        try:
            query = scene.query(tf.query)
        except KeyError:
            query = None
    if tf.scene and tf.scene != scene.name:
        _say(f"note: {args.trajectory} was planned for scene {tf.scene!r}, checking against {scene.name!r}")
    _rows_fit(scene, tf, args.trajectory)
    if args.hold is not None:  # park at the last row (an ad-hoc query has no hold of its own)
        from .scene import Query

        w = tf.waypoints
        base = query or Query("adhoc", tuple(w[0, 1:]), tuple(w[-1, 1:]), float(w[0, 0]))
        query = replace(base, hold=_hold(args, base.hold))
    rep = check_trajectory(scene, tf.waypoints, query)
    if rep.valid and tf.duration is not None:
        actual = float(tf.waypoints[-1, 0] - tf.waypoints[0, 0])
        if abs(actual - tf.duration) > 1e-6:
            _say(f"{args.trajectory}: duration is {tf.duration!r} but the rows span {actual!r}")
            return EXIT_NO
    if not rep.valid:
        _say(f"{args.trajectory}: invalid: {rep.reason}")
        return EXIT_NO
    _say(
        f"{args.trajectory}: valid (min clearance {rep.min_clearance:.4f}, "
        f"max speed {rep.max_speed:.4f}, {rep.evaluations} evaluations)",
        sys.stdout,
    )
    return EXIT_OK


def _rows_fit(scene, tf, path) -> None:
    """Rows of the wrong width for the scene's robot are bad input (for check as for
    render): a trajectory planned for another robot, not an invalid one."""
    if tf.waypoints is not None and tf.waypoints.shape[1] != scene.robot.dof + 1:
        want = "[t, x, y]" if scene.robot.dof == 2 else "[t, x, y, heading]"
        raise BadInput(
            f"{path}: waypoints: rows of {tf.waypoints.shape[1]} numbers, but scene "
            f"{scene.name!r} has a {scene.robot.shape} robot: expected {want}"
        )


def _violation(scene, tf, path):
    """(time, reason) of a drawn trajectory's first violation of the guarantees, told on
    stderr (render draws it anyway, `check` exits 1 on it); None when it is valid."""
    from .check import check_trajectory

    query = None
    if tf.query:
        try:
            query = scene.query(tf.query)
        except KeyError:
            query = None
    rep = check_trajectory(scene, tf.waypoints, query)
    if rep.valid:
        return None
    _say(f"note: {path}: invalid: {rep.reason} (`gfuzzy check` exits 1); drawing it anyway")
    return None if rep.time is None else (rep.time, rep.reason)


def cmd_render(args) -> int:
    from .render import render
    from .roadmap import load_roadmap
    from .trajectory import load_trajectory

    scene = _apply_overrides(_load_scene(args.scene), args)
    out = _out_path(args.output, (".png", ".gif"))
    traj = None
    nav_doc: dict = {}
    if args.trajectory:
        tf = load_trajectory(args.trajectory)
        nav_doc = _navigate_extras(args.trajectory)
        if tf.waypoints is not None:
            _rows_fit(scene, tf, args.trajectory)
            traj = tf.waypoints
        elif nav_doc.get("executed") is not None:  # a navigate run that did not arrive
            traj = nav_doc["executed"]
        else:
            _say(f"note: {args.trajectory} has status {tf.status}: drawing the scene only")
    if args.roadmap:
        roadmap = load_roadmap(args.roadmap, scene)
    elif out.suffix.lower() == ".png" and not args.no_roadmap:
        roadmap = _default_roadmap(scene, quiet=True)
    else:
        roadmap = None
    options = {}
    if traj is not None and args.speed:  # the picture and the animation both colour by speed
        options["speed"] = True
    elif args.speed:
        _say("note: --speed colours a trajectory's path, and there is none to draw")
    if out.suffix.lower() == ".gif" and traj is not None and nav_doc.get("replan_log"):
        options["predictions"] = nav_doc["replan_log"]
    if out.suffix.lower() == ".gif" and roadmap is not None:
        raise BadInput("--roadmap: only drawn in a .png picture")
    if traj is not None and tf.waypoints is not None:
        bad = _violation(scene, tf, args.trajectory)
        if bad is not None and out.suffix.lower() == ".png":
            options["violation"] = bad
    try:
        render(scene, out, trajectory=traj, roadmap=roadmap, **options)
    except InputError as exc:
        raise BadInput(f"{args.trajectory or out}: {exc}") from None
    _say(f"wrote {out}", sys.stdout)
    return EXIT_OK


def _start_on_mover(scene, query) -> str:
    """Why the start overlaps a mover present at t0 (as ``plan`` says), or ""."""
    import numpy as np

    from .geometry import mover_distance

    start = np.asarray(query.start, dtype=float)
    for mv in scene.movers:
        xy, present = mv.state(np.array([query.t0]))
        if present[0] and mover_distance(scene.robot, start, mv.shape, mv.radius, mv.size, xy[0]) < 0:
            return f"start collides with mover {mv.name!r} at t0={query.t0:g}"
    return ""


def _navigate_extras(path) -> dict:
    """The ``executed`` rows and ``replan_log`` of a ``gfuzzy navigate`` file (else {})."""
    import json

    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(doc, dict):
        return {}
    out = {}
    rows = doc.get("executed")
    if isinstance(rows, list) and rows and all(isinstance(r, list) and len(r) in (3, 4) for r in rows):
        try:
            out["executed"] = [[float(v) for v in r] for r in rows]
        except (TypeError, ValueError):
            pass
    log = doc.get("replan_log")
    if isinstance(log, list):
        out["replan_log"] = [e for e in log if isinstance(e, dict) and isinstance(e.get("t"), (int, float))]
    return out


def cmd_regress(args) -> int:
    from .regress import run_regression

    scenes = [_apply_overrides(_load_scene(p), args) for p in args.scenes]  # all bad input first
    options = _plan_options(args)
    _check_roadmap_flags(args)  # before the table's header: bad input prints nothing else
    try:
        ok = run_regression(scenes, lambda sc: _roadmap_for(sc, args), options, sys.stdout)
    except LimitError as exc:  # a request beyond the memory bounds (dt far too fine)
        raise BadInput(f"gfuzzy regress: {exc}") from None
    return EXIT_OK if ok else EXIT_NO


def _tracks_command(args) -> str:
    """The `gfuzzy tracks` command that makes the same scene (for the scene's header)."""
    import shlex

    def g(v) -> str:
        return v if isinstance(v, str) else (str(int(v)) if float(v).is_integer() else repr(float(v)))

    parts = ["gfuzzy", "tracks", args.file]
    for flag, value in (("--format", None if args.format == "auto" else args.format), ("--fps", args.fps),
                        ("--t-start", args.t_start), ("--duration", args.duration), ("--region", args.region),
                        ("--scale", None if args.scale == 1.0 else args.scale),
                        ("--radius", None if args.radius == 0.25 else args.radius), ("--max-movers", args.max_movers),
                        ("--static", args.static), ("--name", args.name), ("--robot-radius", args.robot_radius),
                        ("--vmax", args.vmax), ("--amax", args.amax), ("--start", args.start), ("--goal", args.goal),
                        ("--query-name", None if args.query_name == "cross" else args.query_name),
                        ("--expect", args.expect), ("--max-duration", args.max_duration), ("-o", args.output)):  # fmt: skip
        if value is not None:
            parts += [flag, *(g(v) for v in (value if isinstance(value, list) else [value]))]
    return " ".join(shlex.quote(a) for a in parts)


def cmd_tracks(args) -> int:
    from .atomic import write_atomic
    from .scene import _load_yaml, parse_scene
    from .tracks import TrackSceneOptions, read_tracks, tracks_scene

    out = _out_path(args.output, (".yaml", ".yml"))
    static = _load_scene(args.static) if args.static else None
    try:
        options = TrackSceneOptions(
            t_start=args.t_start,
            duration=args.duration,
            region=tuple(args.region) if args.region else None,
            scale=args.scale,
            radius=args.radius,
            max_movers=args.max_movers,
            name=args.name or out.stem,
            robot_radius=args.robot_radius,
            vmax=args.vmax,
            amax=args.amax,
        )
        tracks = read_tracks(args.file, args.format, args.fps)
        dof = static.robot.dof if static is not None and args.robot_radius is None else 2
        start = _pose(args.start, dof, "--start")
        goal = _pose(args.goal, dof, "--goal")
        expect = {}
        if args.expect:
            expect["status"] = args.expect
        if args.max_duration is not None:
            expect["max_duration"] = args.max_duration
        made = tracks_scene(
            tracks, options, static=static, folder=out.resolve().parent,
            start=start, goal=goal, query_name=args.query_name, expect=expect,
        )  # fmt: skip
    except SceneError:  # a bad file: its own message (SceneError is an InputError too)
        raise
    except InputError as exc:
        raise BadInput(f"gfuzzy tracks: {exc}") from None
    text = made.to_yaml(_tracks_command(args))
    # the file must load as it will be read: check it before it replaces anything
    parse_scene(_load_yaml(text, str(out)), file=str(out), folder=out.resolve().parent)
    write_atomic(out, text)
    _say(f"{out}: {made.movers} movers, bounds {list(made.region)}", sys.stdout)
    return EXIT_OK


def _writable_folder(path: Path, flag: str) -> None:
    """Bad input unless ``path`` is (or can be made) a writable folder."""
    import os

    if path.exists():
        if not path.is_dir():
            raise BadInput(f"{flag} {path}: not a folder")
        if not os.access(path, os.W_OK | os.X_OK):
            raise BadInput(f"{flag} {path}: folder is not writable")
        return
    parent = path.resolve().parent
    if not parent.is_dir():
        raise BadInput(f"{flag} {path}: folder {parent} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BadInput(f"{flag} {path}: folder {parent} is not writable")


def cmd_batch(args) -> int:
    """Every query of every scene on Dask; exit 0 all ran, 1 any error row, 130 interrupted."""
    import logging
    import time

    from .batch import BatchOptions, local_cluster, run_batch, write_table

    if args.workers is not None and args.workers < 1:
        raise BadInput(f"--workers: must be at least 1, got {args.workers}")
    out = _out_path(args.output, (".csv",))
    _writable_folder(out.parent, "-o")
    if args.trajectories:
        _writable_folder(Path(args.trajectories), "--trajectories")
    scenes = [_apply_overrides(_load_scene(p), args) for p in args.scenes]  # all bad input first
    seen: dict = {}
    for path, sc in zip(args.scenes, scenes, strict=True):
        if sc.name in seen:
            raise BadInput(f"{path}: name: scene name {sc.name!r} repeats that of {seen[sc.name]}")
        seen[sc.name] = path
    options = BatchOptions(plan=_plan_options(args), trajectories=args.trajectories)
    pairs = [(sc, _roadmap_for(sc, args)) for sc in scenes]  # once per scene, in the client
    quiet = not args.verbose
    if quiet:  # Dask's own INFO/WARNING lines (a worker restarting) are not ours to show
        for name in ("distributed", "tornado"):
            logging.getLogger(name).setLevel(logging.ERROR)
    t = time.perf_counter()
    if args.scheduler:
        from distributed import Client

        try:
            client = Client(args.scheduler, timeout=args.connect_timeout)
        except (OSError, TimeoutError, ValueError) as exc:
            raise BadInput(f"--scheduler {args.scheduler}: cannot connect: {' '.join(str(exc).split())[:120]}") from None
        where = f"the cluster at {args.scheduler}"
        ctx = contextlib.closing(client)
    else:
        workers = args.workers or 2
        where = f"{workers} local worker(s)"
        ctx = local_cluster(workers, quiet=quiet)
    with ctx as client:
        result = run_batch(client, pairs, options, progress=_progress("queries"))
    written = write_table(result.rows, out)
    counts: dict = {}
    for r in result.rows:
        counts[r.status] = counts.get(r.status, 0) + 1
    summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    invalid = sum(r.check == "invalid" for r in result.rows)
    if result.interrupted:
        _say(
            f"interrupted: wrote the {len(result.rows)} finished of {result.total} queries "
            f"to {', '.join(map(str, written))}"
        )
        return 130
    _say(
        f"{result.total} queries on {where} in {time.perf_counter() - t:.1f} s: {summary or 'none'}"
        f"{f', {invalid} INVALID' if invalid else ''}; wrote {', '.join(map(str, written))}",
        sys.stdout,
    )
    for r in result.rows:
        if not r.ran:
            _say(f"{r.scene} {r.query}: error: {r.error}")
        elif r.check == "invalid":  # a planner defect: reported, but the query did run
            _say(f"{r.scene} {r.query}: the answer fails the check (see `gfuzzy check`)")
    return EXIT_NO if result.errors else EXIT_OK


# ------------------------------------------------------------------ parser


def cmd_navigate(args) -> int:
    """Drive the robot among the scene's movers without knowing their future (section 5)."""
    import numpy as np

    from .check import check_trajectory
    from .geometry import StaticGeometry
    from .navigator import Navigator, NavOptions
    from .navsim import simulate
    from .planner import query_problem
    from .trajectory import TrajectoryFile

    scene = _apply_overrides(_load_scene(args.scene), args)
    for flag, value in (("--period", args.period), ("--max-time", args.max_time), ("--time-budget", args.time_budget)):
        if not (math.isfinite(value) and value > 0):
            raise BadInput(f"gfuzzy navigate: {flag} must be a positive number, got {value:g}")
    if args.log_every < 0:
        raise BadInput(f"gfuzzy navigate: --log-every must be >= 0, got {args.log_every}")
    sense = math.inf if args.sense is None else args.sense
    if not sense > 0:
        raise BadInput(f"gfuzzy navigate: --sense must be a positive number, got {sense:g}")
    if args.query:
        try:
            query = scene.query(args.query)
        except KeyError as exc:
            raise BadInput(f"{scene.source}: queries: {exc.args[0]}") from None
    elif scene.queries:
        query = scene.queries[0]
    else:
        raise BadInput(f"{scene.source}: queries: the scene has no queries to navigate")
    out = _out_path(args.output, (".json",)) if args.output else None
    try:
        options = NavOptions(dt=args.dt, time_budget=args.time_budget)
    except InputError as exc:
        raise BadInput(f"gfuzzy navigate: {exc}") from None
    problem = query_problem(StaticGeometry(scene), query.start, query.goal) or _start_on_mover(scene, query)
    if problem:
        tf = TrajectoryFile(scene.name, query.name, "invalid_query", problem, None, None, None, 0.0)
        if out is not None:
            tf.save(out)
        _say(f"{scene.name} {query.name}: invalid_query ({problem})", sys.stdout)
        return EXIT_NO
    roadmap = _roadmap_for(scene, args)
    nav = Navigator(scene, roadmap, query.goal, options)
    res = simulate(
        scene, roadmap, query.start, query.goal, query.t0, args.period, sense, args.max_time,
        navigator=nav, log_every=args.log_every,
    )
    wps = res.trajectory.waypoints
    report = check_trajectory(scene, wps, query if res.reached else None)
    rd = nav.roadmap_distance(np.asarray(query.start, dtype=float))
    rd_ok = math.isfinite(rd)
    solved = res.reached
    message = "" if solved else f"the goal was not reached within {args.max_time:g} s"
    if not report.valid:
        message = (message + "; " if message else "") + f"the executed trajectory is invalid: {report.reason}"
    extra = {
        "replans": res.replans,
        "replan_seconds_p50": round(res.latency(0.5), 6),
        "replan_seconds_p95": round(res.latency(0.95), 6),
        "replan_seconds_max": round(float(res.replan_seconds.max(initial=0.0)), 6),
        "min_separation": res.min_separation if math.isfinite(res.min_separation) else None,
        "check": {"valid": report.valid, "reason": report.reason},
        "modes": res.modes,
        "navigate": {"period": args.period, "sense": None if math.isinf(sense) else sense, "max_time": args.max_time},
        "replan_log": res.log,
    }
    if not solved:  # only a solved file carries waypoints (section 2): the motion goes here
        extra["executed"] = [[float(v) for v in row] for row in wps]
    tf = TrajectoryFile(
        scene=scene.name,
        query=query.name,
        status="solved" if solved else "timeout",
        message=message,
        duration=res.duration if solved else None,
        roadmap_distance=rd if rd_ok else None,
        delay_factor=res.trajectory.delay_factor(scene.robot.vmax, rd) if (solved and rd_ok) else None,
        planning_seconds=round(float(res.replan_seconds.sum()), 6),
        waypoints=wps if solved else None,
        extra=extra,
    )
    if out is not None:
        tf.save(out)
    sep = "none seen" if not math.isfinite(res.min_separation) else f"{res.min_separation:.3f} m"
    line = f"{scene.name} {query.name}: {'solved' if solved else 'timeout'}"
    if solved:
        line += f" in {res.duration:.2f} s"
    line += (
        f", {res.replans} replans (p95 {res.latency(0.95) * 1000:.0f} ms, max "
        f"{float(res.replan_seconds.max(initial=0.0)) * 1000:.0f} ms), min separation {sep}, "
        f"check {'valid' if report.valid else 'INVALID: ' + report.reason}"
    )
    _say(line, sys.stdout)
    return EXIT_OK if (solved and report.valid) else EXIT_NO


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="gfuzzy",
        description="Roadmap-time-space motion planning among moving obstacles (OMPL + FCL).",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)

    r = sub.add_parser("roadmap", help="build the static roadmap of a scene with OMPL's PRM")
    r.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    r.add_argument("-n", "--vertices", type=int, default=200, help="roadmap vertices (default 200)")
    r.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    r.add_argument("-k", "--neighbors", type=int, default=10, help="PRM nearest neighbours (default 10)")
    r.add_argument("-o", "--output", help="roadmap file (default roadmaps/<scene name>.json)")
    r.set_defaults(func=cmd_roadmap)

    def plan_flags(q, single=True):
        q.add_argument("-n", "--vertices", type=int, help="build a roadmap of this many vertices")
        q.add_argument("--seed", type=int, help="roadmap seed when building (default 1)")
        q.add_argument("--dt", type=float, default=0.07, help="time step of the search (default 0.07)")
        q.add_argument("--refine", action="store_true", help="apply the GA refinement")
        q.add_argument("--speed-layer", action="store_true", help="apply the fuzzy speed layer")
        q.add_argument("--time-limit", type=float, default=60.0, help="planning budget in seconds (default 60)")
        q.add_argument("--horizon", type=float, help="longest trajectory considered, seconds (default: automatic)")
        q.add_argument("--weight", type=float, default=1.0,
                       help="heuristic weight: 1 = earliest arrival (default); w > 1 searches less, arrives at most w times later")  # fmt: skip
        q.add_argument("--ga-seed", type=int, default=0, help="seed of the GA refinement (default 0)")
        q.add_argument("--stretch", type=float, default=1.05,
                       help="search the roadmap's spanner of this stretch (default 1.05; 1 = the whole roadmap)")  # fmt: skip
        clearance_flags(q)

    def clearance_flags(q):
        q.add_argument("--clearance", type=float, metavar="C",
                       help="distance kept from static obstacles, m (overrides robot.clearance; another roadmap)")  # fmt: skip
        q.add_argument("--mover-clearance", type=float, metavar="C",
                       help="distance kept from every mover, m (overrides robot.mover_clearance)")  # fmt: skip

    q = sub.add_parser("plan", help="answer one query")
    q.add_argument("scene", metavar="SCENE")
    q.add_argument("--roadmap", metavar="FILE", help="roadmap file (default roadmaps/<scene name>.json)")
    plan_flags(q)
    q.add_argument("--query", metavar="NAME", help="a query of the scene (default: its first)")
    q.add_argument("--start", nargs="+", metavar="X", help="start pose: X Y (disc) or X Y H (box)")
    q.add_argument("--goal", nargs="+", metavar="X", help="goal pose")
    q.add_argument("--t0", type=float, help="departure time with --start/--goal (default 0)")
    q.add_argument("--hold", type=float, metavar="SECONDS",
                   help="park at the goal this long; it must stay safe (default: the query's hold, or 0)")  # fmt: skip
    q.add_argument("-o", "--output", metavar="OUT",
                   help="trajectory file: OUT.json, or OUT.csv (+ OUT.json); the JSON is written whatever the status, "
                        "an unsolved answer removes an older OUT.csv; stderr names the files written or removed")  # fmt: skip
    q.set_defaults(func=cmd_plan)

    c = sub.add_parser("check", help="check a trajectory against the contract's guarantees")
    c.add_argument("scene", metavar="SCENE")
    c.add_argument("trajectory", metavar="TRAJ.json")
    clearance_flags(c)
    c.add_argument("--hold", type=float, metavar="SECONDS",
                   help="the goal pose must stay safe this long after the last row (default: the query's hold)")  # fmt: skip
    c.set_defaults(func=cmd_check)

    d = sub.add_parser("render", help="draw a scene (and a trajectory): PNG picture or GIF animation")
    d.add_argument("scene", metavar="SCENE")
    d.add_argument("trajectory", metavar="TRAJ.json", nargs="?")
    d.add_argument("-o", "--output", required=True, metavar="OUT", help="OUT.png or OUT.gif")
    d.add_argument("--roadmap", metavar="FILE", help="draw this roadmap (PNG; default: the scene's roadmaps/<name>.json if there is one)")
    d.add_argument("--no-roadmap", action="store_true", help="do not draw a roadmap")
    d.add_argument("--speed", action="store_true", help="colour the path by speed (PNG and GIF)")
    clearance_flags(d)
    d.set_defaults(func=cmd_render)

    v = sub.add_parser("navigate", help="drive to the goal among the movers without knowing their future")
    v.add_argument("scene", metavar="SCENE")
    v.add_argument("--query", metavar="NAME", help="a query of the scene (default: its first)")
    v.add_argument("--roadmap", metavar="FILE", help="roadmap file (default roadmaps/<scene name>.json)")
    v.add_argument("-n", "--vertices", type=int, help="build a roadmap of this many vertices")
    v.add_argument("--seed", type=int, help="roadmap seed when building (default 1)")
    v.add_argument("--period", type=float, default=0.25, help="seconds between observations and replans (default 0.25)")
    v.add_argument("--sense", type=float, help="range in metres within which movers are seen (default: all)")
    v.add_argument("--max-time", type=float, default=120.0, help="give up this long after t0 (default 120 s)")
    v.add_argument("--dt", type=float, default=0.1, help="time step of the replanning search (default 0.1)")
    v.add_argument("--time-budget", type=float, default=0.1, help="seconds one replan may take (default 0.1)")
    v.add_argument("--log-every", type=int, default=4, help="keep every k-th replan's predictions in the file (default 4)")
    clearance_flags(v)
    v.add_argument("-o", "--output", metavar="OUT.json", help="the executed trajectory file")
    v.set_defaults(func=cmd_navigate)

    g = sub.add_parser("regress", help="answer and check every query of every scene")
    g.add_argument("scenes", metavar="SCENE", nargs="+")
    plan_flags(g)
    g.set_defaults(func=cmd_regress, roadmap=None)

    k = sub.add_parser("tracks", help="make a scene of pedestrian tracks (ETH/UCY text or CSV t,id,x,y)")
    k.add_argument("file", metavar="FILE", help="tracks: ETH/UCY text (frame id x y [vx vy]) or CSV (t,id,x,y)")
    k.add_argument("-o", "--output", required=True, metavar="OUT.yaml", help="the scene file to write")
    k.add_argument("--format", choices=("auto", "eth", "csv"), default="auto", help="input format (default: from the file)")
    k.add_argument("--fps", type=float, metavar="FPS", help="eth: frames per second (default: annotated frames 0.4 s apart)")
    k.add_argument("--t-start", type=float, metavar="T", help="window start, seconds of the recording (default: its first time)")
    k.add_argument("--duration", type=float, metavar="D", help="window length, seconds (default: to the recording's end)")
    k.add_argument("--region", type=float, nargs=4, metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
                   help="scene bounds; tracks are clipped to it (default: --static's bounds, or the people's extent + 0.5 m)")  # fmt: skip
    k.add_argument("--scale", type=float, metavar="S", default=1.0, help="multiplies every x and y of the file (default 1)")
    k.add_argument("--radius", "--ped-radius", dest="radius", type=float, metavar="R", default=0.25, help="pedestrians' disc radius (default 0.25)")
    k.add_argument("--max-movers", type=int, metavar="N", help="keep the N people present longest")
    k.add_argument("--static", metavar="SCENE", help="take the robot, the static obstacles and the bounds of this scene")
    k.add_argument("--name", help="scene name (default: the output file's stem)")
    k.add_argument("--robot-radius", type=float, metavar="R", help="a disc robot of this radius (default 0.2, or --static's robot)")
    k.add_argument("--vmax", type=float, metavar="V", help="robot speed bound (default 1.5, or --static's)")
    k.add_argument("--amax", type=float, metavar="A", help="robot acceleration bound (default 3.0, or --static's)")
    k.add_argument("--start", nargs="+", metavar="X", help="a query from this pose at t0 = 0 (with --goal)")
    k.add_argument("--goal", nargs="+", metavar="X", help="the query's goal pose")
    k.add_argument("--query-name", metavar="NAME", default="cross", help="the query's name (default cross)")
    k.add_argument("--expect", choices=("solved", "no_path", "invalid_query"), help="the query's expected status")
    k.add_argument("--max-duration", type=float, metavar="S", help="the query's expected longest duration")
    k.set_defaults(func=cmd_tracks)

    b = sub.add_parser("batch", help="answer every query of every scene on a Dask cluster; one CSV row per query")
    b.add_argument("scenes", metavar="SCENE", nargs="+")
    plan_flags(b)
    where = b.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="K", help="local worker processes (default 2)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://host:8786")
    b.add_argument("--connect-timeout", type=float, default=10.0, help=argparse.SUPPRESS)
    b.add_argument("-o", "--output", required=True, metavar="RESULTS.csv",
                   help="results table (and RESULTS.parquet beside it when pyarrow is installed)")  # fmt: skip
    b.add_argument("--trajectories", metavar="DIR", help="save each answer as DIR/<scene>-<query>.json")
    b.add_argument("-v", "--verbose", action="store_true", help="show Dask's logs")
    b.set_defaults(func=cmd_batch, roadmap=None)
    return p


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    import logging

    logging.basicConfig(level=logging.WARNING, format="%(levelname)s: %(message)s")
    parser = _parser()
    try:
        args = parser.parse_args(argv)
        if not getattr(args, "command", None):
            parser.print_help(sys.stderr)
            return EXIT_BAD
        return args.func(args)
    except BadInput as exc:
        _say(" ".join(str(exc).split()))
        return EXIT_BAD
    except (InputError, LimitError) as exc:  # SceneError included; any other exception is a bug
        _say(" ".join(str(exc).split()))
        return EXIT_BAD
    except KeyboardInterrupt:
        _say("interrupted")
        return 130
    except BrokenPipeError:
        return EXIT_OK

