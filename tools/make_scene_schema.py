"""Writes docs/scene.schema.json, the JSON Schema of the scene file (CONTRACT sections 1
and 6), from the definitions below: ``python tools/make_scene_schema.py docs/scene.schema.json``.
tests/test_export.py checks that the file is what this script writes, that every bundled
scene and every random valid scene passes it, and which bad scenes it rejects.
"""

import json

#: Largest magnitude of a number (gfuzzy.scene.yamldoc.MAX_MAGNITUDE): this also refuses infinities.
MAXMAG = 1e9


def num(**kw):
    d = {"type": "number", "minimum": -MAXMAG, "maximum": MAXMAG}
    d.update(kw)
    return d


D = {}
D["number"] = num(description="A finite number (at most 1e9 in magnitude).")
D["positive"] = {"type": "number", "exclusiveMinimum": 0, "maximum": MAXMAG, "description": "A positive number."}
D["nonnegative"] = {"type": "number", "minimum": 0, "maximum": MAXMAG, "description": "A number >= 0."}
D["point"] = {"type": "array", "items": {"$ref": "#/definitions/number"}, "minItems": 2, "maxItems": 2, "description": "[x, y], metres."}
D["size"] = {"type": "array", "items": {"$ref": "#/definitions/positive"}, "minItems": 2, "maxItems": 2}
D["points"] = {"type": "array", "items": {"$ref": "#/definitions/point"}}
D["polygon"] = {"type": "array", "items": {"$ref": "#/definitions/point"}, "minItems": 3,
                "description": "A simple polygon (>= 3 points, either winding, not self-intersecting, positive area)."}
D["name"] = {"type": "string", "pattern": "^[^\\u0000-\\u001f]*[^\\u0000-\\u001f\\s][^\\u0000-\\u001f]*$",
             "description": "A non-empty name without control characters; unique among its kind."}
D["relative_file"] = {"type": "string", "minLength": 1, "pattern": "^(?![/~])[^\\u0000]*$",
                      "description": "A path relative to the scene file that stays inside its folder."}
D["pose"] = {"type": "array", "items": {"$ref": "#/definitions/number"}, "minItems": 2, "maxItems": 3,
             "description": "[x, y] (a holonomic disc robot) or [x, y, heading] (any other robot)."}

robot = {
    "type": "object", "additionalProperties": False, "required": ["vmax"],
    "description": "The robot: exactly one of disc, box, footprint.",
    "properties": {
        "disc": {"$ref": "#/definitions/positive", "description": "A disc robot of this radius."},
        "box": {"$ref": "#/definitions/size", "description": "A rectangle robot [length along its heading, width]."},
        "footprint": {"$ref": "#/definitions/polygon", "description": "A polygon in the robot's frame (x forward, y left, the pose's reference point at the origin)."},
        "vmax": {"$ref": "#/definitions/positive", "description": "Bound on configuration speed (xy speed + |heading rate| x circumradius)."},
        "amax": {"$ref": "#/definitions/positive", "description": "Acceleration bound, used by the speed layer."},
        "clearance": {"$ref": "#/definitions/nonnegative", "description": "Distance kept from static obstacles (default 0)."},
        "mover_clearance": {"$ref": "#/definitions/nonnegative", "description": "Distance kept from every present mover (default 0)."},
        "kinematics": {"enum": ["holonomic", "unicycle"], "description": "holonomic (default) or unicycle (differential drive: straight moves along the heading and turns in place)."},
        "wmax": {"$ref": "#/definitions/positive", "description": "Unicycle only: bound on |turning rate|, rad/s (default vmax / circumradius)."},
        "reverse": {"type": "boolean", "description": "Unicycle only: may it drive backwards (default false)."},
    },
    "oneOf": [{"required": ["disc"]}, {"required": ["box"]}, {"required": ["footprint"]}],
    "if": {"not": {"required": ["kinematics"], "properties": {"kinematics": {"const": "unicycle"}}}},
    "then": {"properties": {"wmax": False, "reverse": False}},
}


def one(kind, schema, description):
    return {"type": "object", "additionalProperties": False, "required": [kind],
            "properties": {kind: schema}, "description": description}


obstacle = {"oneOf": [
    one("box", {"type": "object", "additionalProperties": False, "required": ["center", "size"], "properties": {
        "center": {"$ref": "#/definitions/point"}, "size": {"$ref": "#/definitions/size"},
        "angle": {"$ref": "#/definitions/number", "description": "Radians, about the center (default 0)."}}},
        "A box [width along x, height along y] rotated by angle about its center."),
    one("disc", {"type": "object", "additionalProperties": False, "required": ["center", "radius"], "properties": {
        "center": {"$ref": "#/definitions/point"}, "radius": {"$ref": "#/definitions/positive"}}}, "A disc."),
    one("polygon", {"$ref": "#/definitions/polygon"}, "A simple polygon, either winding."),
    one("mesh", {"type": "object", "additionalProperties": False, "required": ["file"], "properties": {
        "file": {"$ref": "#/definitions/relative_file"}}}, "A mesh file trimesh reads; it blocks its xy footprint."),
    one("map", {"type": "object", "additionalProperties": False, "required": ["file"], "properties": {
        "file": {"$ref": "#/definitions/relative_file", "description": "A ROS map_server / Nav2 map YAML (its image beside it)."},
        "unknown": {"enum": ["blocked", "free"], "description": "Whether unknown cells block (default blocked)."}}},
        "An occupancy-grid map: its occupied cells block, and its unknown ones unless unknown: free."),
]}

