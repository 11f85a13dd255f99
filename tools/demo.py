"""`make demo`: plan the building-floor query and write its trajectory, picture and GIF;
then navigate among real pedestrians (ETH) without knowing their future.

Runs the real command line (`gfuzzy plan`, `check`, `render`, `navigate`) on the bundled
scenes and roadmaps; everything lands in out/.
"""

from __future__ import annotations

import sys
from pathlib import Path

from gfuzzy.cli import main

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "scenes" / "building-floor.yaml"
PEOPLE = ROOT / "scenes" / "eth-crossing.yaml"
ROADMAP = ROOT / "roadmaps" / "building-floor.json"
OUT = ROOT / "out"


def run(*args: str) -> int:
    print("$ gfuzzy " + " ".join(str(a) for a in args), flush=True)
    return main([str(a) for a in args])


def demo() -> int:
    OUT.mkdir(exist_ok=True)
    roadmap = ["--roadmap", str(ROADMAP)] if ROADMAP.exists() else []
    traj = OUT / "building-floor.json"
    status = run("plan", SCENE, *roadmap, "-o", OUT / "building-floor.csv")
    if status != 0:
        return status
    steps = [
        ("check", SCENE, traj),
        ("render", SCENE, traj, "-o", OUT / "building-floor.png", "--speed"),
        ("render", SCENE, traj, "-o", OUT / "building-floor.gif"),
        ("plan", SCENE, *roadmap, "--refine", "--speed-layer", "-o", OUT / "building-floor-refined.json"),
        ("check", SCENE, OUT / "building-floor-refined.json"),
        ("render", SCENE, OUT / "building-floor-refined.json", "-o", OUT / "building-floor-refined.png", "--speed"),
        # among people: observed every 0.25 s, their future unknown; checked against the real tracks
        ("navigate", PEOPLE, "-o", OUT / "eth-navigate.json"),
        ("check", PEOPLE, OUT / "eth-navigate.json"),
        ("render", PEOPLE, OUT / "eth-navigate.json", "-o", OUT / "eth-navigate.gif"),
    ]
    for args in steps:
        status = run(*args)
        if status != 0:
            return status
    made = sorted(p.name for p in [*OUT.glob("building-floor*"), *OUT.glob("eth-navigate*")])
    print(f"\nwrote {', '.join(made)} in {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(demo())
