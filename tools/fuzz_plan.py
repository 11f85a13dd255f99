"""Random scenes: every answer the planner calls solved is checked independently.

    python tools/fuzz_plan.py                                  # 20 scenes, seed 1, 3 queries each
    python tools/fuzz_plan.py --scenes 100 --seed 7 -o fuzz.csv --dump out/fuzz
    python tools/fuzz_plan.py --seed 7 --only 23 --dump out/   # one scene again

A soundness and robustness net, not a benchmark of success: where ``tools/bench_unseen.py``
draws rooms with a known answer (a witness), this draws clutter nobody designed, as a new
user's first scenes look. Scene ``i`` is drawn from ``numpy.random.default_rng([seed, i])``:

* bounds 6-12 x 5-9 m; 2-8 obstacles: rotated boxes, discs and L-shaped polygons;
* 0-25 movers: discs or boxes, on ``path`` s (``loop``, ``bounce``, ``once``, speeds
  0-1.5 m/s, offsets) or ``trajectory`` rows, crossing walls as they please;
* a robot drawn from five shapes (a disc, a box, an off-centre rectangle, a U and a
  concave star), holonomic or a differential drive (sometimes with ``reverse``), random
  ``vmax``, sometimes a ``clearance`` and a ``mover_clearance``;
* three queries with random start, goal, ``t0`` and ``hold``: poses drawn until clear of
  the static obstacles (up to 40 draws), so the invalid ones are mostly a mover on the
  start at ``t0`` or a robot too large for its clutter; the planner must say so, not fail.

Each scene's roadmap is built (``-n``, seed 1), each query planned with the GA and the speed
layer off and on (``--refine``), within ``--time-limit`` seconds. Outcomes: ``solved``
(checked valid by :func:`gfuzzy.check_trajectory`), ``check_reject`` (solved, but the
check refuses it: a soundness bug), ``no_path``, ``invalid_query``, ``timeout``, ``error``
(an exception: a robustness bug). A ``no_path`` is not judged (there is no witness here).
Times are CPU seconds of this process. ``--dump DIR`` writes the scene of every
``check_reject`` and ``error``, and of every plan slower than the time limit, with the
commands that reproduce it. Exit status 1 when any answer was rejected or raised.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import os
import sys
import time
import traceback
from collections import Counter
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.atomic import write_atomic  # noqa: E402
from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.collision.geometry import StaticGeometry  # noqa: E402
from gfuzzy.planner.planner import PlanOptions, plan  # noqa: E402
from gfuzzy.planner.queries import query_problem  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402

#: Draws of a query's start or goal until one is clear of the static obstacles.
POSE_DRAWS = 40
OUTCOMES = ("solved", "check_reject", "no_path", "invalid_query", "timeout", "error")
#: The robots' shapes: the scene's ``robot`` entry without speed or kinematics.
ROBOTS = {
    "disc": {"disc": 0.2},
    "box": {"box": [0.6, 0.35]},
    "offset": {"footprint": [[0.3, 0.2], [-0.2, 0.2], [-0.2, -0.2], [0.3, -0.2]]},
    "u": {"footprint": [[0.4, -0.45], [0.4, -0.25], [-0.1, -0.25], [-0.1, 0.25], [0.4, 0.25], [0.4, 0.45],
                        [-0.4, 0.45], [-0.4, -0.45]]},
    "star": {"footprint": [[0.5, 0.0], [0.1, 0.1], [0.0, 0.5], [-0.1, 0.1], [-0.5, 0.0], [-0.1, -0.1],
                           [0.0, -0.5], [0.1, -0.1]]},
}


def _r(x: float) -> float:
    return round(float(x), 3)


def make_scene(seed: int, index: int) -> dict:
    """Scene ``index`` of the run ``seed`` as a YAML document (a dict)."""
    rng = np.random.default_rng([seed, index])
    u = lambda lo, hi: _r(rng.uniform(lo, hi))  # noqa: E731
    W, H = u(6, 12), u(5, 9)
    obstacles = []
    for _ in range(int(rng.integers(2, 9))):
        c = [u(1, W - 1), u(1, H - 1)]
        r = rng.random()
        if r < 0.4:
            obstacles.append({"box": {"center": c, "size": [u(0.2, 2), u(0.2, 2)], "angle": u(-3, 3)}})
        elif r < 0.7:
            obstacles.append({"disc": {"center": c, "radius": u(0.1, 0.6)}})
        else:  # an L of arm length L and thickness 0.3
            L = u(0.5, 1.5)
            x, y = c
            obstacles.append({"polygon": [[x, y], [_r(x + L), y], [_r(x + L), _r(y + 0.3)], [_r(x + 0.3), _r(y + 0.3)],
                                          [_r(x + 0.3), _r(y + L)], [x, _r(y + L)]]})
    point = lambda: [u(0, W), u(0, H)]  # noqa: E731
    movers = []
    for i in range(int(rng.integers(0, 26))):
        m = {"name": f"m{i}"}
        if rng.random() < 0.7:
            m["disc"] = u(0.1, 0.35)
        else:
            m["box"] = [u(0.2, 0.6), u(0.2, 0.6)]
        if rng.random() < 0.7:
            m.update(speed=u(0, 1.5), path=[point() for _ in range(int(rng.integers(2, 5)))],
                     mode=str(rng.choice(["loop", "bounce", "once"])), offset=u(0, 3))
        else:
            t, rows = u(0, 10), []
            for _ in range(int(rng.integers(1, 7))):
                rows.append([t, *point()])
                t = _r(t + rng.uniform(0.3, 4))
            m["trajectory"] = rows
        movers.append(m)
    shape = str(rng.choice(list(ROBOTS)))
    robot = {**ROBOTS[shape], "vmax": u(0.5, 1.5)}
    unicycle = rng.random() < 0.5
    if unicycle:
        robot["kinematics"] = "unicycle"
        if rng.random() < 0.3:
            robot["reverse"] = True
    if rng.random() < 0.3:
        robot["clearance"] = u(0, 0.1)
    if rng.random() < 0.3:
        robot["mover_clearance"] = u(0, 0.2)
    doc = {"version": 1, "name": f"fuzz-{seed}-{index}", "bounds": [0, 0, W, H], "robot": robot,
           "obstacles": obstacles, "movers": movers}
    posed = unicycle or shape != "disc"
    geometry = StaticGeometry(parse_scene({**doc, "movers": []}, doc["name"]))

    def pose() -> list:
        """A pose clear of the static obstacles (the last of POSE_DRAWS draws when none is)."""
        for _ in range(POSE_DRAWS):
            p = [u(0.5, W - 0.5), u(0.5, H - 0.5)] + ([u(-3.1, 3.1)] if posed else [])
            if query_problem(geometry, p, p) == "":
                break
        return p

    doc["queries"] = [{"name": f"q{j}", "start": pose(), "goal": pose(), "t0": u(0, 5),
                       "hold": float(rng.choice([0, 0, 1.5]))} for j in range(3)]
    return doc


def run_scene(doc: dict, vertices: int, time_limit: float, refine: tuple) -> list[dict]:
    """Build the roadmap, plan every query (with each ``refine`` setting), check; CSV rows."""
    head = {"scene": doc["name"], "robot": next(k for k in ("disc", "box", "footprint") if k in doc["robot"]),
            "kinematics": doc["robot"].get("kinematics", "holonomic"), "movers": len(doc["movers"])}
    try:
        scene = parse_scene(doc, doc["name"])
        t = time.process_time()
        rm = build_roadmap(scene, RoadmapOptions(vertices=vertices, seed=1))
        build = round(time.process_time() - t, 3)
    except Exception as exc:  # noqa: BLE001 - a fuzz run counts tracebacks, it does not stop at one
        return [{**head, "query": "", "refine": "", "outcome": "error", "message": f"{type(exc).__name__}: {exc}",
                 "traceback": traceback.format_exc()}]
    rows = []
    for q in scene.queries:
        for ref in refine:
            row = {**head, "query": q.name, "refine": ref, "build_s": build, "plan_s": "", "outcome": "", "message": ""}
            try:
                t = time.process_time()
                res = plan(scene, rm, q.start, q.goal, t0=q.t0, hold=q.hold,
                           options=PlanOptions(refine=ref, speed_layer=ref, time_limit=time_limit))
                row["plan_s"] = round(time.process_time() - t, 3)
                status = res.status.value
                if status == "solved":
                    rep = check_trajectory(scene, res.trajectory.waypoints, query=q)
                    row["outcome"], row["message"] = ("solved", "") if rep.valid else ("check_reject", rep.reason)
                else:
                    row["outcome"], row["message"] = status, res.message
            except Exception as exc:  # noqa: BLE001
                row["outcome"], row["message"] = "error", f"{type(exc).__name__}: {exc}"
                row["traceback"] = traceback.format_exc()
            rows.append(row)
    return rows


def dump(folder: Path, doc: dict, rows: list[dict], vertices: int) -> None:
    """The scene and the commands that reproduce its failing queries."""
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{doc['name']}.yaml"
    lines = [f"# tools/fuzz_plan.py {doc['name']}: " + "; ".join(f"{r['query']} refine={r['refine']}: {r['outcome']}"
                                                               f" {r['plan_s']} s {r['message'][:80]}" for r in rows),
             f"# python -m gfuzzy roadmap {path} -n {vertices} --seed 1 -o {folder / doc['name']}.rm.json"]
    for r in rows:
        if r["query"]:
            lines.append(f"# python -m gfuzzy plan {path} --roadmap {folder / doc['name']}.rm.json --query {r['query']}"
                         f"{' --refine --speed-layer' if r['refine'] else ''} -o {folder / doc['name']}.{r['query']}.json")
    write_atomic(path, "\n".join(lines) + "\n" + yaml.safe_dump(doc, sort_keys=False, default_flow_style=None, width=200))


def summary(rows: list[dict], time_limit: float) -> str:
    """One markdown row per kinematics and robot, and one for all."""
    head = ["group", "plans", *OUTCOMES, "over the time limit", "slowest plan s"]
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    groups = sorted({(r["kinematics"], r["robot"]) for r in rows})
    for g in [*groups, "all"]:
        sel = rows if g == "all" else [r for r in rows if (r["kinematics"], r["robot"]) == g]
        counts = Counter(r["outcome"] for r in sel)
        times = [r["plan_s"] for r in sel if r.get("plan_s") not in ("", None)]
        cells = ["all" if g == "all" else " ".join(g), len(sel), *(counts[o] for o in OUTCOMES),
                 sum(t > time_limit for t in times), f"{max(times):.2f}" if times else "-"]
        lines.append("| " + " | ".join(str(c) for c in cells) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("-n", "--vertices", type=int, default=150)
    ap.add_argument("--time-limit", type=float, default=20.0, help="PlanOptions.time_limit of every plan (s)")
    ap.add_argument("--refine", choices=("off", "on", "both"), default="both",
                    help="the GA and the speed layer: off, on, or each plan twice (default)")
    ap.add_argument("--only", type=int, nargs="+", help="run only these scene indices")
    ap.add_argument("-o", "--output", help="CSV, one row per plan (written atomically)")
    ap.add_argument("--dump", help="folder for the scenes with a rejected, raising or slow plan")
    a = ap.parse_args(argv)
    if a.scenes < 1 or a.vertices < 2 or not a.time_limit > 0:
        print("fuzz_plan: --scenes must be >= 1, -n >= 2 and --time-limit > 0", file=sys.stderr)
        return 2
    refine = {"off": (False,), "on": (True,), "both": (False, True)}[a.refine]
    indices = a.only if a.only else range(a.scenes)
    rows, t0 = [], time.perf_counter()
    for k, i in enumerate(indices, 1):
        doc = make_scene(a.seed, i)
        got = run_scene(doc, a.vertices, a.time_limit, refine)
        rows.extend(got)
        tally = Counter(r["outcome"] for r in got)
        print(f"[{k}/{len(indices)}] {doc['name']} {got[0]['robot']} {got[0]['kinematics']} {got[0]['movers']} movers: "
              + ", ".join(f"{n} {o}" for o, n in sorted(tally.items())), file=sys.stderr, flush=True)
        for r in got:
            if r["outcome"] in ("check_reject", "error"):
                print(f"  {r['query']} refine={r['refine']}: {r['outcome']}: {r['message'][:200]}", file=sys.stderr)
                if "traceback" in r:
                    print(r["traceback"], file=sys.stderr)
        bad = [r for r in got if r["outcome"] in ("check_reject", "error")
               or (r.get("plan_s") not in ("", None) and r["plan_s"] > a.time_limit)]
        if a.dump and bad:
            dump(Path(a.dump), doc, bad, a.vertices)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else math.nan
    which = f"--only {' '.join(map(str, a.only))}" if a.only else f"--scenes {a.scenes}"
    print(f"# tools/fuzz_plan.py {which} --seed {a.seed} -n {a.vertices} --time-limit {a.time_limit} --refine {a.refine}: "
          f"{len(rows)} plans in {time.perf_counter() - t0:.0f} s, load average {load:.2f}; times: CPU seconds")
    print(summary(rows, a.time_limit))
    if a.output:
        fields = ["scene", "robot", "kinematics", "movers", "query", "refine", "outcome", "plan_s", "build_s", "message"]
        buf = io.StringIO()
        w = csv.DictWriter(buf, fieldnames=fields, extrasaction="ignore", lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
        write_atomic(a.output, buf.getvalue())
    return 1 if any(r["outcome"] in ("check_reject", "error") for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
