"""The commands around planning: ``tracks`` (a scene from pedestrian data), ``batch``
(every query on Dask), ``navigate`` (online, without knowing the movers' future)."""

from __future__ import annotations

import contextlib
import math
import sys
from pathlib import Path

from ..errors import InputError, SceneError, TimeStepError
from ..status import Status
from .common import (
    EXIT_NO,
    EXIT_OK,
    BadInput,
    _apply_overrides,
    _check_numbers,
    _check_sensor_flags,
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
    _sense,
    _soft_options,
)
from .planning import _start_on_mover


def _tracks_command(args) -> str:
    """The `gfuzzy tracks` command that makes the same scene (for the scene's header)."""
    import shlex

    def g(v) -> str:
        return v if isinstance(v, str) else (str(int(v)) if float(v).is_integer() else repr(float(v)))

    parts = ["gfuzzy", "tracks", args.file]
    for flag, value in (("--format", None if args.format == "auto" else args.format), ("--fps", args.fps),
                        ("--t-start", args.t_start), ("--duration", args.duration), ("--region", args.region),
                        ("--scale", None if args.scale == 1.0 else args.scale), ("--offset", args.offset),
                        ("--radius", None if args.radius == 0.25 else args.radius), ("--max-movers", args.max_movers),
                        ("--max-gap", args.max_gap),
                        ("--static", args.static), ("--name", args.name), ("--robot-radius", args.robot_radius),
                        ("--vmax", args.vmax), ("--amax", args.amax), ("--kinematics", args.kinematics),
                        ("--wmax", args.wmax), ("--start", args.start), ("--goal", args.goal),
                        ("--query-name", None if args.query_name == "cross" else args.query_name),
                        ("--expect", args.expect), ("--max-duration", args.max_duration), ("-o", args.output)):  # fmt: skip
        if value is not None:
            parts += [flag, *(g(v) for v in (value if isinstance(value, list) else [value]))]
    if args.reverse:
        parts.insert(-2, "--reverse")  # before -o OUT
    return " ".join(shlex.quote(a) for a in parts)


def cmd_tracks(args) -> int:
    from ..atomic import write_atomic
    from ..scene.scene import _load_yaml, parse_scene
    from ..scene.tracks import TrackSceneOptions, read_tracks, robot_dof, tracks_scene
    from ..scene.yamldoc import name_from_stem

    static = _load_scene(args.static) if args.static else None
    reads = ((args.file, "tracks file"), *(_scene_reads(static) if static is not None else ()))
    out = _out_path(args.output, (".yaml", ".yml"), reads)
    try:
        options = TrackSceneOptions(
            t_start=args.t_start,
            duration=args.duration,
            region=tuple(args.region) if args.region else None,
            scale=args.scale,
            offset=tuple(args.offset) if args.offset else (0.0, 0.0),
            radius=args.radius,
            max_movers=args.max_movers,
            max_gap=args.max_gap,
            name=args.name or name_from_stem(out.stem, "tracks"),
            robot_radius=args.robot_radius,
            vmax=args.vmax,
            amax=args.amax,
            kinematics=args.kinematics,
            reverse=args.reverse,
            wmax=args.wmax,
        )
        tracks = read_tracks(args.file, args.format, args.fps)
        if args.start is None and args.query_name != "cross":
            raise InputError("--query-name names the query of --start and --goal: give them too")
        dof = robot_dof(static, args.robot_radius, args.kinematics)
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


def _sealed_off(scene, roadmap, query) -> str:
    """Why no way joins the query's start and goal on the roadmap among the static obstacles,
    as ``plan`` says it (its no_path message: a disc robot's free space holds them in separate
    regions; another robot's roadmap does not join them, nor does a bridge to it), or ""."""
    import numpy as np

    from ..planner.planner import Planner, PlanOptions
    from ..poses import wrap_angle

    start, goal = np.array(query.start, dtype=float), np.array(query.goal, dtype=float)
    if len(start) == 3:  # as plan wraps them before it asks
        start[2], goal[2] = wrap_angle(start[2]), wrap_angle(goal[2])
    linked, message = Planner(scene, roadmap).through_free_space(start, goal, PlanOptions().connect_k)
    return "" if linked is not None else message


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


