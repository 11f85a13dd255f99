"""Pedestrian replays: windows of ETH/UCY recordings through ``gfuzzy navigate``, checked.

    python tools/bench_replays.py [FOLDER] [--windows 4] [--duration 35] [--robot disc unicycle box]
                                  [--sensing estimated noisy-half] [--vertices 400] [--seed 1]
                                  [--budget-clock cpu] [--keep DIR]

FOLDER holds recordings in the ETH/UCY text form (``frame id x y [vx vy]``, ``*.txt``), e.g.
the full data sets; default: the repository's excerpts, ``data/pedestrians/``. From each
file, ``--windows`` windows of ``--duration`` seconds are cut, their starts spread evenly over
the recording (``--starts`` gives them instead), each by ``gfuzzy tracks`` with a query that
crosses the people's main flow through the busy part of the window:

* the flow's axis is the principal direction of the people's steps in the window (sign
  ignored: people walking both ways along a street make one axis);
* the crossing runs perpendicular to it, through the median of the positions of the people
  of the window's first ``BUSY_SECONDS`` (where the robot will be then), over the 2nd to the
  98th percentile of the people's spread across the flow (at least ``MIN_CROSSING`` m),
  alternating direction from one window to the next;
* the crossing is shifted along the flow (by up to ``MAX_SHIFT`` m, the smallest shift
  first) until its start is farther than ``START_GAP`` m from every person over the first
  ``START_SECONDS`` (a person on the robot when it wakes up cannot be dodged by anyone);
* the region is the people's extent in the window and the crossing's ends, plus 0.5 m.

Each scene is then driven by ``gfuzzy navigate SCENE -n VERTICES --seed SEED`` (estimated
velocities: what a robot has) once per robot and sensing, and ``gfuzzy check`` verifies the
executed run against the real tracks. A window whose start lies inside a person at t0 is
run too: ``navigate`` must answer ``invalid_query`` there (exit 1, no traceback).

Robots (``ROBOTS``): ``disc`` (radius 0.2, 1.5 m/s: ``gfuzzy tracks``' default, as in the
bundled replays), ``unicycle`` (a differential drive: disc 0.3, 1 m/s, 1 rad/s, as in
``gfuzzy crowd --kinematics unicycle``), ``box`` (a holonomic 0.6 x 0.45 m box, 1 m/s),
``footprint`` (the small house's footprint polygon as a differential drive, 1 m/s, 1.5 rad/s).
Sensing (``SENSING``): ``estimated`` (the default), ``true`` (exact velocities), ``noisy-half``
(``--noise 0.05 --fov 180``), ``noisy-half-occlusion``.

Prints one row per run (outcome, arrival, smallest gap, replan p95 and max on the budget's
clock, the check's verdict and, for a contact, who was hit: their speed, for how long they
had been recorded and how far from the robot they appeared, the navigator's last answer)
and a summary per robot and sensing. Exit status 1 when a run
failed (a collision, a timeout, a check failure, a crash), 0 otherwise.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import shlex
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.scene.trackfiles import read_tracks  # noqa: E402

#: Shortest crossing, metres.
MIN_CROSSING = 6.0
#: The crossing passes through the people of the window's first seconds (where the robot is then).
BUSY_SECONDS = 10.0
#: The start keeps this far (m, centre to centre) from every person over the first
#: START_SECONDS, the crossing shifted along the flow by up to MAX_SHIFT m for it.
START_GAP, START_SECONDS, MAX_SHIFT = 1.5, 1.0, 3.0
#: A person hit less than this long (s) after their first recorded row appeared out of
#: nowhere for the robot (the annotation starts mid-scene): counted apart in the summary.
SUDDEN = 1.0
#: Margin of the region around the people and the crossing, metres.
MARGIN = 0.5

ROBOTS = {
    "disc": None,  # gfuzzy tracks' own robot
    "unicycle": {"disc": 0.3, "vmax": 1.0, "amax": 2.0, "kinematics": "unicycle", "wmax": 1.0},
    "box": {"box": [0.6, 0.45], "vmax": 1.0, "amax": 2.0},
    "footprint": {"footprint": [[0.3, 0.0], [0.22, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.22, -0.2]],
                  "vmax": 1.0, "amax": 2.0, "kinematics": "unicycle", "wmax": 1.5},
}
SENSING = {
    "estimated": [],
    "true": ["--velocity", "true"],
    "noisy-half": ["--noise", "0.05", "--fov", "180"],
    "noisy-half-occlusion": ["--noise", "0.05", "--fov", "180", "--occlusion"],
}


@dataclass(frozen=True)
class Crossing:
    """A window of a recording and the query across its flow."""

    file: Path
    t_start: float
    duration: float
    start: tuple[float, float]
    goal: tuple[float, float]
    region: tuple[float, float, float, float]
    people: int
    shift: float = 0.0

    @property
    def heading(self) -> float:
        """The direction from start to goal (radians)."""
        return math.atan2(self.goal[1] - self.start[1], self.goal[0] - self.start[0])

    @property
    def label(self) -> str:
        return f"{self.file.stem}@{self.t_start:g}"


def _window_rows(tracks, t0: float, t1: float) -> list[np.ndarray]:
    """Each person's rows ``[t, x, y]`` inside the window (those with two rows or more)."""
    out = []
    for tr in tracks.tracks:
        r = tr.rows[(tr.rows[:, 0] >= t0) & (tr.rows[:, 0] <= t1)]
        if len(r) >= 2:
            out.append(r)
    return out


