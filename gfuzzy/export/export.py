"""MCAP export for Foxglove and Lichtblick (docs/export.md; contract section 8).

:func:`export_mcap` writes a scene, and a trajectory, as an MCAP file with JSON-encoded
Foxglove messages (the schemas of :mod:`gfuzzy.export.foxglove`, embedded), which Foxglove and its
open fork Lichtblick open without ROS. Every message is in frame ``map``; log times are the
trajectory's time in nanoseconds.

========================= ========================== ==========================================
topic                     schema                     messages
========================= ========================== ==========================================
``/scene``                ``foxglove.SceneUpdate``   one: bounds, static obstacles (maps as
                                                     their blocked cells), start and goal
``/movers``               ``foxglove.SceneUpdate``   one per time step: the movers present
``/robot``                ``foxglove.PoseInFrame``   one per time step: the pose on the trajectory
``/path``                 ``foxglove.PosesInFrame``  one: every row of the trajectory
``/robot_body``           ``foxglove.SceneUpdate``   one per time step: the robot's shape there
``/predictions``          ``foxglove.SceneUpdate``   one per logged replan of a navigate file
========================= ========================== ==========================================

The time steps are ``t0, t0 + step, ...`` and the trajectory's last t (:func:`step_times`);
without a trajectory the movers are written from 0 over a span like ``gfuzzy render``'s
animations. The ``mcap`` package is an optional dependency (``pip install gfuzzy[export]``).
"""

from __future__ import annotations

import json
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..atomic import write_atomic_with
from ..errors import InputError, check_number
from ..render.span import default_span
from ..scene.scene import Box, Disc, Polygon, Scene
from ..settings import MAX_MAGNITUDE
from ..typed import FloatArray
from .foxglove import SCHEMAS, color, pose, timestamp, vec3

__all__ = ["ExportOptions", "McapReport", "export_mcap", "step_times", "TOPICS", "FRAME"]

log = logging.getLogger(__name__)

#: The frame every message is in.
FRAME = "map"
#: Topic -> schema name.
TOPICS = {
    "/scene": "foxglove.SceneUpdate",
    "/movers": "foxglove.SceneUpdate",
    "/robot": "foxglove.PoseInFrame",
    "/path": "foxglove.PosesInFrame",
    "/predictions": "foxglove.SceneUpdate",
    "/robot_body": "foxglove.SceneUpdate",
}
#: Most time steps one export writes (a step far too small for the span is refused).
MAX_STEPS = 2_000_000

_OBSTACLE = color(0.45, 0.45, 0.5, 1.0)
_BOUNDS = color(0.15, 0.15, 0.15, 1.0)
_MOVER = color(0.85, 0.33, 0.1, 0.9)
_PREDICTED = color(0.5, 0.5, 0.5, 0.35)
_PLAN = color(0.12, 0.47, 0.71, 0.8)
_ROBOT = color(0.12, 0.47, 0.71, 0.85)
_START = color(0.17, 0.63, 0.17, 1.0)
_GOAL = color(0.84, 0.15, 0.16, 1.0)


@dataclass(frozen=True)
class ExportOptions:
    """Settings of :func:`export_mcap`.

    Attributes
    ----------
    step : float
        Seconds between two ``/movers`` and ``/robot`` messages (default 0.1: 10 Hz).
    span : float or None
        Seconds of mover motion written when there is no trajectory (default: the movers'
        longest timed motion or period, within 1-60 s, else 10 s).
    obstacle_height : float
        Height, metres, the planar obstacles are drawn with.
    mover_height : float
        Height, metres, the movers are drawn with.
    robot_height : float
        Height, metres, the robot's body is drawn with (``/robot_body``).
    """

    step: float = 0.1
    span: float | None = None
    obstacle_height: float = 0.5
    mover_height: float = 1.0
    robot_height: float = 0.4

    def __post_init__(self) -> None:
        check_number("step", self.step)
        if self.span is not None:
            check_number("span", self.span)
        check_number("obstacle_height", self.obstacle_height)
        check_number("mover_height", self.mover_height)
        check_number("robot_height", self.robot_height)


