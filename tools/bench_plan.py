"""Query benchmark: the paper's Table 1 on building-floor, and a large crowd scene.

    python tools/bench_plan.py                 # Table 1 + baseline + large scene
    python tools/bench_plan.py --skip-large    # Table 1 only

Table 1 (after van den Berg & Overmars): roadmaps grown from 100 to 1000 vertices, each
extending the previous by 100; per roadmap the edges, the roadmap distance, the duration
and delay factor of the answer, and the query time (median of --repeat runs of
``gfuzzy.plan``, collision model and graph included; "kept": a ``Planner`` kept across
queries), beside the paper's figures where its text gives them.

Baseline, measured in the same run: a plain time-expanded breadth-first search over every
(point, step) of the same graph, with the same safety test but no safe intervals, no
heuristic and no time windows. The ratio says what the safe-interval A* search buys.

Large scene: a 40 m x 30 m hall with 24 pillars and 200 movers (people and carts on
loops, back-and-forth paths and one-way runs), a 10,000-vertex roadmap; the query runs in
a child process so that its peak memory (ru_maxrss) is its own.

Backends (issue 11): every figure is the compiled search (``PlanOptions.backend``, the
default); "ref ms" is the pure-Python reference on the same kept Planner in the same run,
and "x" the speed-up. The large scene runs both backends in their own child processes.

Cold process: the wall time of ``python -m gfuzzy plan scenes/building-floor.yaml`` (import,
load, plan, write), median of 3.

Peer (``--peer``): the OMPL space-time planner of tools/experiments/ompl_peer.py (RRTConnect
in SpaceTimeStateSpace) on every bundled query: our planning time against its time to a first
answer, and our arrival against its first and its best arrival in its budget.

Targets (issue 11, on the project's 2-core machine): building floor 200 vertices <= 10 ms
median, 1000 vertices <= 50 ms; 10,000 vertices with 200 movers <= 1 s and <= 1 GB; a cold
``gfuzzy plan`` process <= 2 s; >= 5x over the reference on building floor; against the peer
a planning-time ratio <= 0.1 at the median and < 1 on every query, arrival <= 1/3 of its.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections import deque
from pathlib import Path

import numpy as np
import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.planner.planner import Planner, PlanOptions, plan  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, grow_roadmaps, load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from gfuzzy.timespace.timespace import MoverField  # noqa: E402

PAPER = {100: "0.33 s", 198: "0.46 s, 35.14 / 15.82 = 2.22", 200: "(198: 0.46 s, df 2.22)", 1000: "3.90 s"}


def time_query(scene, rm, q, repeat):
    """Median seconds of `plan()` (collision model built each call), of a kept Planner, and
    of the kept Planner on the reference backend; and whether both backends agree."""
    times, kept, ref = [], [], []
    res = res_ref = None
    planner = Planner(scene, rm)
    reference = PlanOptions(backend="reference")
    for _ in range(repeat):
        t = time.perf_counter()
        res = plan(scene, rm, q.start, q.goal, q.t0)
        times.append(time.perf_counter() - t)
        t = time.perf_counter()
        planner.plan(q.start, q.goal, q.t0)
        kept.append(time.perf_counter() - t)
        t = time.perf_counter()
        res_ref = planner.plan(q.start, q.goal, q.t0, reference)
        ref.append(time.perf_counter() - t)
    same = (res.status, res.duration) == (res_ref.status, res_ref.duration)
    return res, statistics.median(times), statistics.median(kept), statistics.median(ref), same


def baseline_seconds(scene, rm, q, dt, horizon_steps):
    """Plain time-expanded BFS (no intervals, no heuristic, no windows)."""
    t = time.perf_counter()
    planner = Planner(scene, rm)
    start, goal = np.asarray(q.start, float), np.asarray(q.goal, float)
    qg = planner.prepare(goal, PlanOptions(dt=dt, stretch=1.0)).splice(planner, start)  # the whole roadmap
    graph, s_id, g_id = qg.graph, qg.s_id, qg.g_id
    field = MoverField(scene, q.t0, dt, horizon_steps, scene.robot.vmax)
    unsafe = field.unsafe(graph.poses)
    seen = np.zeros_like(unsafe)
    seen[s_id, 0] = True
    frontier = deque([(s_id, 0)])
    found = None
    while frontier:
        u, n = frontier.popleft()
        if u == g_id:
            found = n
            break
        if n == horizon_steps:
            continue
        for v in list(graph.neighbors[graph.indptr[u] : graph.indptr[u + 1]]) + [u]:
            if not unsafe[v, n + 1] and not seen[v, n + 1]:
                seen[v, n + 1] = True
                frontier.append((v, n + 1))
    return time.perf_counter() - t, found


def table1(repeat: int, seed: int) -> None:
    scene = load_scene(ROOT / "scenes" / "building-floor.yaml")
    q = scene.queries[0]
    sizes = list(range(100, 1001, 100))
    t = time.perf_counter()
    roadmaps = grow_roadmaps(scene, sizes, RoadmapOptions(seed=seed))
    print(f"building-floor, seed {seed}: grew {sizes[-1]} vertices in {time.perf_counter() - t:.2f} s")
    print(
        f"{'vertices':>8} {'edges':>6} {'road dist':>9} {'duration':>8} {'delay':>6} {'query ms':>9} "
        f"{'kept ms':>8} {'ref ms':>7} {'x':>5} {'same':>4} {'expansions':>10}  paper"
    )
    results = {}
    speedups = []
    for rm in roadmaps:
        res, sec, kept, ref, same = time_query(scene, rm, q, repeat)
        n = len(rm.vertices)
        results[n] = (rm, res, sec)
        speedups.append(ref / kept)
        dur = f"{res.duration:8.2f}" if res.solved else f"{res.status.value:>8}"
        df = f"{res.delay_factor:6.3f}" if res.solved else "     -"
        print(
            f"{n:>8} {len(rm.edges):>6} {res.roadmap_distance:>9.2f} {dur} {df} {sec * 1000:>9.1f} "
            f"{kept * 1000:>8.1f} {ref * 1000:>7.1f} {ref / kept:>5.1f} {'yes' if same else 'NO':>4} "
            f"{res.stats.expansions or 0:>10}  {PAPER.get(n, '')}"
        )
    print(f"speed-up over the reference (kept Planner): median {statistics.median(speedups):.1f}x, "
          f"min {min(speedups):.1f}x, max {max(speedups):.1f}x")  # fmt: skip
    rm, res, sec = results[200]
    if res.solved:
        steps = int(math.ceil(res.duration / 0.07)) + 20
        base, found = baseline_seconds(scene, rm, q, 0.07, steps)
        print(
            f"\nbaseline (200 vertices, time-expanded BFS to {steps} steps): {base * 1000:.0f} ms, "
            f"arrives at step {found}; safe-interval A*: {sec * 1000:.1f} ms; ratio {base / sec:.1f}x"
        )


def hall_scene(path: Path, movers: int = 200, seed: int = 7) -> Path:
    rng = np.random.default_rng(seed)
    W, H = 40.0, 30.0
    obstacles = []
    for i in range(6):
        for j in range(4):
            cx, cy = 4 + i * 6.4, 4 + j * 7.3
            obstacles.append({"box": {"center": [cx, cy], "size": [1.2, 2.0], "angle": float(rng.uniform(0, 1))}})
    mv = []
    for k in range(movers):
        pts = rng.uniform([1.5, 1.5], [W - 1.5, H - 1.5], size=(int(rng.integers(2, 5)), 2)).round(3).tolist()
        mode = ["loop", "bounce", "once"][k % 3]
        if k % 10 == 9:
            mv.append({"name": f"cart-{k}", "box": [0.8, 0.6], "speed": 0.8, "path": pts, "mode": mode})
        else:
            mv.append(
                {"name": f"person-{k}", "disc": round(float(rng.uniform(0.2, 0.3)), 3),
                 "speed": round(float(rng.uniform(0.5, 1.4)), 3), "path": pts, "mode": mode,
                 "offset": round(float(rng.uniform(0, 5)), 3)}
            )  # fmt: skip
    doc = {
        "version": 1,
        "name": "hall-200",
        "bounds": [0.0, 0.0, W, H],
        "robot": {"disc": 0.3, "vmax": 1.5},
        "obstacles": obstacles,
        "movers": mv,
        "queries": [{"name": "corner", "start": [1.0, 1.0], "goal": [39.0, 29.0]}],
    }
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def large(vertices: int, seed: int) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        scene_path = hall_scene(Path(tmp) / "hall.yaml")
        scene = load_scene(scene_path)
        t = time.perf_counter()
        rm = build_roadmap(scene, RoadmapOptions(vertices=vertices, seed=seed))
        print(
            f"\nhall-200: {len(scene.movers)} movers, roadmap {len(rm.vertices)} vertices / "
            f"{len(rm.edges)} edges built in {time.perf_counter() - t:.1f} s"
        )
        rm_path = Path(tmp) / "hall.json"
        rm.save(rm_path)
        docs = {}
        for backend in ("reference", "compiled"):
            out = subprocess.run(
                [sys.executable, __file__, "--child", str(scene_path), str(rm_path), backend],
                capture_output=True,
                text=True,
                check=True,
            )
            docs[backend] = json.loads(out.stdout.strip().splitlines()[-1])
        ref, doc = docs["reference"], docs["compiled"]
        print(
            f"reference backend: {ref['status']}, duration {ref['duration']}, {ref['seconds'] * 1000:.0f} ms, "
            f"peak {ref['peak_mb']:.0f} MB; compiled: {doc['seconds'] * 1000:.0f} ms, speed-up "
            f"{ref['seconds'] / doc['seconds']:.1f}x, same answer: "
            f"{'yes' if (ref['status'], ref['duration']) == (doc['status'], doc['duration']) else 'NO'}"
        )
        print(
            f"query: {doc['status']}, duration {doc['duration']}, delay factor {doc['delay_factor']}, "
            f"{doc['seconds'] * 1000:.0f} ms (median of {doc['repeat']}; the first, which also builds the "
            f"roadmap's spanner, {doc['first_seconds'] * 1000:.0f} ms), {doc['expansions']} expansions, "
            f"{doc['graph_nodes']} graph points"
        )
        print(
            f"memory: process peak {doc['peak_mb']:.0f} MB, of which {doc['loaded_mb']:.0f} MB before "
            f"the query (interpreter, libraries, roadmap): the query adds {doc['peak_mb'] - doc['loaded_mb']:.0f} MB"
        )


def peak_mb() -> float:
    """This process's peak resident memory (VmHWM; ru_maxrss would include the parent's
    high-water mark, which Linux carries across fork and exec)."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def child(scene_path: str, rm_path: str, backend: str, repeat: int = 3) -> None:
    scene = load_scene(scene_path)
    rm = load_roadmap(rm_path, scene)
    q = scene.queries[0]
    options = PlanOptions(backend=backend)
    if backend == "compiled":  # load the kernels before measuring what a query adds
        from gfuzzy.timespace.search_kernel import warm

        warm()
    loaded = peak_mb()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        res = plan(scene, rm, q.start, q.goal, q.t0, options)
        times.append(time.perf_counter() - t)
    peak = peak_mb()
    print(
        json.dumps(
            {
                "status": res.status.value,
                "duration": None if res.duration is None else round(res.duration, 3),
                "delay_factor": None if res.delay_factor is None else round(res.delay_factor, 3),
                "seconds": statistics.median(times),
                "first_seconds": times[0],
                "repeat": repeat,
                "expansions": res.stats.expansions,
                "graph_nodes": res.stats.graph_nodes,
                "loaded_mb": loaded,
                "peak_mb": peak,
            }
        )
    )


