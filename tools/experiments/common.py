"""Shared pieces of the experiments: paths, the Dask client, scenes, markdown tables."""

from __future__ import annotations

import json
import math
import statistics
from dataclasses import dataclass
from pathlib import Path

from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.scene.scene import load_scene

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
ROADMAPS = ROOT / "roadmaps"
DOCS = ROOT / "docs"
IMG = DOCS / "img"

#: The paper's figures as the brief of this project gives them (building floor, 3 GHz
#: Pentium IV): vertices -> query seconds, and the 198-vertex answer.
PAPER_SECONDS = {100: 0.33, 198: 0.46, 1000: 3.90}
PAPER_198 = {"vertices": 198, "seconds": 0.46, "duration": 35.14, "roadmap_distance": 15.82, "delay_factor": 2.22}


@dataclass
class Context:
    """What every experiment gets: the Dask client, a scratch folder, the seed, and the
    folder of its pictures."""

    client: object
    scratch: Path
    seed: int = 1
    img: Path = IMG  # where the pictures go (docs/img for a full run)


def bundled(name: str):
    """(scene, saved roadmap) of a bundled scene."""
    scene = load_scene(SCENES / f"{name}.yaml")
    return scene, load_roadmap(ROADMAPS / f"{scene.name}.json", scene)


def all_bundled() -> list:
    return [bundled(p.stem) for p in sorted(SCENES.glob("*.yaml"))]


def load_doc(path: Path) -> dict:
    return json.loads(Path(path).read_text())


def fmt(v, spec: str = ".2f", missing: str = "-") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return missing
    return format(v, spec)


def md_table(header: list[str], rows: list[list]) -> str:
    out = ["| " + " | ".join(header) + " |", "| " + " | ".join("---" for _ in header) + " |"]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out)


def median(xs):
    xs = [x for x in xs if x is not None]
    return statistics.median(xs) if xs else None


def linear_fit(x, y):
    """Least-squares y = a + b x; returns (a, b, pearson r)."""
    import numpy as np

    x = np.asarray(x, float)
    y = np.asarray(y, float)
    b, a = np.polyfit(x, y, 1)
    r = float(np.corrcoef(x, y)[0, 1]) if len(x) > 2 else float("nan")
    return float(a), float(b), r
