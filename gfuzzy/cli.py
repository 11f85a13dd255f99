"""The ``gfuzzy`` command line (CONTRACT.md section 4).

Exit statuses: 0 success, 1 a valid request with a negative answer (no path, invalid
trajectory, missed expectation), 2 bad input. Bad input prints exactly one line on stderr
naming the file and the place in it, and writes nothing.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .errors import SceneError

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
        except ValueError as exc:
            raise BadInput(f"-n/--seed: {exc}") from None
        saved = _default_roadmap(scene, quiet=True)
        if saved is not None and saved.options == opts:  # the saved file is this very roadmap
            return saved
        return build_roadmap(scene, opts, progress=_progress("roadmap"))
    found = _default_roadmap(scene, quiet)
    if found is not None:
        return found
    if not quiet:
        _say(
            f"note: no roadmap file for {scene.name!r}; building one with "
            f"{RoadmapOptions.vertices} vertices (save one with `gfuzzy roadmap`)"
        )
    return build_roadmap(scene, RoadmapOptions(), progress=_progress("roadmap"))


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
                if not quiet:
                    _say(f"note: not using {path}: {exc.message}")
    return None


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
    except ValueError as exc:
        raise BadInput(f"gfuzzy plan: {exc}") from None


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
    except ValueError as exc:
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
        return Query("cli", tuple(start), tuple(goal), t0)
    if args.t0 is not None:
        raise BadInput("gfuzzy plan: --t0 goes with --start/--goal (a scene query has its own t0)")
    if args.query:
        try:
            return scene.query(args.query)
        except KeyError as exc:
            raise BadInput(f"{scene.source}: queries: {exc.args[0]}") from None
    if not scene.queries:
        raise BadInput(f"{scene.source}: queries: the scene has no queries; give --start and --goal")
    return scene.queries[0]


def cmd_plan(args) -> int:
    from .geometry import StaticGeometry
    from .planner import Planner, PlanResult, Status, query_problem

    scene = _load_scene(args.scene)
    query = _query_from_args(scene, args)
    out = _out_path(args.output, (".json", ".csv")) if args.output else None
    options = _plan_options(args)
    problem = query_problem(StaticGeometry(scene), query.start, query.goal)
    if problem:  # answered without a roadmap (the robot may fit nowhere at all)
        result = PlanResult(Status.INVALID_QUERY, None, problem, vmax=scene.robot.vmax)
    else:
        roadmap = _roadmap_for(scene, args)
        try:
            result = Planner(scene, roadmap).plan(query.start, query.goal, query.t0, options)
        except ValueError as exc:  # a request beyond the memory bounds (dt far too fine)
            raise BadInput(f"gfuzzy plan: {exc}") from None
    tf = result.to_file(scene.name, query.name)
    if out is not None:
        json_path = out.with_suffix(".json")
        if out.suffix.lower() == ".csv" and tf.waypoints is not None:
            tf.save(out)
        tf.save(json_path)
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
    return EXIT_OK if result.solved else EXIT_NO


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

    scene = _load_scene(args.scene)
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


def cmd_render(args) -> int:
    from .render import render
    from .roadmap import load_roadmap
    from .trajectory import load_trajectory

    scene = _load_scene(args.scene)
    out = _out_path(args.output, (".png", ".gif"))
    traj = None
    nav_doc: dict = {}
    if args.trajectory:
        tf = load_trajectory(args.trajectory)
        nav_doc = _navigate_extras(args.trajectory)
        if tf.waypoints is not None:
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
    if out.suffix.lower() == ".png" and traj is not None and args.speed:
        options["speed"] = True
    if out.suffix.lower() == ".gif" and traj is not None and nav_doc.get("replan_log"):
        options["predictions"] = nav_doc["replan_log"]
    if out.suffix.lower() == ".gif" and roadmap is not None:
        raise BadInput("--roadmap: only drawn in a .png picture")
    try:
        render(scene, out, trajectory=traj, roadmap=roadmap, **options)
    except ValueError as exc:
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

    scenes = [_load_scene(p) for p in args.scenes]  # all bad input first, before any work
    options = _plan_options(args)
    try:
        ok = run_regression(scenes, lambda sc: _roadmap_for(sc, args), options, sys.stdout)
    except ValueError as exc:  # a request beyond the memory bounds (dt far too fine)
        raise BadInput(f"gfuzzy regress: {exc}") from None
    return EXIT_OK if ok else EXIT_NO


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

    scene = _load_scene(args.scene)
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
    except ValueError as exc:
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

    q = sub.add_parser("plan", help="answer one query")
    q.add_argument("scene", metavar="SCENE")
    q.add_argument("--roadmap", metavar="FILE", help="roadmap file (default roadmaps/<scene name>.json)")
    plan_flags(q)
    q.add_argument("--query", metavar="NAME", help="a query of the scene (default: its first)")
    q.add_argument("--start", nargs="+", metavar="X", help="start pose: X Y (disc) or X Y H (box)")
    q.add_argument("--goal", nargs="+", metavar="X", help="goal pose")
    q.add_argument("--t0", type=float, help="departure time with --start/--goal (default 0)")
    q.add_argument("-o", "--output", metavar="OUT", help="trajectory file: OUT.json, or OUT.csv (+ OUT.json)")
    q.set_defaults(func=cmd_plan)

    c = sub.add_parser("check", help="check a trajectory against the contract's guarantees")
    c.add_argument("scene", metavar="SCENE")
    c.add_argument("trajectory", metavar="TRAJ.json")
    c.set_defaults(func=cmd_check)

    d = sub.add_parser("render", help="draw a scene (and a trajectory): PNG picture or GIF animation")
    d.add_argument("scene", metavar="SCENE")
    d.add_argument("trajectory", metavar="TRAJ.json", nargs="?")
    d.add_argument("-o", "--output", required=True, metavar="OUT", help="OUT.png or OUT.gif")
    d.add_argument("--roadmap", metavar="FILE", help="draw this roadmap (PNG; default: the scene's roadmaps/<name>.json if there is one)")
    d.add_argument("--no-roadmap", action="store_true", help="do not draw a roadmap")
    d.add_argument("--speed", action="store_true", help="colour the path by speed (PNG)")
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
    v.add_argument("-o", "--output", metavar="OUT.json", help="the executed trajectory file")
    v.set_defaults(func=cmd_navigate)

    g = sub.add_parser("regress", help="answer and check every query of every scene")
    g.add_argument("scenes", metavar="SCENE", nargs="+")
    plan_flags(g)
    g.set_defaults(func=cmd_regress, roadmap=None)
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
    except SceneError as exc:
        _say(" ".join(str(exc).split()))
        return EXIT_BAD
    except KeyboardInterrupt:
        _say("interrupted")
        return 130
    except BrokenPipeError:
        return EXIT_OK