@dataclass(frozen=True)
class McapReport:
    """What :func:`export_mcap` wrote.

    Attributes
    ----------
    path : Path
    counts : dict
        Topic -> number of messages.
    t_start, t_end : float
        First and last log time, seconds.
    """

    path: Path
    counts: dict = field(default_factory=dict)
    t_start: float = 0.0
    t_end: float = 0.0


def step_times(t0: float, t1: float, step: float) -> FloatArray:
    """The export's time steps: ``t0, t0 + step, ...`` below ``t1``, then ``t1``.

    Parameters
    ----------
    t0, t1 : float
        First and last time, ``t0 <= t1``.
    step : float
        Positive.

    Returns
    -------
    (n,) float
        Strictly increasing, from ``t0`` to ``t1`` inclusive (just ``[t0]`` when equal);
        a step that would land within 1 ns of ``t1`` is dropped in favour of ``t1``.
    """
    check_number("step", step)
    nf = (t1 - t0) // step + 1.0 if t1 > t0 else 1.0  # a float: with 1e-308, inf (int() overflowed)
    if nf > MAX_STEPS:
        raise InputError(f"step {step:g} s gives {nf:.3g} time steps over {t1 - t0:g} s (at most {MAX_STEPS:,}); use a larger step (--step)")
    ts = t0 + step * np.arange(int(nf))
    ts = ts[ts < t1 - 1e-9]
    return np.append(ts, t1) if t1 > t0 or not len(ts) else ts


def _ns(t: float) -> int:
    return int(round(float(t) * 1e9))


def _headings(rows: FloatArray, times: FloatArray) -> FloatArray:
    """Yaw at ``times``: the heading column, or for [t, x, y] rows the direction of
    travel (kept through waits; the first motion's before it; 0 with no motion).

    Parameters
    ----------
    rows : (n, 3) or (n, 4) float
    times : (k,) float

    Returns
    -------
    (k,) float
    """
    if rows.shape[1] == 4:
        from ..poses import pose_at

        if len(rows) == 1:
            return np.full(len(times), rows[0, 3])
        return pose_at(rows[:, 0], rows[:, 1:], np.clip(times, rows[0, 0], rows[-1, 0]))[:, 2]
    if len(rows) < 2:
        return np.zeros(len(times))
    d = np.diff(rows[:, 1:3], axis=0)
    moving = np.hypot(d[:, 0], d[:, 1]) > 1e-12
    yaw = np.arctan2(d[:, 1], d[:, 0])
    if not moving.any():
        return np.zeros(len(times))
    # forward fill over waits, back fill before the first motion
    idx = np.where(moving, np.arange(len(d)), -1)
    idx = np.maximum.accumulate(idx)
    idx[idx < 0] = int(np.argmax(moving))
    seg_yaw = yaw[idx]
    seg = np.clip(np.searchsorted(rows[:, 0], times, side="right") - 1, 0, len(d) - 1)
    return seg_yaw[seg]


# --------------------------------------------------------------------------- entities


def _entity(eid: str, t_ns: int, **prims) -> dict:
    ent = {"timestamp": timestamp(t_ns), "frame_id": FRAME, "id": eid, "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": False}
    meta = prims.pop("metadata", None)
    if meta:
        ent["metadata"] = [{"key": str(k), "value": str(v)} for k, v in meta.items()]
    ent.update({k: v for k, v in prims.items() if v})
    return ent


def _line(points, loop: bool, thickness: float, col: dict, z: float = 0.0) -> dict:
    return {
        "type": 1 if loop else 0,
        "pose": pose(0.0, 0.0),
        "thickness": thickness,
        "scale_invariant": False,
        "points": [vec3(x, y, z) for x, y in points],
        "color": col,
        "colors": [],
        "indices": [],
    }


def _prism(poly, height: float, col: dict) -> dict:
    """A TriangleListPrimitive: the polygon's top face at ``height`` and its walls."""
    import shapely

    pts: list = []
    tris = shapely.constrained_delaunay_triangles(poly)
    for tri in getattr(tris, "geoms", []):
        for x, y in list(tri.exterior.coords)[:3]:
            pts.append(vec3(x, y, height))
    for ring in [poly.exterior, *poly.interiors]:
        c = np.asarray(ring.coords)
        for (ax, ay), (bx, by) in zip(c[:-1], c[1:], strict=True):
            pts += [vec3(ax, ay, 0), vec3(bx, by, 0), vec3(bx, by, height)]
            pts += [vec3(ax, ay, 0), vec3(bx, by, height), vec3(ax, ay, height)]
    return {"pose": pose(0.0, 0.0), "points": pts, "color": col, "colors": [], "indices": []}


