"""What the commands share: the one-line bad-input error, messages, loading a scene
and finding its roadmap, the options and poses given on the command line."""

from __future__ import annotations

import argparse
import math
import os
import re
import sys
from pathlib import Path

from ..errors import InputError, LimitError, SceneError, check_number

EXIT_OK, EXIT_NO, EXIT_BAD = 0, 1, 2


class BadInput(Exception):
    """A bad command line or file; its message is the one line printed."""


class _Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        # a value that starts as a negative number does (-1e3, -.5, "-1.5,3.0;2,2" for
        # --waypoints) is a value, not an option: argparse's own test takes only -1 and -1.5
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message):  # one line, exit 2 (argparse prints usage + error)
        raise BadInput(f"{self.prog}: {message} (see {self.prog} --help)")


def _say(msg: str, stream=None) -> None:
    stream = stream or sys.stderr
    stream.write(msg + "\n")
    stream.flush()


def _navigator_flags(p) -> None:
    """The navigator's options that ``navigate`` and ``crowd`` both take (``NavOptions``)."""
    p.add_argument("--budget-clock", choices=("wall", "cpu"), default="wall",
                   help="the clock of --time-budget and of the replan times reported: wall (default, a robot's) or "
                        "cpu, the navigator thread's CPU time, so that runs do not depend on the machine's load")  # fmt: skip
    p.add_argument("--personal-space", type=float, default=0.2,
                   help="gap (m) the navigator keeps from people when that costs little (default 0.2, 0: off)")  # fmt: skip
    p.add_argument("--path-space", type=float, default=1.25, metavar="SECONDS",
                   help="how far ahead (s) the navigator keeps off the way people are about to walk, when that "
                        "costs little (default 1.25, 0: off)")  # fmt: skip
    p.add_argument("--soft-search", action="store_true",
                   help="one search pricing people's personal space and ways instead of the tiers (NavOptions.soft_search)")
    p.add_argument("--intrusion-cost", type=float, metavar="SECONDS",
                   help="with --soft-search: seconds of arrival one second inside someone's space or way costs (default 2)")


def _soft_options(args) -> dict:
    """``NavOptions``' priced search from ``--soft-search`` and ``--intrusion-cost`` of
    ``navigate`` and ``crowd``, refused by the flags' names (InputError): the cost is a
    number >= 0 and at most ``settings.MAX_MAGNITUDE``, and only taken with ``--soft-search``."""
    if args.intrusion_cost is None:
        return {"soft_search": args.soft_search}
    if not args.soft_search:
        raise InputError("--intrusion-cost needs --soft-search (the tiers do not price)")
    check_number("--intrusion-cost", args.intrusion_cost, strict=False)
    return {"soft_search": True, "intrusion_cost": args.intrusion_cost}


def _check_numbers(command: str, positive=(), at_least_zero=()) -> None:
    """The numeric flags of ``command``, ``(flag, value)`` pairs, checked by the one rule of
    :func:`gfuzzy.errors.check_number` under the flag's own name: a number above zero
    (``positive``) or at least zero (``at_least_zero``), finite and at most
    ``settings.MAX_MAGNITUDE`` in magnitude, as a scene file's numbers. Bad input
    ``gfuzzy COMMAND: --flag must be ...`` (the library's options name their fields instead)."""
    try:
        for flag, value in positive:
            check_number(flag, value)
        for flag, value in at_least_zero:
            check_number(flag, value, strict=False)
    except InputError as exc:
        raise BadInput(f"gfuzzy {command}: {exc}") from None


def _sense(command: str, value) -> float:
    """``--sense`` of ``navigate`` and ``crowd``: None (not given) or ``inf`` is an unlimited
    range; else a positive number of at most ``settings.MAX_MAGNITUDE`` (bad input otherwise)."""
    if value is None or value == math.inf:
        return math.inf
    _check_numbers(command, positive=(("--sense", value),))
    return value


def _check_sensor_flags(args) -> None:
    """``--noise`` and ``--fov`` of ``navigate`` and ``crowd``, refused by their flags' names
    (InputError)."""
    check_number("--noise", args.noise, strict=False)
    if not (math.isfinite(args.fov) and 0 < args.fov <= 360):
        raise InputError(f"--fov must be in (0, 360] degrees, got {args.fov:g}")


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
    from ..scene.scene import load_scene

    return load_scene(path)


def _roadmap_for(scene, args, quiet=False):
    """The roadmap a plan/regress run uses: --roadmap, -n/--seed, or the default file."""
    from ..roadmap.roadmap import RoadmapOptions, build_roadmap, load_roadmap

    if getattr(args, "roadmap", None):
        return load_roadmap(args.roadmap, scene)
    if args.vertices is not None or args.seed is not None:
        try:
            opts = RoadmapOptions(
                vertices=args.vertices if args.vertices is not None else RoadmapOptions.vertices,
                seed=args.seed if args.seed is not None else RoadmapOptions.seed,
            )
        except (InputError, LimitError) as exc:
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
            f"note: no roadmap file fits {scene.name!r}; building one with "
            f"{RoadmapOptions.vertices} vertices (save one with `gfuzzy roadmap`)"
        )
    return build_roadmap(scene, RoadmapOptions(), progress=_progress("roadmap"))


def _check_roadmap_flags(args) -> None:
    """Refuse bad -n/--seed values up front, as :func:`_roadmap_for` would later."""
    from ..roadmap.roadmap import RoadmapOptions

    if args.vertices is None and args.seed is None:
        return
    try:
        RoadmapOptions(
            vertices=args.vertices if args.vertices is not None else RoadmapOptions.vertices,
            seed=args.seed if args.seed is not None else RoadmapOptions.seed,
        )
    except (InputError, LimitError) as exc:
        raise BadInput(f"-n/--seed: {exc}") from None