def _trajectories_read(folder, scenes, reads) -> None:
    """Bad input when a trajectory file ``batch --trajectories`` would write is a file it reads,
    or a folder (found only once every query had run: the whole table lost), or the file of
    two queries (scene ``a-b`` query ``c``, scene ``a`` query ``b-c``: one answer lost)."""
    from ..runs.batch import trajectory_path

    seen: dict = {}
    for sc in scenes:
        for q in sc.queries:
            path = trajectory_path(folder, sc.name, q.name)
            _refuse_overwrite(path, [path], reads)
            if Path(path).is_dir():
                raise BadInput(f"--trajectories {folder}: {path} is a folder, not a file")
            if path in seen:
                raise BadInput(f"--trajectories {folder}: {path} would hold the answers of both "
                               f"{seen[path]} and scene {sc.name!r} query {q.name!r}")  # fmt: skip
            seen[path] = f"scene {sc.name!r} query {q.name!r}"


def _connect(address: str, timeout: float):
    """A Dask client of the scheduler at ``address`` (bad input when it cannot connect)."""
    from distributed import Client

    try:
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError) as exc:
        raise BadInput(f"--scheduler {address}: cannot connect: {' '.join(str(exc).split())[:120]}") from None
    except Exception as exc:  # noqa: BLE001 - something answered that does not speak Dask's protocol
        # (an HTTP server, Dask's dashboard port: its reply read as a frame length is an
        # exabyte to allocate)
        raise BadInput(
            f"--scheduler {address}: cannot connect: what answers there is not a Dask scheduler "
            f"({type(exc).__name__}: {' '.join(str(exc).split())[:80]}); its address is tcp://HOST:8786 by default"
        ) from None


def cmd_batch(args) -> int:
    """Every query of every scene on Dask; exit 0 all ran, 1 any error row, 130 interrupted
    (143 after a SIGTERM).

    Ctrl-C once the scenes are read (building a roadmap, starting the cluster, between or
    after the queries) writes the rows finished so far, perhaps none, and says so.
    """
    import time

    from ..errors import (
        check_interrupt,
        interrupt_pending,
        interrupted_status,
        interrupts_deferred,
        is_interrupt,
    )
    from ..runs.batch import (
        MAX_LOCAL_WORKERS,
        BatchOptions,
        BatchResult,
        quiet_dask_logs,
        write_table,
    )

    if args.workers is not None and args.workers < 1:
        raise BadInput(f"gfuzzy batch: --workers must be at least 1 (local worker processes), got {args.workers}")
    if args.workers is not None and args.workers > MAX_LOCAL_WORKERS:
        raise BadInput(f"gfuzzy batch: --workers must be at most {MAX_LOCAL_WORKERS} (local worker processes), "
                       f"got {args.workers}")  # fmt: skip
    scenes = [_apply_overrides(_load_scene(p), args) for p in args.scenes]  # all bad input first
    reads = tuple(r for sc in scenes for r in (*_scene_reads(sc), *_roadmap_reads(sc, args)))
    out = _out_path(args.output, (".csv",), reads, beside=(".parquet",))
    _writable_folder(out.parent, "-o")
    if args.trajectories:
        _writable_folder(Path(args.trajectories), "--trajectories")
        _trajectories_read(args.trajectories, scenes, reads)
    seen: dict = {}
    for path, sc in zip(args.scenes, scenes, strict=True):
        if sc.name in seen:
            raise BadInput(f"{path}: name: scene name {sc.name!r} repeats that of {seen[sc.name]}")
        seen[sc.name] = path
    options = BatchOptions(plan=_plan_options(args), trajectories=args.trajectories)
    if not args.verbose:  # Dask's own INFO/WARNING lines (a worker restarting) are not ours to show,
        quiet_dask_logs(errors=True)  # nor tornado's (Dask's callbacks failing as Ctrl-C cuts a wait)
    ran: list = []  # (BatchResult, where, t) once run_batch returns: kept if the cluster's closing is cut
    try:
        _batch_result(args, scenes, options, ran)
        check_interrupt()
        result, where, t = ran[0]
    except BaseException as exc:  # noqa: BLE001 - Ctrl-C outside run_batch: the rows it finished
        if not is_interrupt(exc):
            raise
        total = sum(len(sc.queries) for sc in scenes)
        result = BatchResult(ran[0][0].rows if ran else [], total, interrupted=True)
    # Ctrl-C (again) now: the CSV and the Parquet both, not one; said once, on the last line
    with interrupts_deferred(raise_after=False):
        written = write_table(result.rows, out)
        if result.interrupted or interrupt_pending():  # a Ctrl-C while the table was written too
            _say(
                f"interrupted: wrote the {len(result.rows)} finished of {result.total} queries "
                f"to {', '.join(map(str, written))}"
            )
            return interrupted_status()
    check_interrupt()  # one that came as the section ended
    _report_batch(result, where, time.perf_counter() - t, written)
    return EXIT_NO if result.errors else EXIT_OK


