"""The ``gfuzzy`` parser and entry point."""

from __future__ import annotations

import argparse
import sys

from ..errors import (
    InputError,
    LimitError,
    interrupt_handling,
    interrupts_deferred,
    is_interrupt,
    say_interrupted,
)
from .common import EXIT_BAD, EXIT_OK, BadInput, _navigator_flags, _Parser, _say
from .crowds import add_crowd, add_populate
from .examples import add_examples
from .experiments import cmd_batch, cmd_navigate, cmd_tracks
from .export import add_export
from .mapping import cmd_map
from .planning import cmd_check, cmd_plan, cmd_regress, cmd_render, cmd_roadmap


def _plan_flags(q, single=True):
    """The flags plan, regress and batch share."""
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
    q.add_argument("--drive-repair", action=argparse.BooleanOptionalAction, default=True,
                   help="a box or footprint differential drive whose graph leaves start and goal apart: try to join its "
                        "pieces by small-step manoeuvres (default on; --no-drive-repair: answer no_path at once; "
                        "docs/planner.md)")  # fmt: skip
    q.add_argument("--backend", choices=("compiled", "reference"), default="compiled",
                   help="search implementation: compiled (numba, default) or the pure-Python reference; same answers")  # fmt: skip
    _clearance_flags(q)


def _clearance_flags(q):
    """The robot overrides every scene-reading command takes."""
    q.add_argument("--clearance", type=float, metavar="C",
                   help="distance kept from static obstacles, m (overrides robot.clearance; another roadmap)")  # fmt: skip
    q.add_argument("--mover-clearance", type=float, metavar="C",
                   help="distance kept from every mover, m (overrides robot.mover_clearance)")  # fmt: skip


def _add_roadmap(sub) -> None:
    """``gfuzzy roadmap``."""
    r = sub.add_parser("roadmap", help="build the static roadmap of a scene with OMPL's PRM")
    r.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    r.add_argument("-n", "--vertices", type=int, default=200, help="roadmap vertices (default 200)")
    r.add_argument("--seed", type=int, default=1, help="random seed (default 1)")
    r.add_argument("-k", "--neighbors", type=int, default=10, help="PRM nearest neighbours (default 10)")
    r.add_argument(
        "--no-repair",
        action="store_true",
        help="disc robots: do not join the roadmap's components through the free space "
        "(the repair adds vertices beyond -n where PRM missed a passage)",
    )
    r.add_argument(
        "--no-join",
        action="store_true",
        help="box and footprint robots: do not try to join the roadmap's components (the join "
        "spends a bounded number of collision checks and adds vertices beyond -n where it finds a way)",
    )
    r.add_argument("-o", "--output", help="roadmap file (default roadmaps/<scene name>.json)")
    r.set_defaults(func=cmd_roadmap)


def _add_plan(sub) -> None:
    """``gfuzzy plan``."""
    q = sub.add_parser("plan", help="answer one query")
    q.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    q.add_argument("--roadmap", metavar="FILE", help="roadmap file (default roadmaps/<scene name>.json)")
    _plan_flags(q)
    q.add_argument("--query", metavar="NAME", help="a query of the scene (default: its first)")
    q.add_argument("--start", nargs="+", metavar="X", help="start pose: X Y (a disc) or X Y H (a box, a footprint, or any kinematics: unicycle robot)")
    q.add_argument("--goal", nargs="+", metavar="X", help="goal pose")
    q.add_argument("--t0", type=float, help="departure time with --start/--goal (default 0)")
    q.add_argument("--hold", type=float, metavar="SECONDS",
                   help="park at the goal this long; it must stay safe (default: the query's hold, or 0)")  # fmt: skip
    q.add_argument("-o", "--output", metavar="OUT",
                   help="trajectory file: OUT.json, or OUT.csv (+ OUT.json); the JSON is written whatever the status, "
                        "an unsolved answer removes an older OUT.csv; stderr names the files written or removed")  # fmt: skip
    q.set_defaults(func=cmd_plan)