def _roadmap_of_other_clearance(scene):
    """The options of a saved roadmap built for the same shapes with another static
    clearance (a ``--clearance`` override), or None."""
    from ..roadmap.roadmap import default_roadmap_path, load_roadmap

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


def _roadmap_reads(scene, args) -> tuple:
    """The roadmap files a command may read, as ``_out_path``'s ``reads``: ``--roadmap``,
    or without it the default files :func:`_default_roadmap` looks for."""
    if getattr(args, "roadmap", None):
        return ((args.roadmap, "roadmap"),)
    from ..roadmap.roadmap import default_roadmap_path

    beside = Path(scene.source).resolve().parent.parent / "roadmaps"
    return tuple((p, "default roadmap") for p in (default_roadmap_path(scene), default_roadmap_path(scene, beside)))


def _default_roadmap(scene, quiet=False):
    """The roadmap file built for ``scene`` in roadmaps/ (here, or beside the scene's
    folder), if there is one that matches it."""
    from ..roadmap.roadmap import default_roadmap_path, load_roadmap

    scene_dir = Path(scene.source).resolve().parent
    here, beside = default_roadmap_path(scene), default_roadmap_path(scene, scene_dir.parent / "roadmaps")
    # run from the scene's parent folder, both are one file: read (and refused) once
    for path in (here,) if here.resolve() == beside.resolve() else (here, beside):
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
    from ..roadmap.roadmap import load_roadmap

    try:
        return bool(scene.shape_hash) and load_roadmap(path).scene_hash == scene.shape_hash
    except SceneError:
        return False


def _plan_options(args):
    from ..planner.planner import PlanOptions

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
            backend=getattr(args, "backend", "compiled"),
            drive_repair=getattr(args, "drive_repair", True),
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
    _not_too_large(out, flag)
    return out


def _not_too_large(values, flag: str) -> None:
    """Bad input when a coordinate given on the command line lies beyond ``MAX_MAGNITUDE``, as
    in a scene file (a cell index of 1e308 overflowed)."""
    from ..settings import MAX_MAGNITUDE

    big = max((abs(v) for v in values), default=0.0)
    if big > MAX_MAGNITUDE:
        raise BadInput(f"{flag}: number too large ({big:g}; at most {MAX_MAGNITUDE:g} in magnitude)")


def _out_path(path, allowed, reads=(), beside=()):
    """``path`` checked as an output: its suffix one of ``allowed``, its folder writable, and
    neither it nor the files written ``beside`` it (suffixes: a CSV's JSON, a map's .pgm, a
    table's .parquet) any of the files the command ``reads`` (``(path or None, what)``, e.g.
    :func:`_scene_reads`): writing there destroyed the input, e.g. a roadmap given as both
    ``--roadmap`` and ``-o``, or a scene's own map YAML as ``export --map``."""
    suffix = Path(path).suffix.lower()
    if suffix not in allowed:
        raise BadInput(f"{path}: output must end in {' or '.join(allowed)}")
    _refuse_overwrite(path, [Path(path)] + [Path(path).with_suffix(s) for s in beside], reads)
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise BadInput(f"{path}: folder {parent} does not exist")
    if Path(path).is_dir():
        raise BadInput(f"{path}: is a folder, not a file")
    for other in (Path(path).with_suffix(s) for s in beside):  # found only once the work was done
        if other.is_dir():
            raise BadInput(f"{path}: {other}, written with it, is a folder, not a file")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise BadInput(f"{path}: folder {parent} is not writable")
    _probe_write(path, parent)
    return Path(path)


def _refuse_overwrite(path, writes, reads) -> None:
    """Bad input when any of ``writes`` (the files writing ``path`` makes) is one of the
    files in ``reads`` (``(path or None, what)``), through links and any spelling: the one
    place every command's outputs are checked against its inputs."""
    for source, what in reads:
        for w in writes:
            if source is not None and _same_file(w, source):
                also = "" if w == Path(path) else f" (the file {w} written with it)"
                raise BadInput(
                    f"{path}: would overwrite {source}{also}, the {what} this command reads; write it elsewhere"
                )


def _scene_reads(scene) -> tuple:
    """The files reading ``scene`` read, as ``_out_path``'s ``reads``: the scene file, each
    map's YAML and image, each mesh."""
    from ..scene.maps import MapObstacle

    folder = Path(scene.source).resolve().parent
    reads = [(scene.source, "scene")]
    for ob in scene.obstacles:
        if isinstance(ob, MapObstacle):
            reads += [(ob.path, "map"), (ob.info.image, "map image")]
        elif getattr(ob, "source", "polygon") != "polygon":  # a mesh's polygons name their file
            reads.append((folder / ob.source, "mesh"))
    return tuple(dict.fromkeys(reads))


def _same_file(a, b) -> bool:
    """Whether the paths name one file (through links too); False when either is absent."""
    try:
        return os.path.samefile(a, b)
    except OSError:
        return False


def _probe_write(path, parent: Path) -> None:
    """Create and remove a file in ``parent``: the permission bits do not tell root (or an
    NFS client whose root is squashed, or /proc) that nothing can be written there, and a
    long run would then lose its results at the end."""
    import tempfile

    try:
        fd, tmp = tempfile.mkstemp(prefix=".gfuzzy-probe-", dir=parent)
    except OSError as exc:
        raise BadInput(f"{path}: cannot write in folder {parent} ({exc.strerror})") from None
    os.close(fd)
    os.unlink(tmp)