def _batch_result(args, scenes, options, ran: list) -> None:
    """Append (BatchResult, where it ran, when the queries started) to ``ran``: each scene's
    roadmap built or loaded in the client, then every query on Dask.

    The result is in ``ran`` before the client and cluster close, so a Ctrl-C while they
    close (raised once they are closed) keeps every row.
    """
    import time

    from ..runs.batch import check_time_steps, closed_whole, local_cluster, run_batch

    with contextlib.ExitStack() as stack:
        if args.scheduler:  # connected, or refused, before any roadmap is built or loaded
            client = stack.enter_context(closed_whole(_connect(args.scheduler, args.connect_timeout)))
            where = f"the cluster at {args.scheduler}"
        pairs = [(sc, _roadmap_for(sc, args)) for sc in scenes]  # once per scene, in the client
        try:  # a dt too fine for a roadmap fails every query alike: said once, before any runs
            check_time_steps(pairs, options.plan)
        except TimeStepError as exc:  # the option's fault, said as plan, regress and navigate say it
            raise BadInput(f"gfuzzy batch: --dt {options.plan.dt:g}: {exc}") from None
        t = time.perf_counter()
        if not args.scheduler:
            workers = args.workers or 2
            where = f"{workers} local worker(s)"
            client = stack.enter_context(local_cluster(workers, quiet=not args.verbose))
        ran.append((run_batch(client, pairs, options, progress=_progress("queries")), where, t))


def _report_batch(result, where: str, seconds: float, written) -> None:
    """The summary line (stdout) and each error row or invalid answer (stderr)."""
    counts: dict = {}
    for r in result.rows:
        counts[r.status] = counts.get(r.status, 0) + 1
    summary = ", ".join(f"{n} {s}" for s, n in sorted(counts.items()))
    invalid = sum(r.check == "invalid" for r in result.rows)
    _say(
        f"{result.total} queries on {where} in {seconds:.1f} s: {summary or 'none'}"
        f"{f', {invalid} INVALID' if invalid else ''}; wrote {', '.join(map(str, written))}",
        sys.stdout,
    )
    for r in result.rows:
        if not r.ran:
            _say(f"{r.scene} {r.query}: error: {r.error}")
            if r.traceback:  # a bug, not a bad input: show where it happened
                _say("  " + r.traceback.rstrip().replace("\n", "\n  "))
        elif r.check == "invalid":  # a planner defect: reported, but the query did run
            _say(f"{r.scene} {r.query}: the answer fails the check (see `gfuzzy check`)")

def _sensor_options(args):
    """The sensor of ``gfuzzy navigate`` (section 7) from its flags."""
    from ..navigation.sensing import SensorOptions

    _check_sensor_flags(args)
    velocity = "exact" if args.velocity == "true" else "estimated"
    return SensorOptions(velocity=velocity, noise=args.noise, fov=args.fov, occlusion=args.occlusion,
                         seed=1 if args.seed is None else args.seed)  # fmt: skip


def _navigate_options(args):
    """``gfuzzy navigate``'s flags checked: the navigator's options, the sensor's, the range.

    Every number by the one rule of ``check_number`` under its flag's name (positive or at
    least zero, at most 1e9; ``--dt`` as ``plan`` names it, ``dt``), and the run one that can
    finish (``navsim.check_run``)."""
    from ..navigation.navigator import NavOptions
    from ..navigation.navsim import check_run

    _check_numbers("navigate", positive=(("--period", args.period), ("--max-time", args.max_time),
                                         ("--time-budget", args.time_budget)),
                   at_least_zero=(("--personal-space", args.personal_space), ("--path-space", args.path_space),
                                  ("--log-every", args.log_every)))  # fmt: skip
    sense = _sense("navigate", args.sense)
    try:
        check_run(args.period, args.max_time, ("--period", "--max-time"))
        options = NavOptions(dt=args.dt, time_budget=args.time_budget, backend=args.backend,
                             budget_clock=args.budget_clock, personal_space=args.personal_space,
                             path_space=args.path_space, **_soft_options(args))  # fmt: skip
        return options, _sensor_options(args), sense
    except InputError as exc:
        raise BadInput(f"gfuzzy navigate: {exc}") from None


