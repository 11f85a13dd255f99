"""Regenerate the pictures in docs/img with the current code (run after any change that
alters answers or drawing).

    python tools/doc_images.py [PICTURE ...]     # all, or only these (e.g. depot.png)

Runs the real command line: `gfuzzy plan` then `gfuzzy render`, with the bundled roadmaps.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.cli import main  # noqa: E402

IMG = ROOT / "docs" / "img"
SCENES = ROOT / "scenes"

#: picture -> (scene, plan flags, render flags)
PICTURES = {
    "building-floor.png": ("building-floor", [], []),
    "office-refined-speed.png": ("office-polygons", ["--refine", "--speed-layer"], ["--speed", "--no-roadmap"]),
    # occupancy-grid maps (scenes/maps): the grid drawn at its extent, unknown gray
    "depot.png": ("depot", ["--query", "into-rack-aisle"], []),
    "tb3-arena.png": ("tb3-arena", ["--query", "south-to-north"], []),
    "small-house.png": ("small-house", ["--query", "southwest-to-east"], ["--no-roadmap"]),
    "footprint-office.png": ("footprint-office", ["--query", "dock", "--refine", "--speed-layer"], ["--no-roadmap"]),
}


def run(*args) -> int:
    print("$ gfuzzy " + " ".join(map(str, args)), flush=True)
    return main([str(a) for a in args])


def make(only: list[str] | None = None) -> int:
    with tempfile.TemporaryDirectory() as tmp:
        for picture, (scene, plan_flags, render_flags) in PICTURES.items():
            if only and picture not in only:
                continue
            scene_file = SCENES / f"{scene}.yaml"
            answer = Path(tmp) / f"{scene}.json"
            roadmap = ["--roadmap", ROOT / "roadmaps" / f"{scene}.json"]
            if run("plan", scene_file, *roadmap, *plan_flags, "-o", answer) != 0:
                return 1
            if run("render", scene_file, answer, *render_flags, "-o", IMG / picture) != 0:
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(make(sys.argv[1:]))
