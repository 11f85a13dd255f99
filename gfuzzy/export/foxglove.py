"""JSON Schemas of the Foxglove messages gfuzzy writes (``foxglove.SceneUpdate``,
``foxglove.PoseInFrame``, ``foxglove.PosesInFrame``), and the small builders of their parts.

The schemas are written for gfuzzy from Foxglove's published message reference (the
``foxglove`` schema set, MIT-licensed, whose JSON Schema rendition lives in the
``foxglove/schemas`` repository under ``schemas/jsonschema/``): the same message names, field
names, field types and enumeration values, every type written out in place (no ``$ref``:
Foxglove's JSON Schema reader follows the upstream files' shape). Two deliberate differences:
every object has ``additionalProperties: false`` (a misspelt field in gfuzzy's output then
fails validation in the tests instead of being silently ignored by the viewer), and only the
primitives gfuzzy can write are spelt out in detail (models are accepted as the upstream
files describe them). ``tools/check_foxglove_schemas.py`` compares them with a checkout of
the upstream files field by field (at its commit dd8b4f3: the same 177 + 14 + 14 fields and
JSON types) and validates exported messages against the upstream files. They are embedded in every MCAP file :mod:`gfuzzy.export.export` writes, as
the ``jsonschema`` schema of each channel.
"""

from __future__ import annotations

import math

__all__ = [
    "SCHEMAS",
    "schema",
    "timestamp",
    "vec3",
    "quat_yaw",
    "pose",
    "color",
]


def _obj(props: dict, title: str | None = None, description: str | None = None) -> dict:
    out: dict = {}
    if title:
        out["title"] = title
    if description:
        out["description"] = description
    out.update({"type": "object", "properties": props, "additionalProperties": False})
    return out


def _num(description: str) -> dict:
    return {"type": "number", "description": description}


