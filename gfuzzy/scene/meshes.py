"""Mesh obstacles: the xy footprint of any file trimesh reads, relative to the scene file.

The world is planar, so a mesh blocks its footprint at every height: the union of its
triangles projected on xy (those of positive area), as polygons.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from .yamldoc import _V, MAX_MAGNITUDE, _inside, _join

__all__ = ["mesh_footprint"]


def mesh_footprint(v: _V, spec, place: str, folder: Path) -> tuple[list, bytes]:
    """A ``mesh`` obstacle's xy footprint: its polygons, and the file's bytes (for the hash).

    Raises
    ------
    SceneError
        A path that is not relative or leaves ``folder``, an unreadable file, not a mesh,
        no finite triangles, a vertex beyond ``MAX_MAGNITUDE``, or an empty footprint.
    """
    import shapely
    import trimesh

    spec = v.mapping(spec, place, required=("file",))
    rel = spec["file"]
    fplace = _join(place, "file")
    full = _inside(v, folder, rel, fplace, "mesh")
    try:
        full.relative_to(folder.resolve())
    except ValueError:
        v.fail(fplace, f"mesh path {rel!r} leaves the scene file's folder")
    try:
        data = full.read_bytes()
    except OSError as exc:
        v.fail(fplace, f"cannot read mesh {rel!r}: {exc.strerror or exc}")
    try:
        with warnings.catch_warnings():  # numpy's overflow warnings on absurd vertices: refused below
            warnings.simplefilter("ignore", RuntimeWarning)
            mesh = trimesh.load(full, force="mesh")
        tris = np.asarray(mesh.triangles, dtype=float)
    except Exception as exc:  # trimesh raises many kinds on a bad file
        why = " ".join(str(exc).split()) or type(exc).__name__
        if isinstance(exc, ImportError):  # trimesh guessing at an unknown format
            why = "not a mesh format trimesh reads"
        v.fail(fplace, f"cannot read mesh {rel!r}: {why}")
    if tris.size == 0 or not np.all(np.isfinite(tris)):
        v.fail(fplace, f"mesh {rel!r} has no usable triangles")
    if np.abs(tris).max() > MAX_MAGNITUDE:
        v.fail(fplace, f"mesh {rel!r} has a vertex beyond {MAX_MAGNITUDE:g} in magnitude")
    tri2 = tris[:, :, :2]
    area = 0.5 * np.abs(
        (tri2[:, 1, 0] - tri2[:, 0, 0]) * (tri2[:, 2, 1] - tri2[:, 0, 1])
        - (tri2[:, 2, 0] - tri2[:, 0, 0]) * (tri2[:, 1, 1] - tri2[:, 0, 1])
    )
    tri2 = tri2[area > 1e-12]
    if len(tri2) == 0:
        v.fail(fplace, f"mesh {rel!r} has an empty xy footprint")
    union = shapely.union_all(shapely.polygons(tri2)).buffer(0)
    polys = [union] if union.geom_type == "Polygon" else list(getattr(union, "geoms", []))
    polys = [p for p in polys if p.geom_type == "Polygon" and p.area > 1e-12]
    if not polys:
        v.fail(fplace, f"mesh {rel!r} has an empty xy footprint")
    return polys, data