def _add_check(sub) -> None:
    """``gfuzzy check``."""
    c = sub.add_parser("check", help="check a trajectory against the contract's guarantees")
    c.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    c.add_argument("trajectory", metavar="TRAJ.json", help="a trajectory file of plan or navigate (JSON; not the CSV)")
    _clearance_flags(c)
    c.add_argument("--hold", type=float, metavar="SECONDS",
                   help="the goal pose must stay safe this long after the last row (default: the query's hold)")  # fmt: skip
    c.set_defaults(func=cmd_check)


def _add_render(sub) -> None:
    """``gfuzzy render``."""
    d = sub.add_parser("render", help="draw a scene (and a trajectory): PNG picture or GIF animation")
    d.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    d.add_argument("trajectory", metavar="TRAJ.json", nargs="?", help="a plan or navigate file to draw on it")
    d.add_argument("-o", "--output", required=True, metavar="OUT", help="OUT.png or OUT.gif")
    d.add_argument("--roadmap", metavar="FILE", help="draw this roadmap (PNG; default: the scene's roadmaps/<name>.json if there is one)")
    d.add_argument("--no-roadmap", action="store_true", help="do not draw a roadmap")
    d.add_argument("--speed", action="store_true", help="colour the path by speed (PNG and GIF)")
    _clearance_flags(d)
    d.set_defaults(func=cmd_render)


def _add_navigate(sub) -> None:
    """``gfuzzy navigate``."""
    v = sub.add_parser("navigate", help="drive to the goal among the movers without knowing their future")
    v.add_argument("scene", metavar="SCENE", help="scene file (YAML); its movers are the world")
    v.add_argument("--query", metavar="NAME", help="a query of the scene (default: its first)")
    v.add_argument("--roadmap", metavar="FILE", help="roadmap file (default roadmaps/<scene name>.json)")
    v.add_argument("-n", "--vertices", type=int, help="build a roadmap of this many vertices")
    v.add_argument("--seed", type=int, help="roadmap seed when building, and the sensor noise's seed (default 1)")
    v.add_argument("--period", type=float, default=0.25, help="seconds between observations and replans (default 0.25)")
    v.add_argument("--velocity", choices=("estimated", "true"), default="estimated",
                   help="movers' velocity: estimated from positions one period apart (default), or their true one")
    v.add_argument("--noise", type=float, default=0.0, help="Gaussian noise (m) on observed positions (default 0)")
    v.add_argument("--fov", type=float, default=360.0,
                   help="field of view (degrees) about the robot's heading or direction of motion (default 360)")
    v.add_argument("--occlusion", action="store_true", help="static obstacles hide the movers behind them")
    v.add_argument("--sense", type=float, help="range in metres within which movers are seen (default: all)")
    v.add_argument("--max-time", type=float, default=120.0, help="give up this long after t0 (default 120 s)")
    v.add_argument("--dt", type=float, default=0.1, help="time step of the replanning search (default 0.1)")
    v.add_argument("--time-budget", type=float, default=0.1, help="seconds one replan may take (default 0.1)")
    _navigator_flags(v)
    v.add_argument("--log-every", type=int, default=4, help="keep every k-th replan's predictions in the file (default 4)")
    v.add_argument("--backend", choices=("compiled", "reference"), default="compiled",
                   help="search implementation: compiled (numba, default) or the pure-Python reference")  # fmt: skip
    _clearance_flags(v)
    v.add_argument("-o", "--output", metavar="OUT.json", help="the executed trajectory file")
    v.set_defaults(func=cmd_navigate)


def _add_regress(sub) -> None:
    """``gfuzzy regress``."""
    g = sub.add_parser("regress", help="answer and check every query of every scene")
    g.add_argument("scenes", metavar="SCENE", nargs="+", help="scene files (YAML)")
    _plan_flags(g)
    g.set_defaults(func=cmd_regress, roadmap=None)