def crossing(tracks, file: Path, t_start: float, duration: float, flip: bool) -> Crossing | None:
    """The query across the main flow of the window (None: fewer than two people walk in it)."""
    rows = _window_rows(tracks, t_start, t_start + duration)
    if len(rows) < 2:
        return None
    steps = np.concatenate([np.diff(r[:, 1:], axis=0) for r in rows])
    pos = np.concatenate([r[:, 1:] for r in rows])
    _, vecs = np.linalg.eigh(steps.T @ steps)
    flow = vecs[:, -1]
    across = np.array([-flow[1], flow[0]])
    if across[np.argmax(np.abs(across))] < 0:  # a fixed sign, so that flip alone decides the direction
        across = -across
    # the busy part where the robot will be: the people of the crossing's first seconds
    soon = np.concatenate([r[r[:, 0] <= t_start + BUSY_SECONDS, 1:] for r in rows])
    centre = np.median(soon if len(soon) else pos, axis=0)
    s = (pos - centre) @ across
    lo, hi = np.percentile(s, [2, 98])
    half = max((hi - lo) / 2, MIN_CROSSING / 2)
    mid = centre + across * (lo + hi) / 2
    a, b = mid - across * half, mid + across * half
    if flip:
        a, b = b, a
    shift = _clear_shift(rows, t_start, a, flow)
    a, b = a + shift * flow, b + shift * flow
    pts = np.vstack([pos, a, b])
    region = (
        math.floor((pts[:, 0].min() - MARGIN) * 10) / 10,
        math.floor((pts[:, 1].min() - MARGIN) * 10) / 10,
        math.ceil((pts[:, 0].max() + MARGIN) * 10) / 10,
        math.ceil((pts[:, 1].max() + MARGIN) * 10) / 10,
    )
    r2 = lambda p: (round(float(p[0]), 2), round(float(p[1]), 2))  # noqa: E731
    return Crossing(file, float(t_start), float(duration), r2(a), r2(b), region, len(rows), shift)