def _cube(x: float, y: float, yaw: float, sx: float, sy: float, h: float, col: dict) -> dict:
    return {"pose": pose(x, y, yaw, 0.5 * h), "size": vec3(sx, sy, h), "color": col}


def _cylinder(x: float, y: float, r: float, h: float, col: dict) -> dict:
    return {"pose": pose(x, y, 0.0, 0.5 * h), "size": vec3(2 * r, 2 * r, h), "bottom_scale": 1.0, "top_scale": 1.0, "color": col}


def _obstacle_entity(i: int, ob, t_ns: int, h: float) -> dict:
    import shapely

    eid = f"obstacle-{i}"
    if isinstance(ob, Disc):
        return _entity(eid, t_ns, cylinders=[_cylinder(*ob.center, ob.radius, h, _OBSTACLE)], metadata={"kind": "disc"})
    if isinstance(ob, Box):
        return _entity(eid, t_ns, cubes=[_cube(*ob.center, ob.angle, *ob.size, h, _OBSTACLE)], metadata={"kind": "box"})
    if isinstance(ob, Polygon):
        poly = shapely.Polygon(ob.points, list(ob.holes))
        return _entity(eid, t_ns, triangles=[_prism(poly, h, _OBSTACLE)], metadata={"kind": "polygon", "source": ob.source})
    cells = _blocked_boxes(ob)
    if cells is not None:
        cubes = [_cube(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.0, x1 - x0, y1 - y0, h, _OBSTACLE) for x0, y0, x1, y1 in cells]
        return _entity(eid, t_ns, cubes=cubes, metadata={"kind": "map"})
    raise InputError(f"obstacles[{i}]: cannot export an obstacle of type {type(ob).__name__}")


def _blocked_boxes(ob) -> FloatArray | None:
    """A map obstacle's blocked cells as boxes ``(x0, y0, x1, y1)``, runs along a row merged
    (None for an obstacle that is not a map)."""
    from .mapexport import obstacle_boxes

    return obstacle_boxes(ob)


def _scene_update(scene: Scene, t_ns: int, rows: FloatArray | None, opts: ExportOptions) -> dict:
    x0, y0, x1, y1 = scene.bounds
    ents = [_entity("bounds", t_ns, lines=[_line([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], True, 0.03, _BOUNDS)])]
    for i, ob in enumerate(scene.obstacles):
        ents.append(_obstacle_entity(i, ob, t_ns, opts.obstacle_height))
    if rows is not None:
        r = max(0.05, 0.5 * scene.robot.inradius)
        for eid, row, col in (("start", rows[0], _START), ("goal", rows[-1], _GOAL)):
            ents.append(_entity(eid, t_ns, cylinders=[_cylinder(row[1], row[2], r, 0.02, col)]))
    return {"deletions": [], "entities": ents}


def _robot_body(robot, x: float, y: float, yaw: float, t_ns: int, h: float) -> dict:
    """The robot's body at a pose: one entity ``robot`` (disc, box or footprint)."""
    import shapely

    if robot.shape == "disc":
        prims = {"cylinders": [_cylinder(x, y, robot.radius, h, _ROBOT)]}
    elif robot.shape == "box":
        prims = {"cubes": [_cube(x, y, yaw, *robot.size, h, _ROBOT)]}
    else:  # a footprint polygon in the robot's frame, placed by the primitive's pose
        prism = _prism(shapely.Polygon(getattr(robot, "footprint", ())), h, _ROBOT)
        prism["pose"] = pose(x, y, yaw)
        prims = {"triangles": [prism]}
    return {"deletions": [], "entities": [_entity("robot", t_ns, **prims)]}