def _add_tracks(sub) -> None:
    """``gfuzzy tracks``."""
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
    k.add_argument("--offset", type=float, nargs=2, metavar=("DX", "DY"),
                   help="added to every x and y after --scale: where the file's origin lies in the scene (default 0 0)")  # fmt: skip
    k.add_argument("--radius", "--ped-radius", dest="radius", type=float, metavar="R", default=0.25, help="pedestrians' disc radius (default 0.25)")
    k.add_argument("--max-movers", type=int, metavar="N", help="keep the N people present longest")
    k.add_argument("--max-gap", type=float, metavar="S",
                   help="a person unseen for longer than S seconds is two movers, absent in between "
                        "(default: 5 times the person's own median time between rows; inf: never cut)")  # fmt: skip
    k.add_argument("--static", metavar="SCENE", help="take the robot, the static obstacles and the bounds of this scene")
    k.add_argument("--name", help="scene name (default: the output file's stem)")
    k.add_argument("--robot-radius", type=float, metavar="R", help="a disc robot of this radius (default 0.2, or --static's robot)")
    k.add_argument("--vmax", type=float, metavar="V", help="robot speed bound (default 1.5, or --static's)")
    k.add_argument("--amax", type=float, metavar="A", help="robot acceleration bound (default 3.0, or --static's)")
    k.add_argument("--kinematics", choices=("holonomic", "unicycle"),
                   help="the robot's drive (default: --static's, or holonomic); unicycle: a differential drive, "
                        "poses get a heading")  # fmt: skip
    k.add_argument("--reverse", action="store_true", help="unicycle: the robot may also drive backwards")
    k.add_argument("--wmax", type=float, metavar="W", help="unicycle: bound on the turning rate, rad/s (default vmax / r)")
    k.add_argument("--start", nargs="+", metavar="X", help="a query from this pose at t0 = 0 (with --goal)")
    k.add_argument("--goal", nargs="+", metavar="X", help="the query's goal pose")
    k.add_argument("--query-name", metavar="NAME", default="cross", help="the query's name (default cross)")
    k.add_argument("--expect", choices=("solved", "no_path", "invalid_query"), help="the query's expected status")
    k.add_argument("--max-duration", type=float, metavar="S", help="the query's expected longest duration")
    k.set_defaults(func=cmd_tracks)


def _add_batch(sub) -> None:
    """``gfuzzy batch``."""
    b = sub.add_parser("batch", help="answer every query of every scene on a Dask cluster; one CSV row per query")
    b.add_argument("scenes", metavar="SCENE", nargs="+", help="scene files (YAML)")
    _plan_flags(b)
    where = b.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="K", help="local worker processes (default 2)")
    where.add_argument("--scheduler", metavar="ADDRESS", help="an existing Dask scheduler, e.g. tcp://host:8786")
    b.add_argument("--connect-timeout", type=float, default=10.0, help=argparse.SUPPRESS)
    b.add_argument("-o", "--output", required=True, metavar="RESULTS.csv",
                   help="results table (and RESULTS.parquet beside it when pyarrow is installed)")  # fmt: skip
    b.add_argument("--trajectories", metavar="DIR", help="save each answer as DIR/<scene>-<query>.json")
    b.add_argument("-v", "--verbose", action="store_true", help="show Dask's logs")
    b.set_defaults(func=cmd_batch, roadmap=None)