def _time(description: str) -> dict:
    return {
        "type": "object",
        "title": "time",
        "description": description,
        "properties": {
            "sec": {"type": "integer", "minimum": 0},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
        "additionalProperties": False,
    }


def _duration(description: str) -> dict:
    return {
        "type": "object",
        "title": "duration",
        "description": description,
        "properties": {
            "sec": {"type": "integer"},
            "nsec": {"type": "integer", "minimum": 0, "maximum": 999_999_999},
        },
        "additionalProperties": False,
    }


def _vector3(description: str) -> dict:
    return _obj({k: _num(f"{k} coordinate length") for k in "xyz"}, "foxglove.Vector3", description)


def _point3() -> dict:
    return _obj({k: _num(f"{k} coordinate position") for k in "xyz"}, "foxglove.Point3", "A point in 3D space")


def _quaternion() -> dict:
    return _obj({k: _num(f"{k} value") for k in "xyzw"}, "foxglove.Quaternion", "Quaternion denoting orientation in 3D space")


def _pose(description: str) -> dict:
    return _obj(
        {"position": _vector3("Point denoting position in 3D space"), "orientation": _quaternion()},
        "foxglove.Pose",
        description,
    )


def _color(description: str) -> dict:
    return _obj(
        {k: _num(f"{name} value between 0 and 1") for k, name in zip("rgba", ("Red", "Green", "Blue", "Alpha"), strict=True)},
        "foxglove.Color",
        description,
    )


def _array(items: dict, description: str) -> dict:
    return {"type": "array", "items": items, "description": description}


def _enum(title: str, description: str, values: list[tuple[str, int]]) -> dict:
    return {"title": title, "description": description, "oneOf": [{"title": n, "const": v} for n, v in values]}


def _primitives() -> dict:
    """The SceneEntity fields that hold primitives -> their array schemas."""
    pose = _pose("Position and orientation of the primitive")
    arrow = _obj(
        {
            "pose": pose,
            "shaft_length": _num("Length of the arrow shaft"),
            "shaft_diameter": _num("Diameter of the arrow shaft"),
            "head_length": _num("Length of the arrow head"),
            "head_diameter": _num("Diameter of the arrow head"),
            "color": _color("Color of the arrow"),
        },
        "foxglove.ArrowPrimitive",
        "A primitive representing an arrow",
    )
    cube = _obj(
        {"pose": pose, "size": _vector3("Size of the cube along each axis"), "color": _color("Color of the cube")},
        "foxglove.CubePrimitive",
        "A primitive representing a cube or rectangular prism",
    )
    sphere = _obj(
        {"pose": pose, "size": _vector3("Size (diameter) of the sphere along each axis"), "color": _color("Color of the sphere")},
        "foxglove.SpherePrimitive",
        "A primitive representing a sphere or ellipsoid",
    )
    cylinder = _obj(
        {
            "pose": pose,
            "size": _vector3("Size of the cylinder's bounding box"),
            "bottom_scale": _num("0-1, ratio of the diameter of the cylinder's bottom face to that of its bounding box"),
            "top_scale": _num("0-1, ratio of the diameter of the cylinder's top face to that of its bounding box"),
            "color": _color("Color of the cylinder"),
        },
        "foxglove.CylinderPrimitive",
        "A primitive representing a cylinder, elliptic cylinder, or truncated cone",
    )
    line = _obj(
        {
            "type": _enum(
                "foxglove.LineType",
                "An enumeration indicating how input points should be interpreted to create lines",
                [("LINE_STRIP", 0), ("LINE_LOOP", 1), ("LINE_LIST", 2)],
            ),
            "pose": pose,
            "thickness": _num("Line thickness"),
            "scale_invariant": {"type": "boolean", "description": "Whether the thickness is in pixels (true) or metres (false)"},
            "points": _array(_point3(), "Points along the line"),
            "color": _color("Solid color to use for the whole line"),
            "colors": _array(_color("Per-point color"), "Per-point colors"),
            "indices": _array({"type": "integer", "minimum": 0}, "Indices into the points and colors attribute arrays"),
        },
        "foxglove.LinePrimitive",
        "A primitive representing a series of points connected by lines",
    )
    triangles = _obj(
        {
            "pose": pose,
            "points": _array(_point3(), "Vertices to use for triangles, interpreted as a list of triples"),
            "color": _color("Solid color to use for the whole shape"),
            "colors": _array(_color("Per-vertex color"), "Per-vertex colors"),
            "indices": _array({"type": "integer", "minimum": 0}, "Indices into the points and colors attribute arrays"),
        },
        "foxglove.TriangleListPrimitive",
        "A primitive representing a set of triangles or a surface tiled by triangles",
    )
    text = _obj(
        {
            "pose": pose,
            "billboard": {"type": "boolean", "description": "Whether the text should respect pose.orientation (false) or always face the camera (true)"},
            "font_size": _num("Font size (height of one line of text)"),
            "scale_invariant": {"type": "boolean", "description": "Whether the font size is in pixels (true) or metres (false)"},
            "color": _color("Color of the text"),
            "text": {"type": "string", "description": "Text"},
        },
        "foxglove.TextPrimitive",
        "A primitive representing a text label",
    )
    model = {
        "title": "foxglove.ModelPrimitive",
        "description": "A primitive representing a 3D model file loaded from an external URL or embedded data",
        "type": "object",
    }
    return {
        "arrows": _array(arrow, "Arrow primitives"),
        "cubes": _array(cube, "Cube primitives"),
        "spheres": _array(sphere, "Sphere primitives"),
        "cylinders": _array(cylinder, "Cylinder primitives"),
        "lines": _array(line, "Line primitives"),
        "triangles": _array(triangles, "Triangle list primitives"),
        "texts": _array(text, "Text primitives"),
        "models": _array(model, "Model primitives"),
    }


def _scene_update() -> dict:
    entity = _obj(
        {
            "timestamp": _time("Timestamp of the entity"),
            "frame_id": {"type": "string", "description": "Frame of reference"},
            "id": {"type": "string", "description": "Identifier for the entity; it replaces any prior entity on the same topic with the same id"},
            "lifetime": _duration("Length of time (relative to timestamp) after which the entity is removed; zero: until replaced or deleted"),
            "frame_locked": {"type": "boolean", "description": "Whether the entity follows the frame given in frame_id as it moves relative to the fixed frame"},
            "metadata": _array(
                _obj({"key": {"type": "string"}, "value": {"type": "string"}}, "foxglove.KeyValuePair", "A key with its associated value"),
                "Additional user-provided metadata associated with the entity; keys must be unique",
            ),
            **_primitives(),
        },
        "foxglove.SceneEntity",
        "A visual element in a 3D scene; its primitives share one frame of reference",
    )
    deletion = _obj(
        {
            "timestamp": _time("Timestamp of the deletion; only matching entities earlier than it are deleted"),
            "type": _enum(
                "foxglove.SceneEntityDeletionType",
                "Type of deletion action to perform",
                [("MATCHING_ID", 0), ("ALL", 1)],
            ),
            "id": {"type": "string", "description": "Identifier which must match if type is MATCHING_ID"},
        },
        "foxglove.SceneEntityDeletion",
        "Command to remove previously published entities",
    )
    out = _obj(
        {"deletions": _array(deletion, "Scene entities to delete"), "entities": _array(entity, "Scene entities to add or replace")},
        "foxglove.SceneUpdate",
        "An update to the entities displayed in a 3D scene",
    )
    return out


def _pose_in_frame() -> dict:
    return _obj(
        {
            "timestamp": _time("Timestamp of pose"),
            "frame_id": {"type": "string", "description": "Frame of reference for pose position and orientation"},
            "pose": _pose("Pose in 3D space"),
        },
        "foxglove.PoseInFrame",
        "A timestamped pose for an object or reference frame in 3D space",
    )


def _poses_in_frame() -> dict:
    return _obj(
        {
            "timestamp": _time("Timestamp of pose"),
            "frame_id": {"type": "string", "description": "Frame of reference for pose position and orientation"},
            "poses": _array(_pose("A position and orientation in 3D space"), "Poses in 3D space"),
        },
        "foxglove.PosesInFrame",
        "An array of timestamped poses for an object or reference frame in 3D space",
    )


def _with_meta(s: dict) -> dict:
    return {"$schema": "http://json-schema.org/draft-07/schema#", **s}


#: Message name -> its JSON Schema (draft-07).
SCHEMAS: dict[str, dict] = {
    "foxglove.SceneUpdate": _with_meta(_scene_update()),
    "foxglove.PoseInFrame": _with_meta(_pose_in_frame()),
    "foxglove.PosesInFrame": _with_meta(_poses_in_frame()),
}


def schema(name: str) -> dict:
    """The JSON Schema of message ``name`` (e.g. ``"foxglove.SceneUpdate"``)."""
    return SCHEMAS[name]


# --------------------------------------------------------------------------- message parts


def timestamp(ns: int) -> dict:
    """``{"sec", "nsec"}`` of a time in nanoseconds (>= 0)."""
    ns = int(ns)
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def vec3(x: float, y: float, z: float = 0.0) -> dict:
    """A ``foxglove.Vector3`` / ``Point3``."""
    return {"x": float(x), "y": float(y), "z": float(z)}


def quat_yaw(yaw: float) -> dict:
    """The quaternion of a rotation by ``yaw`` radians about z."""
    return {"x": 0.0, "y": 0.0, "z": math.sin(0.5 * yaw), "w": math.cos(0.5 * yaw)}


def pose(x: float, y: float, yaw: float = 0.0, z: float = 0.0) -> dict:
    """A ``foxglove.Pose`` in the plane (rotation about z)."""
    return {"position": vec3(x, y, z), "orientation": quat_yaw(yaw)}


def color(r: float, g: float, b: float, a: float = 1.0) -> dict:
    """A ``foxglove.Color`` (components in [0, 1])."""
    return {"r": float(r), "g": float(g), "b": float(b), "a": float(a)}
