"""Cut the pedestrian excerpts shipped in data/pedestrians/ from the full ETH/UCY files.

    python tools/excerpt_tracks.py FULL_DATA_FOLDER [-o data/pedestrians]

Each excerpt keeps, verbatim and in file order, every row of the full file whose time lies
in its window (time = frame x 0.4 s / frame step, as ``gfuzzy tracks`` reads it), plus each
of those pedestrians' last row before the window and first row after it: so the window's
edges interpolate exactly as they do in the full file, and ``gfuzzy tracks`` makes the same
scenes from the excerpt as from the full file. Frame numbers are the original ones.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.scene.tracks import ANNOTATION_PERIOD, read_tracks  # noqa: E402

#: file -> (window start, window end) in seconds of the recording; what the bundled scenes
#: (eth-crossing, zara-crowd) and tests/test_tracks.py use.
WINDOWS = {
    "biwi_eth.txt": (300.0, 345.0),
    "biwi_hotel.txt": (50.0, 80.0),
    "crowds_zara01.txt": (205.0, 245.0),
    "students001.txt": (100.0, 140.0),
}


def excerpt(path: Path, t_lo: float, t_hi: float) -> tuple[list[str], int]:
    """The excerpt's lines, and the full file's frame step."""
    step = read_tracks(path, "eth").frame_step
    spf = ANNOTATION_PERIOD / step
    lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip()]
    rows = [(float(ln.split()[0]), float(ln.split()[1])) for ln in lines]
    inside = {pid for f, pid in rows if t_lo <= f * spf <= t_hi}
    before: dict = {}  # pid -> index of its last row before the window
    after: dict = {}  # pid -> index of its first row after it
    keep = set()
    for i, (f, pid) in enumerate(rows):
        t = f * spf
        if pid not in inside:
            continue
        if t < t_lo:
            before[pid] = i
        elif t > t_hi:
            after.setdefault(pid, i)
        else:
            keep.add(i)
    keep |= set(before.values()) | set(after.values())
    return [lines[i] for i in sorted(keep)], step


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder", type=Path, help="folder holding the full files")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "data" / "pedestrians")
    args = ap.parse_args(argv)
    args.output.mkdir(parents=True, exist_ok=True)
    for name, (t_lo, t_hi) in WINDOWS.items():
        lines, step = excerpt(args.folder / name, t_lo, t_hi)
        (args.output / name).write_text("\n".join(lines) + "\n", encoding="utf-8")
        frames = sorted({float(ln.split()[0]) for ln in lines})
        people = len({ln.split()[1] for ln in lines})
        print(
            f"{name}: {len(lines)} rows, {people} pedestrians, frames {frames[0]:g}..{frames[-1]:g} "
            f"(step {step}), window {t_lo:g}..{t_hi:g} s"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
