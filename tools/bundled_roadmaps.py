"""Rebuild the bundled roadmaps (roadmaps/*.json) with today's code, or check that they are.

    python tools/bundled_roadmaps.py                  # rebuild every one (make roadmaps)
    python tools/bundled_roadmaps.py --check          # rebuild in memory; name those that differ
    python tools/bundled_roadmaps.py sealed-room ...  # only these

Each file is rebuilt for its scene, ``scenes/<name>.yaml``, from the options it stores
(``vertices``, ``seed``, ``neighbors``, ``resolution``, ``sampler``, ``bridge_ratio``), as
``gfuzzy roadmap scenes/<name>.yaml -n <vertices> --seed <seed>`` builds it: the free-space
repair and the component join at their defaults (on) unless the file says ``false`` (a file
written before they existed says nothing; its rebuild stores them). Same seed, same code,
same roadmap: a file that ``--check`` finds different was built by older code (the passage
sampler's draws changed since), and ``make roadmaps`` brings it up to date. Run
``gfuzzy regress scenes/*.yaml`` after a rebuild: the answers may change with the roadmap.

Exit status: 0 (rebuilt, or all identical), 1 (``--check``: some differ), 2 (bad input).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gfuzzy.roadmap.roadmap import Roadmap, build_roadmap, load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]


def rebuild(path: Path) -> tuple[Roadmap, Roadmap]:
    """The bundled roadmap at ``path`` and its rebuild from its stored options."""
    scene = load_scene(ROOT / "scenes" / f"{path.stem}.yaml")
    old = load_roadmap(path, scene)
    stored = json.loads(path.read_text(encoding="utf-8"))["options"]
    options = replace(old.options, repair=stored.get("repair", True), join=stored.get("join", True))
    return old, build_roadmap(scene, options)


def same(a: Roadmap, b: Roadmap) -> bool:
    """The same vertices, edges and options (the build's timings aside)."""
    return (
        a.vertices.shape == b.vertices.shape
        and np.array_equal(a.vertices, b.vertices)
        and np.array_equal(a.edges, b.edges)
        and a.options == b.options
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="roadmap names (default: every roadmaps/*.json)")
    ap.add_argument("--check", action="store_true", help="compare only; write nothing")
    args = ap.parse_args(argv)
    paths = [ROOT / "roadmaps" / f"{n}.json" for n in args.names] or sorted((ROOT / "roadmaps").glob("*.json"))
    missing = [str(p) for p in paths if not p.is_file()]
    if missing:
        print(f"bundled_roadmaps: no such roadmap: {', '.join(missing)}", file=sys.stderr)
        return 2
    differ = []
    for path in paths:
        t = time.perf_counter()
        old, new = rebuild(path)
        verdict = "identical" if same(old, new) else "differs"
        if verdict == "differs":
            differ.append(path.stem)
        print(
            f"{path.stem}: {verdict} ({len(old.vertices)} -> {len(new.vertices)} vertices, "
            f"{len(old.edges)} -> {len(new.edges)} edges, {time.perf_counter() - t:.1f} s)",
            flush=True,
        )
        if not args.check and verdict == "differs":
            new.save(path)
    if args.check and differ:
        print(f"{len(differ)} of {len(paths)} differ from today's build: {' '.join(differ)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
