"""The planning commands: ``roadmap``, ``plan``, ``check``, ``render``, ``regress``."""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

from ..errors import InputError, LimitError, TimeStepError
from ..settings import MAX_MAGNITUDE
from ..status import Status
from .common import (
    EXIT_NO,
    EXIT_OK,
    BadInput,
    _apply_overrides,
    _check_roadmap_flags,
    _default_roadmap,
    _load_scene,
    _out_path,
    _plan_options,
    _pose,
    _progress,
    _refuse_overwrite,
    _roadmap_for,
    _roadmap_reads,
    _say,
    _scene_reads,
)


def cmd_roadmap(args) -> int:
    from ..roadmap.roadmap import RoadmapOptions, build_roadmap, default_roadmap_path

    scene = _load_scene(args.scene)
    if args.output:
        out = _out_path(args.output, (".json",), _scene_reads(scene))
    else:
        out = default_roadmap_path(scene)
        _refuse_overwrite(out, [out], _scene_reads(scene))
    try:
        opts = RoadmapOptions(
            vertices=args.vertices,
            seed=args.seed,
            neighbors=args.neighbors,
            repair=not args.no_repair,
            join=not args.no_join,
        )
    except (InputError, LimitError) as exc:
        raise BadInput(f"gfuzzy roadmap: {exc}") from None
    rm = build_roadmap(scene, opts, progress=_progress("roadmap"))
    rm.save(out)
    info = rm.info
    _say(
        f"{out}: {len(rm.vertices)} vertices, {len(rm.edges)} edges, "
        f"{info.components} component(s), {info.seconds:.2f} s, "
        f"{info.validity_calls + info.certify_calls} collision checks",
        sys.stdout,
    )
    rep = info.repair
    if rep and rep["added_vertices"]:
        _say(
            f"  free-space repair: PRM missed {rep['components_joined']} passage(s); "
            f"{rep['added_vertices']} vertices beyond -n {opts.vertices} join them "
            f"({rep['seconds']:.2f} s)",
            sys.stdout,
        )
    join = info.join
    if join:
        apart = join.get("components_apart", 0)
        why = f"; {apart} proven apart: the robot's inscribed disc cannot get out" if apart else ""
        _say(
            f"  component join: {join['components_before']} -> {join['components_after']} component(s), "
            f"{join['added_vertices']} vertices beyond -n {opts.vertices} "
            f"({join['checks']} of {join['budget']} collision checks{why}; {join['seconds']:.2f} s)",
            sys.stdout,
        )
    return EXIT_OK


def _query_from_args(scene, args):
    from ..scene.scene import Query

    dof = scene.robot.dof
    start = _pose(args.start, dof, "--start")
    goal = _pose(args.goal, dof, "--goal")
    if args.query and (start or goal):
        raise BadInput("gfuzzy plan: give either --query or --start/--goal, not both")
    if start is not None or goal is not None:
        if start is None or goal is None:
            raise BadInput("gfuzzy plan: --start and --goal go together")
        t0 = args.t0 if args.t0 is not None else 0.0
        if not (math.isfinite(t0) and abs(t0) <= MAX_MAGNITUDE):
            raise BadInput(f"--t0: must be a finite number of at most {MAX_MAGNITUDE:g} in magnitude, got {t0:g}")
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
    if not (math.isfinite(hold) and 0 <= hold <= MAX_MAGNITUDE):
        raise BadInput(f"--hold: must be a non-negative finite number of at most {MAX_MAGNITUDE:g}, got {hold:g}")
    return float(hold)


def cmd_plan(args) -> int:
    from ..collision.geometry import StaticGeometry
    from ..planner.planner import Planner, PlanResult, Status, query_problem

    scene = _apply_overrides(_load_scene(args.scene), args)
    query = _query_from_args(scene, args)
    reads = (*_scene_reads(scene), *_roadmap_reads(scene, args))
    out = _out_path(args.output, (".json", ".csv"), reads, beside=(".json",)) if args.output else None
    options = _plan_options(args)
    problem = query_problem(StaticGeometry(scene), query.start, query.goal)
    if problem:  # answered without a roadmap (the robot may fit nowhere at all)
        result = PlanResult(Status.INVALID_QUERY, None, problem, vmax=scene.robot.vmax)
    else:
        roadmap = _roadmap_for(scene, args)
        try:
            result = Planner(scene, roadmap).plan(query.start, query.goal, query.t0, options, hold=query.hold)
        except TimeStepError as exc:  # the option's fault, said as regress says it
            raise BadInput(f"gfuzzy plan: --dt {options.dt:g}: {exc}") from None
        except LimitError as exc:  # a request beyond the memory bounds (a hold of 1e6 s)
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
    for report, label in ((result.refine_report, "GA refinement"), (result.speed_report, "speed layer")):
        if report is not None:
            _say(f"  {label}: {_stage_summary(report.to_dict())}", sys.stdout)
    if result.amax_honoured is False:
        _say(f"note: {result.stats.amax_note}")
    return EXIT_OK if result.solved else EXIT_NO


