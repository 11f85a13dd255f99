"""``gfuzzy export``: an MCAP file for Foxglove / Lichtblick, or a Nav2 map (docs/export.md)."""

from __future__ import annotations

import math
import sys

from ..errors import InputError
from .common import EXIT_OK, BadInput, _load_scene, _out_path, _say, _scene_reads
from .planning import _navigate_extras, _rows_fit, _violation


def add_export(sub) -> None:
    """``gfuzzy export``."""
    e = sub.add_parser(
        "export",
        help="write a scene (and a trajectory) as MCAP for Foxglove / Lichtblick, or its obstacles as a Nav2 map",
    )
    e.add_argument("scene", metavar="SCENE", help="scene file (YAML)")
    e.add_argument("trajectory", metavar="TRAJ.json", nargs="?", help="a plan or navigate file (MCAP only)")
    e.add_argument("-o", "--output", metavar="OUT.mcap", help="the MCAP file to write")
    e.add_argument("--map", metavar="OUT.yaml", help="write the static obstacles as a Nav2 map: OUT.yaml and OUT.pgm")
    e.add_argument("--resolution", type=float, metavar="R", help="map cell size, metres (default 0.05)")
    e.add_argument("--step", type=float, metavar="S", help="seconds between /movers and /robot messages (default 0.1)")
    e.add_argument("--span", type=float, metavar="T", help="seconds of mover motion without a trajectory (default: as render)")
    e.set_defaults(func=cmd_export)


def _positive(value, flag: str) -> None:
    if value is not None and not (math.isfinite(value) and value > 0):
        raise BadInput(f"{flag}: must be a positive number, got {value:g}")


def cmd_export(args) -> int:
    if (args.output is None) == (args.map is None):
        raise BadInput("gfuzzy export: give exactly one of -o OUT.mcap or --map OUT.yaml (see gfuzzy export --help)")
    for flag, value in (("--resolution", args.resolution), ("--step", args.step), ("--span", args.span)):
        _positive(value, flag)
    if args.map is not None:
        for flag, value in (("TRAJ.json", args.trajectory), ("--step", args.step), ("--span", args.span)):
            if value is not None:
                raise BadInput(f"gfuzzy export: {flag} is for an MCAP export (-o OUT.mcap), not --map")
        return _export_map(args)
    if args.resolution is not None:
        raise BadInput("gfuzzy export: --resolution is for --map OUT.yaml, not an MCAP export")
    return _export_mcap(args)


def _export_map(args) -> int:
    from ..export.mapexport import export_nav2_map

    scene = _load_scene(args.scene)
    out = _out_path(args.map, (".yaml", ".yml"), _scene_reads(scene), beside=(".pgm",))
    try:
        grid = export_nav2_map(scene, out, args.resolution if args.resolution is not None else 0.05)
    except InputError as exc:
        raise BadInput(f"{args.map}: {exc}") from None
    h, w = grid.shape
    _say(f"wrote {out} and {out.with_suffix('.pgm')} ({w} x {h} cells of {grid.resolution:g} m, {int(grid.occupied.sum())} occupied)", sys.stdout)
    return EXIT_OK


def _export_mcap(args) -> int:
    from ..export.export import ExportOptions, export_mcap
    from ..trajectory import load_trajectory

    scene = _load_scene(args.scene)
    out = _out_path(args.output, (".mcap",), (*_scene_reads(scene), (args.trajectory, "trajectory")))
    rows, predictions = None, None
    if args.trajectory:
        tf = load_trajectory(args.trajectory)
        _rows_fit(scene, tf.waypoints, args.trajectory)
        extras = _navigate_extras(scene, tf, args.trajectory)
        rows = tf.waypoints if tf.waypoints is not None else extras.get("executed")
        if rows is None:
            _say(f"note: {args.trajectory} has status {tf.status} and no rows: exporting the scene only")
        predictions = extras.get("replan_log")
    kw = {k: v for k, v in (("step", args.step), ("span", args.span)) if v is not None}
    try:
        report = export_mcap(scene, out, rows, predictions, ExportOptions(**kw))
    except ImportError as exc:
        raise BadInput(str(exc)) from None
    except InputError as exc:
        raise BadInput(f"{args.trajectory or args.scene}: {exc}") from None
    if rows is not None and rows is tf.waypoints:  # exported: told when check rejects it
        _violation(scene, tf, args.trajectory, "exported anyway")
    counts = ", ".join(f"{topic} {n}" for topic, n in report.counts.items())
    _say(f"wrote {out} ({counts} messages, t {report.t_start:g}-{report.t_end:g} s)", sys.stdout)
    return EXIT_OK