def _run_settings(args, options, seed: int, sense: float) -> dict:
    """The ``navigate`` key of a run's file: every setting that changes the run (the sensor's,
    the loop's, the navigator's options as the flags set them), so that two files say how
    they differ; ``intrusion_cost`` is null without ``--soft-search`` (nothing is priced)."""
    return {
        "period": args.period, "sense": None if math.isinf(sense) else sense, "max_time": args.max_time,
        "velocity": args.velocity, "noise": args.noise, "fov": args.fov, "occlusion": args.occlusion,
        "seed": seed, "budget_clock": options.budget_clock, "time_budget": options.time_budget,
        "dt": options.dt, "backend": options.backend, "personal_space": options.personal_space,
        "path_space": options.path_space, "soft_search": options.soft_search,
        "intrusion_cost": options.intrusion_cost if options.soft_search else None,
    }  # fmt: skip


def _navigate_query(scene, name: str | None):
    """The query ``--query`` names, or the scene's first."""
    if name:
        try:
            return scene.query(name)
        except KeyError as exc:
            raise BadInput(f"{scene.source}: queries: {exc.args[0]}") from None
    if not scene.queries:
        raise BadInput(f"{scene.source}: queries: the scene has no queries to navigate")
    return scene.queries[0]


def cmd_navigate(args) -> int:
    """Drive the robot among the scene's movers without knowing their future (section 5)."""
    import numpy as np

    from ..check.check import check_trajectory
    from ..collision.geometry import StaticGeometry
    from ..navigation.lookout import knowing_view
    from ..navigation.navigator import Navigator
    from ..navigation.navsim import simulate
    from ..planner.planner import query_problem
    from ..trajectory import TrajectoryFile

    scene = _apply_overrides(_load_scene(args.scene), args)
    options, sensor, sense = _navigate_options(args)
    query = _navigate_query(scene, args.query)
    reads = (*_scene_reads(scene), *_roadmap_reads(scene, args))
    out = _out_path(args.output, (".json",), reads) if args.output else None
    problem = query_problem(StaticGeometry(scene), query.start, query.goal) or _start_on_mover(scene, query)
    if problem:
        tf = TrajectoryFile(scene.name, query.name, Status.INVALID_QUERY, problem, None, None, None, 0.0)
        if out is not None:
            tf.save(out)
        _say(f"{scene.name} {query.name}: invalid_query ({problem})", sys.stdout)
        return EXIT_NO
    roadmap = _roadmap_for(scene, args)
    try:
        nav = Navigator(scene, roadmap, query.goal, knowing_view(options, sensor.fov) if sensor else options)
    except TimeStepError as exc:  # the option's fault, said as regress and plan say it
        raise BadInput(f"gfuzzy navigate: --dt {args.dt:g}: {exc}") from None
    rd = nav.roadmap_distance(np.asarray(query.start, dtype=float))
    sealed = "" if math.isfinite(rd) else _sealed_off(scene, roadmap, query)
    if sealed:  # no mover opens a way: replanning until --max-time (up to 100000 replans: hours) changes nothing
        tf = TrajectoryFile(scene.name, query.name, Status.NO_PATH, sealed, None, None, None, 0.0)
        if out is not None:
            tf.save(out)
        _say(f"{scene.name} {query.name}: no_path ({sealed})", sys.stdout)
        return EXIT_NO
    straight = math.dist(query.start[:2], query.goal[:2])
    slow = _beyond_max_time(rd, scene.robot.vmax, args.max_time, straight)
    if slow:  # said before the run: it will time out whatever the movers do
        _say(f"note: {slow}")
    if args.period >= args.max_time:  # --period 1e300 ran one plan blind into a mover, saying nothing
        _say(f"note: --period {args.period:g} s is not shorter than --max-time {args.max_time:g} s: the robot "
             "observes and plans once, at the start, and follows that plan without looking again")  # fmt: skip
    res = simulate(
        scene, roadmap, query.start, query.goal, query.t0, args.period, sense, args.max_time,
        navigator=nav, log_every=args.log_every, sensor=sensor,
    )
    wps = res.trajectory.waypoints
    report = check_trajectory(scene, wps, query if res.reached else None)
    rd_ok = math.isfinite(rd)
    solved = res.reached
    message = "" if solved else f"the goal was not reached within {args.max_time:g} s" + (f" ({slow})" if slow else "")
    if not report.valid:
        message = (message + "; " if message else "") + f"the executed trajectory is invalid: {report.reason}"
    extra = {
        "replans": res.replans,
        "replan_seconds_p50": round(res.latency(0.5), 6),
        "replan_seconds_p95": round(res.latency(0.95), 6),
        "replan_seconds_max": round(float(res.replan_seconds.max(initial=0.0)), 6),
        "min_separation": res.min_separation if math.isfinite(res.min_separation) else None,
        "discomfort_frequency": round(res.social.discomfort_frequency, 6),
        "intrusion_ratio": round(res.social.intrusion_ratio, 6),
        "check": {"valid": report.valid, "reason": report.reason},
        "modes": res.modes,
        "replans_out_of_time": res.out_of_time,
        "navigate": _run_settings(args, options, sensor.seed, sense),
        "replan_log": res.log,
    }
    if not solved:  # only a solved file carries waypoints (section 2): the motion goes here
        extra["executed"] = [[float(v) for v in row] for row in wps]
    tf = TrajectoryFile(
        scene=scene.name,
        query=query.name,
        status=Status.SOLVED if solved else Status.TIMEOUT,
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
    _say(f"{scene.name} {query.name}: {_navigate_summary(res, report)}", sys.stdout)
    gone = _after_the_movers(scene, float(wps[-1, 0]))
    if gone:
        _say(f"note: {gone}")
    if res.out_of_time and 2 * res.out_of_time >= res.replans:  # the run lived on its fallbacks: say why
        _say(f"note: {res.out_of_time} of {res.replans} replans ran out of --time-budget {options.time_budget:g} s "
             f"before their search answered (the robot made fallback motions instead): give it more time "
             f"(--time-budget), a smaller roadmap (-n), or, for a differential drive, a larger wmax")
    return EXIT_OK if (solved and report.valid) else EXIT_NO


def _after_the_movers(scene, t_end: float) -> str:
    """Why a run's end was among nobody: every mover's recorded motion (``gfuzzy populate``'s
    ``--duration``, a tracks window) ended before the robot stopped at ``t_end``; "" when
    someone is there to the end (a path mover is there always) or there are no movers."""
    ends = [m.time_range[1] for m in scene.movers]
    if not ends or max(ends) >= t_end:
        return ""
    return (f"every mover's recorded motion ends by t = {max(ends):g} s and the robot drove on to "
            f"t = {t_end:g} s among nobody: record longer (gfuzzy populate --duration, a longer tracks window)")


def _navigate_summary(res, report) -> str:
    """``navigate``'s one line on a run: the outcome, the replans' times, the distances kept, the check."""
    sep = "none seen" if not math.isfinite(res.min_separation) else f"{res.min_separation:.3f} m"
    return (
        (f"solved in {res.duration:.2f} s" if res.reached else "timeout")
        + f", {res.replans} replans (p95 {res.latency(0.95) * 1000:.0f} ms, max "
        f"{float(res.replan_seconds.max(initial=0.0)) * 1000:.0f} ms), min separation {sep}, "
        f"discomfort {res.social.discomfort_frequency:.3f}, intrusion {res.social.intrusion_ratio:.3f}, "
        f"check {'valid' if report.valid else 'INVALID: ' + report.reason}"
    )


def _beyond_max_time(rd: float, vmax: float, max_time: float, straight: float) -> str:
    """Why a navigate run is unlikely to arrive within ``--max-time``: the shortest roadmap
    route ``rd`` takes longer at ``vmax`` (a 500 m hall timed out after the default 120 s
    saying only "not reached"); "" when it does not. Only the ``straight`` line from start
    to goal is a lower bound ("at least"): the robot may leave the roadmap (the direct
    motion, a differential drive's fan, whose roadmap distance also counts its turns)."""
    fastest = rd / vmax
    if not math.isfinite(fastest) or fastest <= max_time:
        return ""
    if straight / vmax > max_time:
        least = math.ceil(straight / vmax * 100.0) / 100.0  # rounded up: 3.004 s is "3.01", never "3.0"
        return (f"the goal is {straight:.1f} m away in a straight line: at least {least:g} s at vmax "
                f"{vmax:g}, more than --max-time {max_time:g} s: give a larger --max-time")
    return (f"the shortest roadmap route ({rd:.1f} m) takes {fastest:.1f} s at vmax {vmax:g}, more than --max-time "
            f"{max_time:g} s (only a shorter way off the roadmap can arrive in time): give a larger --max-time")