def _clear_shift(rows: list[np.ndarray], t_start: float, start: np.ndarray, flow: np.ndarray) -> float:
    """The smallest shift along the flow (0, +-0.5, +-1, ... +-``MAX_SHIFT`` m) that puts the
    start farther than ``START_GAP`` m (centre to centre) from every person over the first
    ``START_SECONDS`` (nobody can dodge someone who is on the robot when it wakes up);
    0 when none does (the table then shows what happened)."""
    times = t_start + np.linspace(0.0, START_SECONDS, 11)
    near = []
    for r in rows:
        inside = (times >= r[0, 0]) & (times <= r[-1, 0])
        if inside.any():
            near.append(np.column_stack([np.interp(times[inside], r[:, 0], r[:, k]) for k in (1, 2)]))
    if not near:
        return 0.0
    people = np.concatenate(near)
    for k in range(int(2 * MAX_SHIFT) + 1):
        shift = 0.5 * ((k + 1) // 2) * (1 if k % 2 else -1) if k else 0.0
        if np.hypot(*(people - (start + shift * flow)).T).min() > START_GAP:
            return shift
    return 0.0


def window_starts(tracks, windows: int, duration: float) -> list[float]:
    """``windows`` starts spread evenly over the recording (whole seconds)."""
    first, last = tracks.time_range
    span = max(last - first - duration, 0.0)
    return [float(round(first + span * (k + 0.5) / windows)) for k in range(windows)]


def _py(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "gfuzzy", *args], capture_output=True, text=True, cwd=cwd)


def _robot_scene(robot: dict, region, folder: Path) -> Path:
    """A scene holding only ``robot`` (for ``gfuzzy tracks --static``)."""
    path = folder / "robot.yaml"
    doc = {"version": 1, "name": "robot", "bounds": list(region), "robot": robot, "obstacles": []}
    path.write_text(json.dumps(doc))  # JSON is YAML
    return path


def make_scene(c: Crossing, robot: str, folder: Path) -> tuple[Path, str]:
    """Cut the window with ``gfuzzy tracks``; the scene's path and an error ('' when made)."""
    out = folder / f"{c.file.stem}-{c.t_start:g}-{robot}.yaml"
    args = [str(c.file), "--t-start", f"{c.t_start:g}", "--duration", f"{c.duration:g}",
            "--region", *(f"{v:g}" for v in c.region), "--name", out.stem, "-o", str(out)]  # fmt: skip
    start, goal = [f"{v:g}" for v in c.start], [f"{v:g}" for v in c.goal]
    if ROBOTS[robot] is not None:
        args += ["--static", str(_robot_scene(ROBOTS[robot], c.region, folder))]
        start.append(f"{c.heading:.4f}")
        goal.append(f"{c.heading:.4f}")
    made = _py("tracks", *args, "--start", *start, "--goal", *goal, cwd=ROOT)
    return out, (made.stderr.strip() if made.returncode else "")


@dataclass
class Run:
    """One navigate run and its check."""

    window: str
    robot: str
    sensing: str
    outcome: str
    arrival: float | None = None
    gap: float | None = None
    p95_ms: float | None = None
    max_ms: float | None = None
    check: str = ""
    modes: str = ""
    error: str = ""
    hit: str = ""
    recorded_for: float | None = None

    @property
    def failed(self) -> bool:
        return self.outcome not in ("solved", "invalid_query") or self.check not in ("valid", "-") or bool(self.error)


def drive(scene: Path, c: Crossing, robot: str, sensing: str, args, folder: Path) -> Run:
    """``gfuzzy navigate`` then ``gfuzzy check`` of one scene."""
    out = folder / f"{scene.stem}-{sensing}.json"
    nav = _py("navigate", str(scene), "-n", str(args.vertices), "--seed", str(args.seed),
              "--budget-clock", args.budget_clock, "--log-every", "1", *SENSING[sensing], "-o", str(out),
              cwd=ROOT)  # fmt: skip
    run = Run(c.label, robot, sensing, "crash")
    if nav.returncode not in (0, 1) or "Traceback" in nav.stderr or not out.exists():
        run.error = (nav.stderr.strip().splitlines() or ["no output"])[-1]
        return run
    doc = json.loads(out.read_text())
    run.outcome = doc["status"]
    if run.outcome == "invalid_query":
        run.check = "-"
        run.error = "" if nav.returncode == 1 else f"exit {nav.returncode}"
        return run
    run.arrival = doc.get("duration")
    run.gap = doc.get("min_separation")
    run.p95_ms = 1000 * doc["replan_seconds_p95"]
    run.max_ms = 1000 * doc["replan_seconds_max"]
    run.modes = " ".join(f"{k}:{v}" for k, v in sorted(doc.get("modes", {}).items()))
    chk = _py("check", str(scene), str(out), cwd=ROOT)
    if "Traceback" in chk.stderr:
        run.error = chk.stderr.strip().splitlines()[-1]
    text = chk.stdout.strip() or chk.stderr.strip()
    run.check = "valid" if chk.returncode == 0 else text.split(": ", 1)[-1]
    if run.outcome != "solved":
        run.check = "valid" if doc["check"]["valid"] else doc["check"]["reason"]
    if run.check != "valid":
        run.hit, run.recorded_for = explain(scene, doc, run.check)
    return run


