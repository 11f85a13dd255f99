"""Turn an ETH/UCY pedestrian file into a gfuzzy scene with timed `trajectory` movers.

Input: the plain-text form of the ETH (biwi_eth, biwi_hotel) and UCY (crowds_zara01,
students001) data sets, one annotation per line, whitespace-separated columns
``frame pedestrian_id x y [vx vy]`` (metres).  Annotated frames are 0.4 s apart; the frame
step (6 or 10, depending on the camera) is derived from the data: the smallest positive
difference between two frames of the same pedestrian is taken to be 0.4 s.

Output: a scene (CONTRACT.md section 1) whose bounds are the chosen region, a disc robot, one
`trajectory` mover per pedestrian (``ped-<id>``) and one query from --start to --goal at t0 = 0.
Times are seconds relative to the start of the window (so they start at 0).

* Each pedestrian is clipped to the time window [T, T + D]; where its track runs through a
  window boundary, a row is interpolated at the boundary.
* Each pedestrian is clipped to the region as well (rows interpolated where the track crosses
  the region's border), so every mover's centre stays inside the bounds.  A pedestrian who
  leaves the region and comes back becomes two movers, ``ped-<id>`` and ``ped-<id>-2``.
* After rounding (t, x and y to 3 decimals) a row whose t does not exceed the previous row's
  is dropped; a mover left with fewer than two rows is dropped.
* --max-movers N keeps the N movers present longest in the window (ties: smaller id first).

Example::

    python tools/ped_scene.py /work/shared/data/pedestrians/biwi_eth.txt \\
        --t-start 340 --duration 50 --region -2 -1 13 9 \\
        --start 4 -0.5 --goal 4 8.5 -o scenes/eth-crossing.yaml

Bad input (a file that cannot be read, a row that cannot be parsed, an impossible option)
prints one line on stderr naming the file (and line) and exits with status 2.  The output is
written atomically: to a temporary file in the same folder, then renamed.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import shlex
import sys
from collections import defaultdict
from dataclasses import dataclass
from itertools import pairwise

from gfuzzy.atomic import write_atomic

ANNOTATION_PERIOD = 0.4  # seconds between consecutive annotated frames (ETH/UCY convention)
NAME_RE = re.compile(r"^[a-zA-Z0-9_.-]+$")


class BadInput(Exception):
    """One line that names the file (and line) and what is wrong."""


@dataclass
class Mover:
    name: str
    pid: int
    rows: list[tuple[float, float, float]]  # (t, x, y), t relative to the window start

    @property
    def duration(self) -> float:
        return self.rows[-1][0] - self.rows[0][0]


# ---------------------------------------------------------------------------------- reading


def _integral(value: float) -> int | None:
    if math.isfinite(value) and value == int(value):
        return int(value)
    return None


def read_pedestrians(path: str) -> dict[int, list[tuple[int, float, float]]]:
    """Read a data file into {pedestrian id: [(frame, x, y), ...] sorted by frame}."""
    try:
        with open(path, encoding="utf-8") as fh:
            lines = fh.readlines()
    except (OSError, UnicodeDecodeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise BadInput(f"{path}: cannot read: {reason}") from None
    peds: dict[int, dict[int, tuple[float, float]]] = defaultdict(dict)
    for lineno, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        cols = text.split()
        if len(cols) not in (4, 6):
            raise BadInput(
                f"{path}:{lineno}: expected 4 or 6 columns (frame id x y [vx vy]), got {len(cols)}"
            )
        try:
            nums = [float(c) for c in cols]
        except ValueError:
            raise BadInput(f"{path}:{lineno}: not a number in {text!r}") from None
        if not all(math.isfinite(v) for v in nums):
            raise BadInput(f"{path}:{lineno}: non-finite number in {text!r}")
        frame, pid = _integral(nums[0]), _integral(nums[1])
        if frame is None or pid is None:
            raise BadInput(f"{path}:{lineno}: frame and pedestrian id must be whole numbers")
        if frame in peds[pid]:
            raise BadInput(f"{path}:{lineno}: pedestrian {pid} appears twice in frame {frame}")
        peds[pid][frame] = (nums[2], nums[3])
    if not peds:
        raise BadInput(f"{path}: no data rows")
    return {pid: [(f, *xy) for f, xy in sorted(rows.items())] for pid, rows in peds.items()}


def seconds_per_frame(path: str, peds: dict[int, list[tuple[int, float, float]]]) -> float:
    """0.4 s divided by the smallest positive frame step of any pedestrian."""
    steps = [b[0] - a[0] for rows in peds.values() for a, b in pairwise(rows)]
    if not steps:
        raise BadInput(f"{path}: no pedestrian has two rows; cannot derive the frame rate")
    return ANNOTATION_PERIOD / min(steps)


# ---------------------------------------------------------------------------------- clipping


def _lerp(a: tuple[float, float, float], b: tuple[float, float, float], u: float):
    return tuple(a[i] + u * (b[i] - a[i]) for i in range(3))


def clip_time(rows, t_lo: float, t_hi: float):
    """Rows (t, x, y) restricted to [t_lo, t_hi], with rows interpolated at the boundaries."""
    out = []
    for a, b in pairwise(rows):
        if b[0] < t_lo or a[0] > t_hi:
            continue
        u0 = max(0.0, (t_lo - a[0]) / (b[0] - a[0]))
        u1 = min(1.0, (t_hi - a[0]) / (b[0] - a[0]))
        p, q = _lerp(a, b, u0), _lerp(a, b, u1)
        if not out or out[-1] != p:
            out.append(p)
        if q != p:
            out.append(q)
    if not out:  # a track with a single row, or one row only touching the window
        out = [r for r in rows if t_lo <= r[0] <= t_hi]
    return out


def _clip_segment(p, q, region) -> tuple[float, float] | None:
    """Liang-Barsky: parameter interval [u0, u1] of the segment p->q inside the region."""
    xmin, ymin, xmax, ymax = region
    dx, dy = q[1] - p[1], q[2] - p[2]
    u0, u1 = 0.0, 1.0
    for den, num in ((-dx, p[1] - xmin), (dx, xmax - p[1]), (-dy, p[2] - ymin), (dy, ymax - p[2])):
        if den == 0:
            if num < 0:
                return None
            continue
        u = num / den
        if den < 0:
            u0 = max(u0, u)
        else:
            u1 = min(u1, u)
    if u0 > u1:
        return None
    return u0, u1


def clip_region(rows, region):
    """Split a track into the runs that lie inside the region (borders interpolated)."""
    xmin, ymin, xmax, ymax = region
    if len(rows) == 1:
        t, x, y = rows[0]
        return [rows] if xmin <= x <= xmax and ymin <= y <= ymax else []
    runs: list[list] = []
    cur: list = []
    for a, b in pairwise(rows):
        span = _clip_segment(a, b, region)
        if span is None:
            if cur:
                runs.append(cur)
                cur = []
            continue
        u0, u1 = span
        p, q = _lerp(a, b, u0), _lerp(a, b, u1)
        if u0 > 0.0 and cur:
            runs.append(cur)
            cur = []
        if not cur or cur[-1] != p:
            cur.append(p)
        if q != p:
            cur.append(q)
        if u1 < 1.0:
            runs.append(cur)
            cur = []
    if cur:
        runs.append(cur)
    # keep the rounded coordinates inside the region too
    return [
        [(t, min(max(x, xmin), xmax), min(max(y, ymin), ymax)) for t, x, y in run] for run in runs
    ]


def round_rows(rows):
    out = []
    for t, x, y in rows:
        r = (round(t, 3), round(x, 3), round(y, 3))
        if out and r[0] <= out[-1][0]:
            continue
        out.append(r)
    return out


def build_movers(peds, spf: float, t_start: float, duration: float, region, max_movers):
    movers: list[Mover] = []
    for pid in sorted(peds):
        rows = [(f * spf - t_start, x, y) for f, x, y in peds[pid]]
        rows = clip_time(rows, 0.0, duration)
        if len(rows) < 2:
            continue
        for k, run in enumerate(clip_region(rows, region), start=1):
            run = round_rows(run)
            if len(run) < 2:
                continue
            name = f"ped-{pid}" if k == 1 else f"ped-{pid}-{k}"
            movers.append(Mover(name, pid, run))
    if max_movers is not None and len(movers) > max_movers:
        keep = sorted(movers, key=lambda m: (-m.duration, m.pid, m.rows[0][0]))[:max_movers]
        keep_ids = {id(m) for m in keep}
        movers = [m for m in movers if id(m) in keep_ids]
    movers.sort(key=lambda m: (m.rows[0][0], m.pid, m.name))
    return movers


def position_at(m: Mover, t: float):
    rows = m.rows
    if not rows[0][0] <= t <= rows[-1][0]:
        return None
    for a, b in pairwise(rows):
        if a[0] <= t <= b[0]:
            u = (t - a[0]) / (b[0] - a[0])
            return a[1] + u * (b[1] - a[1]), a[2] + u * (b[2] - a[2])
    return rows[-1][1], rows[-1][2]


# ---------------------------------------------------------------------------------- writing


def _num(v: float) -> str:
    v = float(v)
    if v == 0:
        v = 0.0  # no "-0.0"
    return repr(v)


def _row(r) -> str:
    return "[" + ", ".join(_num(v) for v in r) + "]"


def _flow_rows(rows, indent: str, width: int = 100) -> str:
    """A YAML flow sequence of rows, wrapped over several lines."""
    parts = [_row(r) for r in rows]
    lines, cur = [], "["
    for i, p in enumerate(parts):
        piece = p + ("," if i < len(parts) - 1 else "]")
        if len(cur) + len(piece) + 1 > width - len(indent) and cur != "[":
            lines.append(cur)
            cur = indent + "  " + piece
        else:
            cur = cur + ("" if cur.endswith("[") else " ") + piece
    lines.append(cur)
    return "\n".join(lines)


def render_scene(args, source: str, spf: float, region, movers: list[Mover]) -> str:
    cmd = " ".join(shlex.quote(a) for a in [os.path.join("tools", "ped_scene.py")] + args.argv)
    out = [
        f"# Generated by tools/ped_scene.py from {os.path.basename(source)}; do not edit by hand.",
        f"#   {cmd}",
        f"# Frame step {round(ANNOTATION_PERIOD / spf)} = {ANNOTATION_PERIOD} s;"
        f" window {args.t_start:g} s .. {args.t_start + args.duration:g} s of the recording"
        f" (t = 0 here is {args.t_start:g} s there).",
        f"# {len(movers)} pedestrians as disc movers of radius {args.ped_radius:g}, clipped to"
        " the window and the region;",
        "# each exists only between its first and last row.",
        "version: 1",
        f"name: {args.name}",
        f"bounds: {_row(region)}",
        "robot:",
        f"  disc: {_num(args.robot_radius)}",
        f"  vmax: {_num(args.vmax)}",
        f"  amax: {_num(args.amax)}",
        "obstacles: []",
    ]
    if movers:
        out.append("movers:")
        for m in movers:
            out.append(f"  - name: {m.name}")
            out.append(f"    disc: {_num(args.ped_radius)}")
            out.append("    trajectory: " + _flow_rows(m.rows, "    "))
    else:
        out.append("movers: []")
    out += [
        "queries:",
        f"  - name: {args.query_name}",
        f"    start: {_row(args.start)}",
        f"    goal: {_row(args.goal)}",
        "    t0: 0.0",
    ]
    if args.expect or args.max_duration is not None:
        out += ["    expect:"]
        if args.expect:
            out += [f"      status: {args.expect}"]
        if args.max_duration is not None:
            out += [f"      max_duration: {args.max_duration:g}"]
    return "\n".join(out) + "\n"


# ---------------------------------------------------------------------------------- main


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one line, exit 2
        sys.stderr.write(f"{self.prog}: {message}\n")
        sys.exit(2)


def parse_args(argv):
    p = _Parser(prog="ped_scene.py", description=__doc__.split("\n\n")[0])
    p.add_argument("datafile")
    p.add_argument("--t-start", type=float, required=True, help="window start, s of the recording")
    p.add_argument("--duration", type=float, required=True, help="window length, s")
    p.add_argument(
        "--region",
        type=float,
        nargs=4,
        metavar=("XMIN", "YMIN", "XMAX", "YMAX"),
        help="scene bounds (default: the pedestrians' extent in the window, +0.5 m)",
    )
    p.add_argument("--max-movers", type=int)
    p.add_argument("--start", type=float, nargs=2, required=True, metavar=("X", "Y"))
    p.add_argument("--goal", type=float, nargs=2, required=True, metavar=("X", "Y"))
    p.add_argument("-o", "--output", required=True)
    p.add_argument("--name", help="scene name (default: the output file's stem)")
    p.add_argument("--query-name", default="cross")
    p.add_argument("--ped-radius", type=float, default=0.25)
    p.add_argument("--robot-radius", type=float, default=0.2)
    p.add_argument("--vmax", type=float, default=1.5)
    p.add_argument("--amax", type=float, default=3.0)
    p.add_argument(
        "--expect",
        choices=["solved", "no_path", "invalid_query"],
        help="add `expect: {status: ...}` to the query",
    )
    p.add_argument("--max-duration", type=float, help="add `max_duration` to the query's expect")
    args = p.parse_args(argv)
    args.argv = list(argv)
    floats = [
        args.t_start,
        args.duration,
        args.ped_radius,
        args.robot_radius,
        args.vmax,
        args.amax,
        *args.start,
        *args.goal,
        *(args.region or []),
    ]
    if not all(math.isfinite(v) for v in floats):
        p.error("every number must be finite")
    for opt in ("duration", "ped_radius", "robot_radius", "vmax", "amax"):
        if getattr(args, opt) <= 0:
            p.error(f"--{opt.replace('_', '-')} must be positive")
    if args.max_movers is not None and args.max_movers < 0:
        p.error("--max-movers must not be negative")
    if args.region and not (args.region[0] < args.region[2] and args.region[1] < args.region[3]):
        p.error("--region must be XMIN YMIN XMAX YMAX with XMIN < XMAX and YMIN < YMAX")
    if args.name is None:
        args.name = os.path.splitext(os.path.basename(args.output))[0]
    if not NAME_RE.match(args.name) or not NAME_RE.match(args.query_name):
        p.error("scene and query names must match [a-zA-Z0-9_.-]+")
    return args


def default_region(peds, spf, t_start, duration):
    xs, ys = [], []
    for rows in peds.values():
        trows = clip_time([(f * spf - t_start, x, y) for f, x, y in rows], 0.0, duration)
        xs += [r[1] for r in trows]
        ys += [r[2] for r in trows]
    if not xs:
        return None
    return [
        math.floor((min(xs) - 0.5) * 10) / 10,
        math.floor((min(ys) - 0.5) * 10) / 10,
        math.ceil((max(xs) + 0.5) * 10) / 10,
        math.ceil((max(ys) + 0.5) * 10) / 10,
    ]


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args = parse_args(argv)
    try:
        peds = read_pedestrians(args.datafile)
        spf = seconds_per_frame(args.datafile, peds)
        region = args.region or default_region(peds, spf, args.t_start, args.duration)
        if region is None:
            raise BadInput(
                f"{args.datafile}: no pedestrian in the window "
                f"{args.t_start:g} s .. {args.t_start + args.duration:g} s"
            )
        region = [float(v) for v in region]
        rr = args.robot_radius
        for label, (x, y) in (("start", args.start), ("goal", args.goal)):
            if not (
                region[0] + rr <= x <= region[2] - rr and region[1] + rr <= y <= region[3] - rr
            ):
                raise BadInput(
                    f"{args.datafile}: --{label} {x:g} {y:g} does not fit in the region "
                    f"{' '.join(f'{v:g}' for v in region)}"
                )
        movers = build_movers(peds, spf, args.t_start, args.duration, region, args.max_movers)
        for label, (x, y) in (("start", args.start), ("goal", args.goal)):
            for m in movers:
                p = position_at(m, 0.0)
                if p and math.hypot(p[0] - x, p[1] - y) < rr + args.ped_radius:
                    sys.stderr.write(f"warning: the {label} overlaps {m.name} at t0 = 0\n")
        text = render_scene(args, args.datafile, spf, region, movers)
        write_atomic(args.output, text)
    except BadInput as exc:
        sys.stderr.write(f"{exc}\n")
        return 2
    except OSError as exc:
        sys.stderr.write(f"{args.output}: cannot write: {exc.strerror or exc}\n")
        return 2
    sys.stderr.write(f"{args.output}: {len(movers)} movers, bounds {region}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
