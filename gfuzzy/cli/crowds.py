"""The crowd commands: ``crowd`` (the crowd navigation benchmarks, CONTRACT.md section 7)
and ``populate`` (walking people for a scene)."""

from __future__ import annotations

import math
import sys

from ..errors import InputError
from .common import (
    EXIT_OK,
    BadInput,
    _check_numbers,
    _check_sensor_flags,
    _load_scene,
    _navigator_flags,
    _out_path,
    _say,
    _scene_reads,
    _sense,
    _soft_options,
)


def add_crowd(sub) -> None:
    """``gfuzzy crowd``."""
    c = sub.add_parser("crowd", help="crowd navigation benchmarks (CrowdNav circle/square, CrowdNav++ arena)")
    c.add_argument("--scenario", choices=("circle", "square", "arena"), default="circle",
                   help="circle or square crossing (CrowdNav), or the CrowdNav++ arena (default circle)")  # fmt: skip
    c.add_argument("--humans", type=int, metavar="K", help="number of humans (default 5; 20 in the arena)")
    c.add_argument("--visible", action="store_true", help="the humans see the robot and react to it")
    c.add_argument("--steady-goals", action="store_true",
                   help="arena: humans change goal only on arrival, not every 5 s at random (CrowdNav++'s "
                        "non-randomised test)")  # fmt: skip
    c.add_argument("--crowd", choices=("orca", "social-force"), default="orca", help="how the humans move (default orca)")
    c.add_argument("--kinematics", choices=("holonomic", "unicycle"), default="holonomic",
                   help="the robot's kinematics (unicycle: a differential drive turning at most 1 rad/s, navigator only)")
    c.add_argument("--reverse", action="store_true",
                   help="unicycle: the robot may also drive backwards (default: forwards only)")
    c.add_argument("--episodes", type=int, default=100, metavar="N", help="episodes (default 100)")
    c.add_argument("--seed", type=int, default=1, help="the run's seed: same seed, same episodes (default 1)")
    c.add_argument("--policy", nargs="+", choices=("navigator", "orca", "social-force", "oracle"),
                   help="robot policies (default: navigator orca, and oracle when the humans do not see the robot)")  # fmt: skip
    c.add_argument("--workers", type=int, default=0, metavar="W",
                   help="episodes on a local Dask cluster of W processes (default 0: in this process)")  # fmt: skip
    c.add_argument("--velocity", choices=("estimated", "true"), default="estimated",
                   help="humans' velocity: estimated from positions one step apart (default), or their true one")  # fmt: skip
    c.add_argument("--noise", type=float, default=0.0, help="Gaussian noise (m) on observed positions")
    c.add_argument("--fov", type=float, default=360.0, help="field of view (degrees) about the direction of motion")
    c.add_argument("--sense", type=float, help="sensing range (m; default: all, 5 in the arena)")
    c.add_argument("--time-budget", type=float, default=0.1, help="seconds one navigator replan may take (default 0.1)")
    _navigator_flags(c)
    c.add_argument("--dt", type=float, default=0.1, help="the navigator's search time step (s; default 0.1)")
    c.add_argument("--full-speed", action="store_true",
                   help="the navigator runs its plans at full speed up to their first wait (NavOptions.full_speed)")
    c.add_argument("-o", "--output", metavar="RESULTS.csv", help="one row per episode and policy")
    c.set_defaults(func=cmd_crowd)


def _progress_bar(label: str):
    """A progress bar on stderr (drawn only on a terminal)."""
    if not sys.stderr.isatty():
        return None

    def cb(done: int, total: int) -> None:
        width = 30
        fill = int(width * done / max(total, 1))
        sys.stderr.write(f"\r{label} [{'#' * fill}{'.' * (width - fill)}] {done}/{total}")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()

    return cb