def _write_answer(tf, out: Path) -> None:
    """Write OUT.json, or OUT.csv and OUT.json beside it, and say on stderr what changed.

    The JSON is written whatever the status (it holds the status). The CSV has no status
    column, so an unsolved answer, which has no rows, removes an older OUT.csv: a
    controller reading that path must not drive a stale trajectory.
    """
    from ..errors import check_interrupt, interrupts_deferred

    json_path = out.with_suffix(".json")
    check_interrupt()
    with interrupts_deferred():  # Ctrl-C now: both files (a new JSON beside an old CSV misleads)
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
    if info.get("hasty"):
        h = info["hasty"]
        parts.append(f"{h['legs']} of {h['of']} legs ({h['length']:.2f} of {h['total']:.2f} m metric length, turns as r*angle) at the search's pace")
    return ("applied in part: " if info.get("hasty") else "applied: ") + ", ".join(parts)


def cmd_check(args) -> int:
    from ..check.check import check_trajectory
    from ..trajectory import load_trajectory

    scene = _apply_overrides(_load_scene(args.scene), args)
    tf = load_trajectory(args.trajectory)
    if tf.scene and tf.scene != scene.name:
        _say(f"note: {args.trajectory} was planned for scene {tf.scene!r}, checking against {scene.name!r}")
    if tf.status != Status.SOLVED:
        executed = _executed_verdict(scene, tf, args.trajectory)
        _say(f"{args.trajectory}: status is {tf.status}: " + (executed or "there is no trajectory to check"))
        return EXIT_NO
    query = _query_of(scene, tf)
    if query is None:
        what = f"names query {tf.query!r}, which scene {scene.name!r} does not have" if tf.query else "names no query"
        _say(
            f"note: {args.trajectory} {what}: its start, goal, departure time and any hold are "
            "not checked (only motion, speed and collisions; --hold checks a parking)"
        )
    _rows_fit(scene, tf.waypoints, args.trajectory)
    if args.hold is not None:  # park at the last row (an ad-hoc query has no hold of its own)
        from ..scene.scene import Query

        w = tf.waypoints
        base = query or Query("adhoc", tuple(w[0, 1:]), tuple(w[-1, 1:]), float(w[0, 0]))
        query = replace(base, hold=_hold(args, base.hold))
    rep = check_trajectory(scene, tf.waypoints, query)
    if rep.valid and (wrong := _duration_disagrees(tf)):
        _say(f"{args.trajectory}: {wrong}")
        return EXIT_NO
    if not rep.valid:
        _say(f"{args.trajectory}: invalid: {rep.reason}")
        return EXIT_NO
    clear = max(rep.min_clearance, 0.0)  # valid: within the check's tolerance of touching is touching
    _say(
        f"{args.trajectory}: valid (min clearance {clear:.4f}, "
        f"max speed {rep.max_speed:.4f}, {rep.evaluations} evaluations)",
        sys.stdout,
    )
    return EXIT_OK


def _duration_disagrees(tf) -> str:
    """What `check` says of a solved file whose ``duration`` is not the span of its rows
    (render and export note it), or ""."""
    if tf.duration is None or tf.waypoints is None:
        return ""
    actual = float(tf.waypoints[-1, 0] - tf.waypoints[0, 0])
    # "not <=": a NaN duration (JSON's NaN, read as written) disagrees too; it passed as valid
    return f"duration is {tf.duration!r} but the rows span {actual!r}" if not abs(actual - tf.duration) <= 1e-6 else ""


def _executed_verdict(scene, tf, path) -> str:
    """What the check says of a navigate run's ``executed`` rows, when it did not arrive (its
    motion, speed and collisions, as navigate checked them), or "" (no such rows).
    BadInput (a SceneError) when they are no table of numbers or not the robot's width."""
    from ..check.check import check_trajectory
    from ..trajectory import executed_rows

    rows = executed_rows(tf, path)
    if rows is None:
        return ""
    _rows_fit(scene, rows, path, "executed")
    rep = check_trajectory(scene, rows, None)
    n = len(rows)
    done = (f"the goal was not reached, no answer to check; the motion it executed "
            f"({n} row{'s' if n != 1 else ''}, t {rows[0, 0]:g} to {rows[-1, 0]:g})")
    if not rep.valid:
        return f"{done} is invalid: {rep.reason}"
    return f"{done} is valid (min clearance {max(rep.min_clearance, 0.0):.4f}, max speed {rep.max_speed:.4f})"