def _mover_updates(scene: Scene, times: FloatArray, opts: ExportOptions):
    """One SceneUpdate per time: everything before it deleted, the present movers added."""
    xy, present = scene.mover_states(times)  # (m, n, 2), (m, n)
    h = opts.mover_height
    for k, t in enumerate(times):
        t_ns = _ns(t)
        ents = []
        for i, mv in enumerate(scene.movers):
            if not present[i, k]:
                continue
            x, y = xy[i, k]
            if mv.shape == "disc":
                body = {"cylinders": [_cylinder(x, y, mv.radius, h, _MOVER)]}
            else:
                body = {"cubes": [_cube(x, y, 0.0, *mv.size, h, _MOVER)]}
            label = {"pose": pose(x, y, 0.0, h + 0.2), "billboard": True, "font_size": 0.25, "scale_invariant": False, "color": color(0, 0, 0), "text": mv.name}
            ents.append(_entity(f"mover-{mv.name}", t_ns, texts=[label], **body))
        yield t_ns, {"deletions": [{"timestamp": timestamp(t_ns), "type": 1, "id": ""}], "entities": ents}


def _prediction_update(entry: dict, t_ns: int, opts: ExportOptions) -> dict:
    """A logged replan: the predicted discs (with their velocity) and the plan."""
    pred = np.asarray(entry.get("predicted", []), dtype=float).reshape(-1, 5)
    ents = []
    for j, (x, y, vx, vy, r) in enumerate(pred):
        speed = math.hypot(vx, vy)
        prims: dict = {"cylinders": [_cylinder(x, y, max(r, 1e-3), 0.5 * opts.mover_height, _PREDICTED)]}
        if speed > 1e-9:  # the velocity it was predicted to keep: one second's travel
            prims["arrows"] = [
                {
                    "pose": pose(x, y, math.atan2(vy, vx), 0.5 * opts.mover_height),
                    "shaft_length": speed,
                    "shaft_diameter": 0.04,
                    "head_length": 0.12,
                    "head_diameter": 0.1,
                    "color": _PREDICTED,
                }
            ]
        ents.append(_entity(f"predicted-{j}", t_ns, **prims))
    plan = np.asarray(entry.get("plan", []), dtype=float)
    if plan.ndim == 2 and len(plan) >= 2 and plan.shape[1] >= 3:
        ents.append(_entity("plan", t_ns, lines=[_line(plan[:, 1:3], False, 0.03, _PLAN, z=0.01)], metadata={"mode": entry.get("mode", "")}))
    return {"deletions": [{"timestamp": timestamp(t_ns), "type": 1, "id": ""}], "entities": ents}


def _valid_predictions(predictions) -> list:
    """``predictions`` read as a navigate file's ``replan_log`` (:func:`gfuzzy.trajectory.replan_entries`)."""
    from ..trajectory import replan_entries

    return replan_entries(list(predictions or []), "predictions")


# --------------------------------------------------------------------------- the file


def _check_rows(trajectory) -> FloatArray | None:
    """The trajectory's rows, validated (None for none)."""
    if trajectory is None:
        return None
    rows = np.asarray(trajectory, dtype=float)
    if rows.ndim != 2 or rows.shape[1] not in (3, 4) or len(rows) == 0 or not np.all(np.isfinite(rows)):
        raise InputError("trajectory: expected finite rows [t, x, y] or [t, x, y, heading]")
    if np.any(np.diff(rows[:, 0]) <= 0):
        raise InputError("trajectory: t must increase strictly")
    if rows[0, 0] < 0:
        raise InputError(f"trajectory starts at t={rows[0, 0]:g}: MCAP log times are nanoseconds from 0, so a trajectory must start at t >= 0")
    if rows[-1, 0] > MAX_MAGNITUDE:  # MCAP log times are unsigned 64-bit nanoseconds: 1.8e10 s at most
        raise InputError(f"trajectory ends at t={rows[-1, 0]:g}: an MCAP file's times must be at most {MAX_MAGNITUDE:g} s")
    return rows