def _setting(args):
    from ..navigation.crowd import MAX_EPISODES, CrowdSetting
    from ..navigation.navigator import NavOptions
    from ..navigation.sensing import SensorOptions
    from ..runs.batch import MAX_LOCAL_WORKERS

    humans = args.humans if args.humans is not None else (20 if args.scenario == "arena" else 5)
    if humans < 0 or humans > 200:
        raise BadInput(f"gfuzzy crowd: --humans must be between 0 and 200, got {humans}")
    if not 1 <= args.episodes <= MAX_EPISODES:
        raise BadInput(f"gfuzzy crowd: --episodes must be between 1 and {MAX_EPISODES}, got {args.episodes}")
    if not 0 <= args.workers <= MAX_LOCAL_WORKERS:  # 0: in this process
        raise BadInput(f"gfuzzy crowd: --workers must be between 0 and {MAX_LOCAL_WORKERS}, got {args.workers}")
    if args.seed < 0:  # numpy refuses it deep in the first episode
        raise BadInput(f"gfuzzy crowd: --seed must be >= 0, got {args.seed}")
    _check_numbers("crowd", positive=(("--time-budget", args.time_budget), ("--dt", args.dt)),
                   at_least_zero=(("--personal-space", args.personal_space), ("--path-space", args.path_space)))
    try:
        _check_sensor_flags(args)
    except InputError as exc:
        raise BadInput(f"gfuzzy crowd: {exc}") from None
    sense = _sense("crowd", args.sense)
    if args.reverse and args.kinematics != "unicycle":
        raise BadInput("gfuzzy crowd: --reverse needs --kinematics unicycle")
    if args.steady_goals and args.scenario != "arena":  # only the arena's humans change goals
        raise BadInput(f"gfuzzy crowd: --steady-goals needs --scenario arena (the {args.scenario}'s humans never change goals)")
    try:
        sensor = SensorOptions(velocity="exact" if args.velocity == "true" else "estimated", noise=args.noise,
                               fov=args.fov, sense=sense, seed=args.seed)  # fmt: skip
        setting = CrowdSetting(args.scenario, humans, args.visible, args.crowd, args.kinematics, sensor,
                               not args.steady_goals, args.reverse)  # fmt: skip
        options = NavOptions(time_budget=args.time_budget, personal_space=args.personal_space,
                             path_space=args.path_space, budget_clock=args.budget_clock, full_speed=args.full_speed,
                             dt=args.dt, **_soft_options(args))  # fmt: skip
    except InputError as exc:
        raise BadInput(f"gfuzzy crowd: {exc}") from None
    policies = args.policy or (["navigator", "orca"] + ([] if args.visible else ["oracle"]))
    if args.kinematics == "unicycle":
        if args.policy and set(args.policy) - {"navigator", "oracle"}:
            raise BadInput("gfuzzy crowd: with --kinematics unicycle only --policy navigator and oracle run")
        policies = args.policy or (["navigator"] + ([] if args.visible else ["oracle"]))
    if "oracle" in policies and args.visible:
        raise BadInput("gfuzzy crowd: --policy oracle needs humans who do not see the robot (drop --visible)")
    return setting, options, list(dict.fromkeys(policies))


def _table(setting, runs, policies) -> str:
    from ..navigation.crowdsummary import summarize

    head = (f"{'policy':<13}{'n':>5}{'success':>9}{'collide':>9}{'timeout':>9}{'time s':>8}{'discomf':>9}"
            f"{'intrus':>8}{'min sep':>9}{'p50 ms':>8}{'p95 ms':>8}")  # fmt: skip
    lines = [
        f"{setting.scenario}, {setting.humans} humans ({setting.crowd}, {'visible' if setting.visible else 'invisible'}),"
        f" {setting.kinematics}{' (reverse)' if setting.reverse else ''} robot, velocity {setting.sensor.velocity}, noise {setting.sensor.noise:g} m,"
        f" fov {setting.sensor.fov:g} deg, sense {setting.sense:g} m"
        + (", goals change on arrival only" if setting.scenario == "arena" and not setting.goal_changes else ""),
        head,
    ]
    for p in policies:
        s = summarize(runs, p)

        def f(v, fmt):
            return f"{v:{fmt}}" if math.isfinite(v) else "-"

        lines.append(
            f"{p:<13}{s.episodes:>5}{f(s.success, '9.3f')}{f(s.collision, '9.3f')}{f(s.timeout, '9.3f')}"
            f"{f(s.time, '8.2f'):>8}{f(s.discomfort, '9.3f')}{f(s.intrusion, '8.3f')}{f(s.min_separation, '9.3f'):>9}"
            f"{f(s.replan_p50 * 1e3, '8.1f'):>8}{f(s.replan_p95 * 1e3, '8.1f'):>8}"
        )
        if s.modes:
            lines[-1] += "   " + " ".join(f"{m}:{v}" for m, v in s.modes)
    return "\n".join(lines)


def _write_csv(path, setting, runs, seed: int) -> None:
    import csv
    import io

    from ..atomic import write_atomic
    from ..navigation.crowd import CSV_COLUMNS

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    w.writeheader()
    for run in runs:
        for e in run:
            w.writerow(e.row(setting, seed))
    write_atomic(path, buf.getvalue())


def _need_pyrvo(command: str) -> None:
    try:
        import pyrvo  # noqa: F401
    except ImportError:
        raise BadInput(f"gfuzzy {command}: ORCA people need pyrvo: pip install 'gfuzzy[crowd]'") from None


def _placeable(setting, seed: int, count: int) -> None:
    """Draw every episode's layout before any runs (a few ms each): a count of humans
    the protocol cannot place is refused at once, not in the middle of the run."""
    from ..navigation.crowd import episode_layout

    try:
        for i in range(count):
            episode_layout(setting, seed, i)
    except InputError as exc:
        raise BadInput(f"gfuzzy crowd: {exc}") from None