_HIT = re.compile(r"collides with mover '([^']+)' (?:at|between) t=([-+0-9.e]+)")


def explain(scene_path: Path, doc: dict, reason: str) -> tuple[str, float | None]:
    """Who was hit and how: when the person appeared (their first recorded row) and how
    far from the robot, their speed at the contact, and the navigator's last answer before
    it (``navigate --log-every 1`` logs every replan); and for how long (s) the person had
    been recorded at the contact (None: not a contact)."""
    m = _HIT.search(reason)
    if not m:
        return "", None
    scene = load_scene(scene_path)
    mv = next(x for x in scene.movers if x.name == m.group(1))
    t = float(m.group(2))
    tr = mv.trajectory
    rows = np.array(doc.get("waypoints") or doc["executed"])
    first = float(tr[0, 0])
    robot = np.array([np.interp(first, rows[:, 0], rows[:, k]) for k in (1, 2)])
    away = float(np.hypot(*(tr[0, 1:] - robot))) - mv.radius - scene.robot.circumradius
    k = int(np.clip(np.searchsorted(tr[:, 0], t) - 1, 0, len(tr) - 2))
    speed = float(np.hypot(*(tr[k + 1, 1:] - tr[k, 1:])) / (tr[k + 1, 0] - tr[k, 0]))
    modes = [e["mode"] for e in doc.get("replan_log", []) if e["t"] <= t]
    text = (f"{mv.name}, {speed:.1f} m/s, recorded from {t - first:.1f} s before, {away:.2f} m away then; "
            f"answer: {modes[-1] if modes else '-'}")
    return text, t - first


def _fmt(v, spec: str) -> str:
    return "-" if v is None else format(v, spec)