def _add_map(sub) -> None:
    """``gfuzzy map``."""
    m = sub.add_parser("map", help="write a scene around an occupancy-grid map (ROS map_server / Nav2 YAML)")
    m.add_argument("map", metavar="MAP.yaml", help="the map's YAML file (inside the scene file's folder)")
    m.add_argument("-o", "--output", required=True, metavar="SCENE.yaml", help="the scene file to write")
    robot = m.add_mutually_exclusive_group()
    robot.add_argument("--robot-disc", type=float, metavar="R", help="a disc robot of radius R (default 0.2)")
    robot.add_argument("--robot-footprint", type=float, nargs="+", metavar="X",
                       help="a footprint robot: the polygon's x y pairs in the robot's frame (x forward)")  # fmt: skip
    m.add_argument("--vmax", type=float, metavar="V", help="robot speed bound (default 0.5)")
    m.add_argument("--kinematics", choices=("holonomic", "unicycle"), default="holonomic",
                   help="unicycle: a differential drive (turns in place, straight moves; poses get a heading)")  # fmt: skip
    m.add_argument("--reverse", action="store_true",
                   help="unicycle: the robot may also drive backwards (default: forwards only)")  # fmt: skip
    m.add_argument("--wmax", type=float, metavar="W",
                   help="unicycle: bound on the turning rate, rad/s (default: the scene file's, vmax / r)")  # fmt: skip
    m.add_argument("--name", help="scene name (default: the output file's stem)")
    m.set_defaults(func=cmd_map)


def _parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="gfuzzy",
        description="Roadmap-time-space motion planning among moving obstacles (OMPL + FCL).",
    )
    sub = p.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for add in (_add_roadmap, _add_plan, _add_check, _add_render, _add_navigate, _add_regress, _add_tracks, _add_batch,
                _add_map, add_export, add_crowd, add_populate, add_examples):
        add(sub)
    return p


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status.

    Ctrl-C at any moment prints one line, ``interrupted``, and returns 130 (a SIGTERM:
    ``terminated``, 143), leaving no file half-written (``batch`` writes the rows it
    finished): see the Ctrl-C section of
    :mod:`gfuzzy.errors`. With ``argv`` None (the process's own command line), a Ctrl-C after
    the command is over is ignored: the process exits with the command's status.
    """
    import logging

    logging.basicConfig(level=logging.WARNING, format="%(levelname)s: %(message)s")
    with interrupt_handling(restore=argv is not None):
        try:
            return _run(argv)  # its last line is out: a Ctrl-C now changes nothing
        except BaseException as exc:
            if not is_interrupt(exc):
                raise
            # Ctrl-C comes twice (a terminal's repeat, `timeout`'s group signal): one line
            return say_interrupted()


def _run(argv: list[str] | None) -> int:
    """Parse ``argv`` and run its command; bad input is one line and :data:`EXIT_BAD`."""
    parser = _parser()
    try:
        args, extra = parser.parse_known_args(argv)
        command = getattr(args, "command", None)
        if extra:  # name the command whose --help lists its options (gfuzzy's for one before it)
            tokens = list(sys.argv[1:] if argv is None else argv)
            at = tokens.index(command) if command in tokens else len(tokens)
            ours = command and not any(t in tokens[:at] for t in extra)
            prog = f"{parser.prog} {command}" if ours else parser.prog
            raise BadInput(f"{prog}: unrecognized arguments: {' '.join(extra)} (see {prog} --help)")
        if not command:
            parser.print_help(sys.stderr)
            return EXIT_BAD
        return args.func(args)
    except (BadInput, InputError, LimitError) as exc:  # SceneError included; any other exception is a bug
        return _bad_input(str(exc))
    except BrokenPipeError:
        return EXIT_OK
    except OSError as exc:
        if exc.filename is None:
            raise
        # a file the command had to read or write and could not (a full disc, a folder
        # that refuses writing, /proc): the user's to fix, one line, nothing half-written
        return _bad_input(f"{exc.filename}: {exc.strerror or exc}")


def _bad_input(message: str) -> int:
    """Say ``message`` on one line; :data:`EXIT_BAD`. A Ctrl-C meanwhile adds no second line."""
    with interrupts_deferred(raise_after=False):
        _say(" ".join(message.split()))
    return EXIT_BAD