def cmd_crowd(args) -> int:
    """Run the crowd benchmark; print the table of section 7; write the CSV."""
    import contextlib

    from ..navigation.crowd import crowd_roadmap, episodes

    setting, options, policies = _setting(args)
    _need_pyrvo("crowd")
    out = _out_path(args.output, (".csv",)) if args.output else None
    _placeable(setting, args.seed, args.episodes)
    roadmap = crowd_roadmap(setting)
    bar = _progress_bar(f"crowd {setting.scenario} x{args.episodes}")
    if args.workers:
        from ..runs.batch import local_cluster

        ctx = local_cluster(args.workers)
    else:
        ctx = contextlib.nullcontext(None)
    with ctx as client:
        runs = episodes(setting, roadmap, args.seed, args.episodes, policies, options, client, bar)
    if out is not None:
        _write_csv(out, setting, runs, args.seed)
    _say(_table(setting, runs, policies), sys.stdout)
    return EXIT_OK


def add_populate(sub) -> None:
    """``gfuzzy populate``."""
    p = sub.add_parser("populate", help="add walking people (ORCA among the static obstacles) to a scene")
    p.add_argument("scene", metavar="SCENE", help="scene file (YAML) to add the people to")
    p.add_argument("--people", type=int, required=True, metavar="N", help="number of people")
    p.add_argument("--seed", type=int, default=1, help="seed of their starts, goals and walks (default 1)")
    p.add_argument("--duration", type=float, default=60.0, help="seconds of walking recorded (default 60)")
    p.add_argument("--radius", type=float, default=0.3, help="the people's radius (m, default 0.3)")
    p.add_argument("--speed", type=float, default=1.0, help="their preferred speed (m/s, default 1)")
    p.add_argument("--waypoints", metavar="X,Y;X,Y;...", help="walk between these points instead of random free ones")
    p.add_argument("-o", "--output", required=True, metavar="OUT.yaml", help="the scene with the people added")
    p.set_defaults(func=cmd_populate)


def _cut_note(asked: int, result) -> str:
    """What became of the people cut short: those whose walk stops early are in the file,
    those whose very first step was cut are not (the count of people written said nothing
    of them)."""
    gone = asked - len(result.movers)
    notes = []
    if result.cut - gone:
        notes.append(f"{result.cut - gone} of them stop short, where ORCA would take them into an obstacle")
    if gone:
        notes.append(f"{gone} more left out, whose first step it would")
    return f" ({'; '.join(notes)})" if notes else ""


def _waypoints_named(message: str, exc: InputError, scene: str) -> str:
    """``message``, or, for an error about ``PopulateOptions.waypoints`` (``waypoints[2] ...``),
    the same said of ``--waypoints`` (its point counted from 1) and the scene file; one about
    ``people`` or ``duration`` said of their flags."""
    import re

    m = re.match(r"waypoints(?:\[(\d+)\])? (.*)", str(exc))
    if m is None:  # PopulateOptions' people and duration are the flags --people and --duration
        return re.sub(r"^gfuzzy populate: (people|duration) ", r"gfuzzy populate: --\1 ", message)
    which = f" point {int(m[1]) + 1}" if m[1] is not None else ""
    return f"{scene}: --waypoints:{which} {m[2]}"


def cmd_populate(args) -> int:
    """Write a copy of the scene with ``--people`` walking people as trajectory movers."""
    from ..navigation.populate import PopulateOptions, populate, scene_copy, write_scene

    scene = _load_scene(args.scene)
    _check_numbers("populate", positive=(("--duration", args.duration), ("--radius", args.radius),
                                         ("--speed", args.speed)))  # fmt: skip
    _need_pyrvo("populate")
    out = _out_path(args.output, (".yaml", ".yml"), _scene_reads(scene))
    copy = scene_copy(args.scene, out)  # a folder that does not hold the scene's files: before the work
    waypoints = None
    if args.waypoints:
        try:
            waypoints = [tuple(float(v) for v in p.split(",")) for p in args.waypoints.split(";") if p.strip()]
        except ValueError:
            raise BadInput(f"gfuzzy populate: --waypoints: expected X,Y;X,Y;..., got {args.waypoints!r}") from None
        if any(len(p) != 2 for p in waypoints) or len(waypoints) < 2:
            raise BadInput("gfuzzy populate: --waypoints: give at least two points X,Y")
    try:
        opts = PopulateOptions(people=args.people, seed=args.seed, duration=args.duration, radius=args.radius,
                               speed=args.speed, waypoints=tuple(waypoints) if waypoints else None)  # fmt: skip
    except InputError as exc:
        raise BadInput(_waypoints_named(f"gfuzzy populate: {exc}", exc, args.scene)) from None
    try:
        result = populate(scene, opts)
    except InputError as exc:  # a point outside the bounds or not free; no room for them all
        raise BadInput(_waypoints_named(f"gfuzzy populate: {exc}", exc, args.scene)) from None
    write_scene(args.scene, result, out, copy)
    _say(f"{out}: {len(result.movers)} people walking for {args.duration:g} s added to {scene.name}"
         f"{_cut_note(args.people, result)}", sys.stdout)  # fmt: skip
    return EXIT_OK