def cold(repeat: int = 3) -> None:
    """Wall time of a fresh ``gfuzzy plan`` process on building floor (median)."""
    times = {}
    with tempfile.TemporaryDirectory() as tmp:
        for backend in ("compiled", "reference"):
            runs = []
            for _ in range(repeat):
                t = time.perf_counter()
                subprocess.run(
                    [sys.executable, "-m", "gfuzzy", "plan", str(ROOT / "scenes" / "building-floor.yaml"),
                     "-o", str(Path(tmp) / "a.json"), "--backend", backend],
                    capture_output=True, check=True, cwd=ROOT,
                )  # fmt: skip
                runs.append(time.perf_counter() - t)
            times[backend] = statistics.median(runs)
    print(
        f"\ncold `gfuzzy plan scenes/building-floor.yaml` process (import + load + plan + write), median "
        f"of {repeat}: {times['compiled']:.2f} s (reference backend {times['reference']:.2f} s; target <= 2 s)"
    )


def peer(time_limit: float) -> None:
    """Our planner against the OMPL space-time peer on every bundled query."""
    from tools.experiments.common import all_bundled
    from tools.experiments.ompl_peer import PeerOptions, solve_peer

    print(f"\nOMPL space-time peer (RRTConnect in SpaceTimeStateSpace, seed 1, budget {time_limit:g} s)")
    print(f"{'scene/query':<34} {'ours ms':>8} {'peer 1st ms':>11} {'t ratio':>7} {'ours s':>7} "
          f"{'peer 1st s':>10} {'peer best s':>11} {'a ratio':>7}")  # fmt: skip
    t_ratios, a_ratios = [], []
    for scene, rm in all_bundled():
        planner = Planner(scene, rm)
        for q in scene.queries:
            planner.plan(q.start, q.goal, q.t0, hold=q.hold)  # the collision model's caches warm
            t = time.perf_counter()
            res = planner.plan(q.start, q.goal, q.t0, hold=q.hold)
            ours = time.perf_counter() - t
            ans = solve_peer(scene, q, PeerOptions(seed=1, time_limit=time_limit))
            p_sec = ans.first_seconds if ans.status == "solved" else time_limit
            tr = ours / p_sec
            ar = (res.duration / ans.first_arrival) if (res.solved and ans.first_arrival) else None
            if res.solved:
                t_ratios.append(tr)
            if ar is not None:
                a_ratios.append(ar)
            fa = f"{ans.first_arrival:10.2f}" if ans.first_arrival else f"{ans.status:>10}"
            ba = f"{ans.arrival:11.2f}" if ans.arrival else f"{'-':>11}"
            od = f"{res.duration:7.2f}" if res.solved else f"{res.status.value:>7}"
            print(f"{scene.name + '/' + q.name:<34} {ours * 1000:>8.1f} {p_sec * 1000:>11.1f} {tr:>7.3f} "
                  f"{od} {fa} {ba} {'-' if ar is None else f'{ar:.2f}':>7}")  # fmt: skip
    if t_ratios:
        print(f"planning time ratio (ours / peer's first answer; a peer without answer counts its budget): "
              f"median {statistics.median(t_ratios):.3f}, max {max(t_ratios):.3f}")  # fmt: skip
    if a_ratios:
        print(f"arrival ratio (ours / peer's first), where both solved: median {statistics.median(a_ratios):.2f}, "
              f"max {max(a_ratios):.2f}")  # fmt: skip


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--child":
        child(sys.argv[2], sys.argv[3], sys.argv[4])
        return
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--skip-large", action="store_true")
    ap.add_argument("--large-vertices", type=int, default=10_000)
    ap.add_argument("--peer", action="store_true", help="also run the OMPL space-time peer (~1-2 min)")
    ap.add_argument("--peer-budget", type=float, default=5.0)
    args = ap.parse_args()
    from gfuzzy.timespace.search_kernel import warm

    warm()  # the compiled kernels load once, before anything is timed
    table1(args.repeat, args.seed)
    cold()
    if not args.skip_large:
        large(args.large_vertices, args.seed)
    if args.peer:
        peer(args.peer_budget)


if __name__ == "__main__":
    main()
