"""``gfuzzy map``: write a scene around an occupancy-grid map."""

from __future__ import annotations

import math
import shlex
import sys

from ..errors import InputError, SceneError
from .common import EXIT_OK, BadInput, _check_numbers, _not_too_large, _out_path, _say


def cmd_map(args) -> int:
    from ..atomic import write_atomic
    from ..scene.mapscene import map_scene
    from ..scene.yamldoc import _load_yaml

    out = _out_path(args.output, (".yaml", ".yml"), ((args.map, "map"), (_map_image(args.map), "map image")))
    footprint = None
    if args.robot_footprint is not None:
        vals = args.robot_footprint
        if len(vals) < 6 or len(vals) % 2:
            raise BadInput("--robot-footprint: expected x y pairs of at least 3 points")
        if not all(math.isfinite(v) for v in vals):
            raise BadInput("--robot-footprint: numbers must be finite")
        _not_too_large(vals, "--robot-footprint")  # 1e10 was blamed on the scene not yet written
        footprint = [vals[i : i + 2] for i in range(0, len(vals), 2)]
        _check_footprint(footprint)
    if args.vmax is not None:
        _check_numbers("map", positive=(("--vmax", args.vmax),))
    command = "gfuzzy " + " ".join(shlex.quote(a) for a in sys.argv[1:]) if sys.argv[1:] else ""
    try:
        made = map_scene(
            args.map, out, robot_disc=args.robot_disc, robot_footprint=footprint,
            vmax=args.vmax or 0.5, name=args.name, command=command, kinematics=args.kinematics,
            reverse=args.reverse, wmax=args.wmax,
        )  # fmt: skip
    except SceneError:
        raise
    except InputError as exc:
        raise BadInput(f"gfuzzy map: {exc}") from None
    # the file must load as it will be read (a footprint robot needs a gfuzzy that has them)
    doc = _load_yaml(made.text, str(out))
    if footprint is None or _knows_footprints():
        from ..scene.scene import parse_scene

        parse_scene(doc, file=str(out), folder=out.resolve().parent)
    write_atomic(out, made.text)
    _say(f"wrote {out}", sys.stdout)
    if made.start is None:  # else `gfuzzy plan` on it says only that it has no queries
        _say(
            f"note: the robot fits nowhere on this map ({made.fit}): {out} has no sample query "
            "(a smaller robot?)"
        )
    return EXIT_OK


def _check_footprint(footprint) -> None:
    """``--robot-footprint`` checked as a scene file's ``robot.footprint`` is (the scene's own
    polygon rule, its words: too small, collinear, self-intersecting), blamed on the option."""
    import numpy as np

    from ..scene.scene import _check_polygon
    from ..scene.yamldoc import _V

    try:
        _check_polygon(_V("--robot-footprint"), np.asarray(footprint, dtype=float), "")
    except SceneError as exc:
        raise BadInput(f"--robot-footprint: {exc.message}") from None


def _map_image(path):
    """The image the map YAML at ``path`` names, or None when it cannot be read (said later)."""
    from ..scene.maps import read_map_yaml

    try:
        return read_map_yaml(path)[0].image
    except (InputError, OSError):
        return None


def _knows_footprints() -> bool:
    from ..scene.scene import Robot

    return "footprint" in getattr(Robot, "__dataclass_fields__", {})