mover_common = {
    "name": {"$ref": "#/definitions/name"},
    "disc": {"$ref": "#/definitions/positive", "description": "A disc mover of this radius."},
    "box": {"$ref": "#/definitions/size", "description": "An axis-aligned box mover [w, h] that does not rotate."},
}
path_mover = {"type": "object", "additionalProperties": False, "required": ["name", "path", "speed", "mode"],
    "properties": dict(mover_common, **{
        "path": {"type": "array", "items": {"$ref": "#/definitions/point"}, "minItems": 2, "description": "A polyline of positive length."},
        "speed": {"$ref": "#/definitions/nonnegative", "description": "Constant speed along the path, m/s."},
        "mode": {"enum": ["loop", "bounce", "once"], "description": "loop: closes the polyline and repeats; bounce: back and forth; once: stops at the end."},
        "offset": {"$ref": "#/definitions/number", "description": "Arc length already travelled at t = 0 (default 0)."}}),
    "description": "A mover at constant speed along a path."}
timed_mover = {"type": "object", "additionalProperties": False, "required": ["name", "trajectory"],
    "properties": dict(mover_common, **{
        "trajectory": {"type": "array", "minItems": 1, "items": {"type": "array", "items": {"$ref": "#/definitions/number"}, "minItems": 3, "maxItems": 3},
                       "description": "[t, x, y] rows, t increasing; linear between rows; the mover exists from its first t to its last."}}),
    "description": "A mover along timed rows."}
mover = {"allOf": [{"oneOf": [path_mover, timed_mover]}, {"oneOf": [{"required": ["disc"]}, {"required": ["box"]}]}]}

query = {"type": "object", "additionalProperties": False, "required": ["name", "start", "goal"], "properties": {
    "name": {"$ref": "#/definitions/name"},
    "start": {"$ref": "#/definitions/pose"}, "goal": {"$ref": "#/definitions/pose"},
    "t0": {"$ref": "#/definitions/number", "description": "Departure time (default 0)."},
    "hold": {"$ref": "#/definitions/nonnegative", "description": "The robot then stays at the goal this long (default 0)."},
    "expect": {"type": "object", "additionalProperties": False, "description": "Expectations of a regression run.", "properties": {
        "status": {"enum": ["solved", "no_path", "invalid_query", "timeout"]},
        "max_duration": {"$ref": "#/definitions/nonnegative"},
        "max_delay_factor": {"$ref": "#/definitions/positive"}}}}}


def pose_len(n):
    p = {"minItems": n, "maxItems": n}
    return {"properties": {"queries": {"items": {"properties": {"start": p, "goal": p}}}}}


holonomic_disc = {"properties": {"robot": {"required": ["disc"], "not": {"required": ["kinematics"], "properties": {"kinematics": {"const": "unicycle"}}}}}}
has_map = {"required": ["obstacles"], "properties": {"obstacles": {"type": "array", "contains": {"required": ["map"]}}}}

schema = {
    "$schema": "http://json-schema.org/draft-07/schema#",
    "title": "gfuzzy scene file (version 1)",
    "description": "A gfuzzy scene: bounds, robot, static obstacles, movers and queries (CONTRACT sections 1 and 6). The schema checks keys, types, signs and lengths; the parser also checks what a schema cannot say (unique names, simple polygons, files that exist, non-finite numbers).",
    "type": "object",
    "additionalProperties": False,
    "required": ["version", "name", "robot"],
    "properties": {
        "version": {"const": 1},
        "name": {"type": "string", "pattern": "^[A-Za-z0-9_.-]+$"},
        "bounds": {"type": "array", "items": {"$ref": "#/definitions/number"}, "minItems": 4, "maxItems": 4,
                   "description": "[xmin, ymin, xmax, ymax]: the robot's whole body stays inside; optional when the scene has a map (then the map's extent)."},
        "robot": {"$ref": "#/definitions/robot"},
        "obstacles": {"type": ["array", "null"], "items": {"$ref": "#/definitions/obstacle"}, "description": "Static obstacles; each item has exactly one key."},
        "movers": {"type": ["array", "null"], "items": {"$ref": "#/definitions/mover"}, "description": "Moving obstacles: a disc or an axis-aligned box."},
        "queries": {"type": ["array", "null"], "items": {"$ref": "#/definitions/query"}},
    },
    "allOf": [
        {"if": holonomic_disc, "then": pose_len(2), "else": pose_len(3)},
        {"if": {"not": has_map}, "then": {"required": ["bounds"]}},
    ],
    "definitions": dict(D, robot=robot, obstacle=obstacle, mover=mover, query=query),
}


def render() -> str:
    """The schema file's text."""
    return json.dumps(schema, indent=2) + "\n"


if __name__ == "__main__":
    import sys
    from pathlib import Path

    Path(sys.argv[1] if len(sys.argv) > 1 else "docs/scene.schema.json").write_text(render(), encoding="utf-8")
