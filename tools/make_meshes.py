"""Generate the mesh files that bundled scenes refer to (deterministic; rerun to refresh).

scenes/meshes/shelves.stl: the shelving of scenes/warehouse-mesh.yaml, three rows of racks
(each row split by a cross aisle at 5.6 < x < 6.4), 0.8 deep and 2.0 high, standing on z = 0,
plus a block of stacked pallets in the north-east corner. A mesh blocks its xy footprint, so only
the racks' outlines matter to the planner; the height is for pictures.

    python tools/make_meshes.py [OUTDIR]      # default: scenes/meshes next to this tools/ folder
"""

from __future__ import annotations

import os
import sys

import numpy as np
import trimesh

# (xmin, ymin, xmax, ymax, height)
SHELVES = [(2.0, y - 0.4, 5.6, y + 0.4, 2.0) for y in (2.0, 4.0, 6.0)]  # west racks
SHELVES += [(6.4, y - 0.4, 9.6, y + 0.4, 2.0) for y in (2.0, 4.0, 6.0)]  # east racks
SHELVES += [(10.8, 6.6, 11.8, 7.8, 1.2)]  # pallets


def shelves_mesh() -> trimesh.Trimesh:
    parts = []
    for xmin, ymin, xmax, ymax, h in SHELVES:
        box = trimesh.creation.box(extents=(xmax - xmin, ymax - ymin, h))
        box.apply_translation(((xmin + xmax) / 2, (ymin + ymax) / 2, h / 2))
        parts.append(box)
    mesh = trimesh.util.concatenate(parts)
    mesh.vertices = np.round(mesh.vertices, 6)
    return mesh


def write_stl(mesh: trimesh.Trimesh, path: str) -> None:
    data = trimesh.exchange.stl.export_stl(mesh)  # binary STL, fixed header: same bytes each run
    tmp = path + ".tmp"
    with open(tmp, "wb") as fh:
        fh.write(data)
    os.replace(tmp, path)


def main(argv: list[str]) -> int:
    here = os.path.dirname(os.path.abspath(__file__))
    outdir = argv[0] if argv else os.path.join(here, "..", "scenes", "meshes")
    os.makedirs(outdir, exist_ok=True)
    path = os.path.join(outdir, "shelves.stl")
    write_stl(shelves_mesh(), path)
    print(f"{os.path.normpath(path)}: {os.path.getsize(path)} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
