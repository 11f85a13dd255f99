"""Draws docs/img/export-map.png: a scene's obstacles (outlines) over the Nav2 map
`gfuzzy export --map` makes of them, at a coarse resolution so the cells show.

    python tools/export_images.py [--resolution 0.25]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Circle  # noqa: E402
from matplotlib.patches import Polygon as Patch  # noqa: E402

from gfuzzy.export.mapexport import rasterise  # noqa: E402
from gfuzzy.scene.scene import Box, Disc, Polygon, load_scene  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "office-polygons.yaml"))
    ap.add_argument("--resolution", type=float, default=0.25)
    ap.add_argument("-o", "--output", default=str(ROOT / "docs" / "img" / "export-map.png"))
    args = ap.parse_args()
    scene = load_scene(args.scene)
    grid = rasterise(scene, args.resolution)
    h, w = grid.shape
    ox, oy = grid.origin
    fig, ax = plt.subplots(figsize=(7.5, 5.2), dpi=100)
    ax.imshow(np.where(grid.occupied, 0.0, 254 / 255), cmap="gray", vmin=0, vmax=1, interpolation="nearest",
              extent=(ox, ox + w * grid.resolution, oy, oy + h * grid.resolution), origin="upper")
    for ob in scene.obstacles:
        if isinstance(ob, Disc):
            ax.add_patch(Circle(ob.center, ob.radius, fill=False, ec="tab:orange", lw=1.5))
        elif isinstance(ob, Box):
            ax.add_patch(Patch(ob.vertices(), closed=True, fill=False, ec="tab:orange", lw=1.5))
        elif isinstance(ob, Polygon):
            ax.add_patch(Patch(ob.points, closed=True, fill=False, ec="tab:orange", lw=1.5))
    ax.set_xticks(np.arange(ox, ox + w * grid.resolution + 1e-9, grid.resolution), minor=True)
    ax.set_yticks(np.arange(oy, oy + h * grid.resolution + 1e-9, grid.resolution), minor=True)
    ax.grid(which="minor", color="0.8", lw=0.3)
    ax.set_title(f"{scene.name}: obstacles (orange) over the exported map ({grid.resolution:g} m cells)", fontsize=10)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    fig.tight_layout()
    fig.savefig(args.output)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