def table(runs: list[Run]) -> str:
    lines = ["| window | robot | sensing | outcome | arrival (s) | min gap (m) | replan p95 / max (ms) | check | answers |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    for r in runs:
        check = r.check if not r.error else f"{r.check} ({r.error})"
        check = check.split(" (penetration")[0] + (f": {r.hit}" if r.hit else "")
        lines.append(f"| {r.window} | {r.robot} | {r.sensing} | {r.outcome} | {_fmt(r.arrival, '.2f')} | "
                     f"{_fmt(r.gap, '.3f')} | {_fmt(r.p95_ms, '.0f')} / {_fmt(r.max_ms, '.0f')} | {check} | {r.modes} |")
    return "\n".join(lines)


def summary(runs: list[Run], budget_ms: float = 100.0) -> str:
    lines = ["| robot | sensing | runs | arrived, valid | invalid start | failed (hit by someone recorded < 1 s) | "
             "arrival median (s) | replan p95 max (ms) |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    keys = sorted({(r.robot, r.sensing) for r in runs}, key=lambda k: (list(ROBOTS).index(k[0]), list(SENSING).index(k[1])))
    for robot, sensing in keys:
        rs = [r for r in runs if (r.robot, r.sensing) == (robot, sensing)]
        ok = [r for r in rs if not r.failed and r.outcome == "solved"]
        bad = [r for r in rs if r.failed]
        inv = [r for r in rs if r.outcome == "invalid_query" and not r.failed]
        arr = [r.arrival for r in ok]
        p95 = [r.p95_ms for r in rs if r.p95_ms is not None]
        over = sum(p > budget_ms for p in p95)
        sudden = sum(r.recorded_for is not None and r.recorded_for < SUDDEN for r in bad)
        lines.append(f"| {robot} | {sensing} | {len(rs)} | {len(ok)} | {len(inv)} | {len(bad)} ({sudden}) | "
                     f"{_fmt(float(np.median(arr)) if arr else None, '.2f')} | "
                     f"{_fmt(max(p95) if p95 else None, '.0f')}{f' ({over} over budget)' if over else ''} |")
    return "\n".join(lines)


def recordings(folder: Path, only: list[str] | None) -> list[Path]:
    """The recordings (``*.txt``) of ``folder``, those named in ``only`` when given."""
    return sorted(p for p in folder.glob("*.txt") if only is None or p.stem in only)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder", nargs="?", default=str(ROOT / "data" / "pedestrians"),
                    help="ETH/UCY text recordings (default: the repository's excerpts, data/pedestrians)")
    ap.add_argument("--files", nargs="+", metavar="STEM", help="only these recordings (file names without .txt)")
    ap.add_argument("--windows", type=int, default=4, help="windows per recording (default 4)")
    ap.add_argument("--starts", type=float, nargs="+", metavar="T", help="window starts (s of the recording) instead")
    ap.add_argument("--duration", type=float, default=35.0, help="window length, s (default 35)")
    ap.add_argument("--robot", nargs="+", choices=list(ROBOTS), default=["disc"])
    ap.add_argument("--sensing", nargs="+", choices=list(SENSING), default=["estimated"])
    ap.add_argument("--vertices", type=int, default=400)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--budget-clock", choices=("wall", "cpu"), default="cpu",
                    help="navigate's --budget-clock (default cpu: figures independent of the load)")
    ap.add_argument("--keep", metavar="DIR", help="keep the scenes and runs here (default: a temporary folder)")
    args = ap.parse_args(argv)
    folder = Path(args.folder)
    files = recordings(folder, args.files) if folder.is_dir() else []
    if not files:
        print(f"bench_replays: {folder}: no recordings (*.txt){' named ' + ' '.join(args.files) if args.files else ''} "
              "here (the full ETH/UCY files are not in the repository: give their folder)", file=sys.stderr)
        return 2
    runs: list[Run] = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(args.keep or tmp).resolve()
        work.mkdir(parents=True, exist_ok=True)
        for file in files:
            tracks = read_tracks(file)
            starts = args.starts or window_starts(tracks, args.windows, args.duration)
            for k, t in enumerate(starts):
                c = crossing(tracks, file.resolve(), t, args.duration, flip=bool(k % 2))
                if c is None:
                    print(f"{file.stem}@{t:g}: fewer than two people walk in the window; skipped", flush=True)
                    continue
                print(f"{c.label}: {c.people} people, {' '.join(map(str, c.start))} -> {' '.join(map(str, c.goal))}"
                      f"{f' (shifted {c.shift:+g} m along the flow)' if c.shift else ''}", flush=True)  # fmt: skip
                for robot in args.robot:
                    scene, err = make_scene(c, robot, work)
                    if err:
                        runs.append(Run(c.label, robot, "-", "no scene", error=err))
                        print(f"  {robot}: gfuzzy tracks failed: {err}", flush=True)
                        continue
                    for sensing in args.sensing:
                        run = drive(scene, c, robot, sensing, args, work)
                        runs.append(run)
                        print(f"  {robot} {sensing}: {run.outcome} {_fmt(run.arrival, '.2f')} s, gap "
                              f"{_fmt(run.gap, '.3f')}, p95 {_fmt(run.p95_ms, '.0f')} / max {_fmt(run.max_ms, '.0f')} ms, "
                              f"{run.check} {run.error} {run.hit}", flush=True)
                        if args.keep:
                            print(f"    $ gfuzzy navigate {shlex.quote(str(scene))} -n {args.vertices} --seed {args.seed} "
                                  f"{' '.join(SENSING[sensing])}", flush=True)
    print()
    print(table(runs))
    print()
    print(summary(runs))
    return 1 if any(r.failed for r in runs) else 0


if __name__ == "__main__":
    raise SystemExit(main())