def _rows_fit(scene, rows, path, key="waypoints") -> None:
    """Rows of the wrong width for the scene's robot are bad input (for check as for
    render and export): a trajectory planned for another robot, not an invalid one."""
    if rows is not None and rows.shape[1] != scene.robot.dof + 1:
        from ..poses import row_words

        raise BadInput(
            f"{path}: {key}: rows of {rows.shape[1]} numbers, but scene "
            f"{scene.name!r} expects {row_words(scene.robot.dof, scene.robot)}"
        )


def _query_of(scene, tf):
    """The scene's query a trajectory file names, or None (an ad-hoc query)."""
    try:
        return scene.query(tf.query) if tf.query else None
    except KeyError:
        return None


def _violation(scene, tf, path, anyway="drawing it anyway"):
    """(time, reason) of a drawn or exported trajectory's first violation of the guarantees,
    told on stderr (render and export go on, `check` exits 1 on it); None when it is valid
    (a ``duration`` that disagrees with its rows then noted, as `check` says it)."""
    from ..check.check import check_trajectory

    query = _query_of(scene, tf)
    rep = check_trajectory(scene, tf.waypoints, query)
    if rep.valid:
        if wrong := _duration_disagrees(tf):  # as `check` says it (it said nothing here)
            _say(f"note: {path}: {wrong} (`gfuzzy check` exits 1); {anyway}")
        return None
    _say(f"note: {path}: invalid: {rep.reason} (`gfuzzy check` exits 1); {anyway}")
    return None if rep.time is None else (rep.time, rep.reason)


def cmd_render(args) -> int:
    from ..render.render import render
    from ..roadmap.roadmap import load_roadmap
    from ..trajectory import load_trajectory

    scene = _apply_overrides(_load_scene(args.scene), args)
    reads = (*_scene_reads(scene), (args.trajectory, "trajectory"), *_roadmap_reads(scene, args))
    out = _out_path(args.output, (".png", ".gif"), reads)
    traj = None
    nav_doc: dict = {}
    if args.trajectory:
        tf = load_trajectory(args.trajectory)
        nav_doc = _navigate_extras(scene, tf, args.trajectory)
        traj = tf.waypoints if tf.waypoints is not None else nav_doc.get("executed")
        _rows_fit(scene, tf.waypoints, args.trajectory)
        if traj is None:
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

    from ..collision.geometry import mover_distance

    start = np.asarray(query.start, dtype=float)
    for mv in scene.movers:
        xy, present = mv.state(np.array([query.t0]))
        if present[0] and mover_distance(scene.robot, start, mv.shape, mv.radius, mv.size, xy[0]) < 0:
            return f"start collides with mover {mv.name!r} at t0={query.t0:g}"
    return ""


def _navigate_extras(scene, tf, path) -> dict:
    """The ``executed`` rows (:func:`gfuzzy.trajectory.executed_rows`, of the robot's width)
    and ``replan_log`` of a ``gfuzzy navigate`` file (else {}), for render and export."""
    from ..trajectory import executed_rows, replan_entries

    out = {}
    rows = executed_rows(tf, path)
    if rows is not None:
        _rows_fit(scene, rows, path, "executed")
        out["executed"] = rows
    log = tf.extra.get("replan_log")
    if log is not None:
        out["replan_log"] = replan_entries(log, path)
    return out


def cmd_regress(args) -> int:
    from ..runs.regress import run_regression

    scenes = [_apply_overrides(_load_scene(p), args) for p in args.scenes]  # all bad input first
    options = _plan_options(args)
    _check_roadmap_flags(args)  # before the table's header: bad input prints nothing else
    try:
        ok = run_regression(scenes, lambda sc: _roadmap_for(sc, args), options, sys.stdout)
    except TimeStepError as exc:  # the option's fault, not the first query's
        raise BadInput(f"gfuzzy regress: --dt {options.dt:g}: {exc}") from None
    except LimitError as exc:  # a request beyond the memory bounds (a hold of 1e6 s): names file and query
        raise BadInput(str(exc)) from None
    return EXIT_OK if ok else EXIT_NO