def _messages(scene: Scene, rows: FloatArray | None, preds: list, times: FloatArray, opts: ExportOptions):
    """Every message as ``(topic, log time ns, message)``, in log-time order."""
    t0_ns = _ns(times[0])
    yield "/scene", t0_ns, _scene_update(scene, t0_ns, rows, opts)
    robot = robot_yaw = None
    if rows is not None:
        from ..trajectory import Trajectory

        ns0 = _ns(rows[0, 0])
        yaws = _headings(rows, rows[:, 0])
        poses_ = [pose(r[1], r[2], y) for r, y in zip(rows, yaws, strict=True)]
        yield "/path", ns0, {"timestamp": timestamp(ns0), "frame_id": FRAME, "poses": poses_}
        robot = Trajectory(rows).at(times).reshape(len(times), -1)
        robot_yaw = _headings(rows, times)
    movers = _mover_updates(scene, times, opts) if scene.movers else None
    pending = list(preds)
    for k, t in enumerate(times):
        t_ns = _ns(t)
        while pending and _ns(pending[0]["t"]) <= t_ns:
            e = pending.pop(0)
            yield "/predictions", _ns(e["t"]), _prediction_update(e, _ns(e["t"]), opts)
        if movers is not None:
            yield ("/movers", *next(movers))
        if robot is not None:
            x, y, yaw = robot[k, 0], robot[k, 1], robot_yaw[k]
            yield "/robot", t_ns, {"timestamp": timestamp(t_ns), "frame_id": FRAME, "pose": pose(x, y, yaw)}
            yield "/robot_body", t_ns, _robot_body(scene.robot, x, y, yaw, t_ns, opts.robot_height)
    for e in pending:
        yield "/predictions", _ns(e["t"]), _prediction_update(e, _ns(e["t"]), opts)


def export_mcap(
    scene: Scene,
    path,
    trajectory: FloatArray | None = None,
    predictions: list | None = None,
    options: ExportOptions | None = None,
) -> McapReport:
    """Write ``scene`` (and a trajectory) as an MCAP file for Foxglove / Lichtblick.

    Parameters
    ----------
    scene : Scene
    path : path-like
        The ``.mcap`` file, written atomically (a failure leaves no partial file).
    trajectory : (n, 3) or (n, 4) float, optional
        Rows ``[t, x, y]`` / ``[t, x, y, heading]``, t strictly increasing and >= 0.
    predictions : list of dict, optional
        A navigate file's ``replan_log``: entries with ``t``, ``predicted`` (rows
        ``[x, y, vx, vy, radius]``) and ``plan`` (rows ``[t, x, y, ...]``); each becomes a
        ``/predictions`` message at its ``t``.
    options : ExportOptions, optional

    Returns
    -------
    McapReport

    Raises
    ------
    InputError
        A trajectory before t = 0 (MCAP log times are unsigned), rows of the wrong
        shape, or a bad replan log.
    ImportError
        When the ``mcap`` package is not installed (``pip install gfuzzy[export]``).
    """
    opts = options or ExportOptions()
    try:
        from mcap.writer import CompressionType, Writer
    except ImportError:
        raise ImportError("gfuzzy export needs the mcap package: pip install 'gfuzzy[export]' (or pip install mcap)") from None
    from .. import __version__

    rows = _check_rows(trajectory)
    preds = _valid_predictions(predictions)
    if any(float(e["t"]) < 0 for e in preds):
        raise InputError("replan_log: a replan before t = 0 cannot be an MCAP log time")
    if rows is not None:
        times = step_times(float(rows[0, 0]), float(rows[-1, 0]), opts.step)
    else:
        times = step_times(0.0, opts.span if opts.span is not None else default_span(scene), opts.step)
    counts = {topic: 0 for topic in TOPICS}

    def write(tmp: str) -> None:
        with open(tmp, "wb") as fh:
            w = Writer(fh, compression=CompressionType.ZSTD)
            w.start(profile="", library=f"gfuzzy {__version__}")
            schema_ids = {name: w.register_schema(name, "jsonschema", json.dumps(SCHEMAS[name]).encode()) for name in sorted(set(TOPICS.values()))}
            channels: dict = {}
            for topic, t_ns, msg in _messages(scene, rows, preds, times, opts):
                if topic not in channels:
                    channels[topic] = w.register_channel(topic, "json", schema_ids[TOPICS[topic]])
                data = json.dumps(msg, separators=(",", ":"), allow_nan=False).encode()
                w.add_message(channels[topic], log_time=t_ns, data=data, publish_time=t_ns, sequence=counts[topic])
                counts[topic] += 1
            w.finish()

    write_atomic_with(path, write)
    counts = {k: v for k, v in counts.items() if v}
    t_end = float(times[-1])
    if preds:
        t_end = max(t_end, float(preds[-1]["t"]))
    log.info("wrote %s: %s", path, counts)
    return McapReport(Path(path), counts, float(times[0]), t_end)
