"""Replanning benchmark: a fresh ``Planner.plan`` against ``Planner.plan_from`` (issue 11).

    python tools/bench_replan.py                       # building floor 200/1000/5000 + hall
    python tools/bench_replan.py --sizes 200 1000 --skip-hall --repeat 3

A navigator replans to the same goal from where the robot is. For each setup the first
query is answered once; then, from a few poses along that answer (at 10, 20, 30 and 40 %
of its duration, at the time the robot is there: mid-edge poses, later departures), the
same query is answered by a fresh ``plan`` and by ``plan_from`` on a goal prepared once
(``Planner.prepare``), both on one kept ``Planner`` (the collision model is shared; what
differs is the graph), alternating, median of ``--repeat`` runs each. Printed per setup:

* ``plan ms`` / ``from ms``: the medians over the starts of each start's median; ``x`` their
  ratio (fresh / plan_from), measured in the same run;
* ``graph ms`` / ``splice ms``: the graph part alone, a fresh query's (``Planner.prepare``
  then ``PreparedGoal.splice``: both ends' connections, the spanner's cut from the roadmap's
  cache, three Dijkstras) against ``PreparedGoal.splice`` on the kept goal (the start's
  connections, one Dijkstra on the vertices);
* ``same``: on how many starts both give the same status and arrival (they must: both search
  the same graph, the prepared goal's with the start spliced in).

Setups: building-floor roadmaps grown to 200, 1000 and 5000 vertices (seed 1) and the hall of
``tools/bench_plan.py`` (40 m x 30 m, 24 pillars, 200 movers) with a ``--hall-vertices`` roadmap.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.planner.planner import Planner  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, grow_roadmaps  # noqa: E402
from gfuzzy.scene.scene import load_scene  # noqa: E402
from tools.bench_plan import hall_scene  # noqa: E402

FRACTIONS = (0.1, 0.2, 0.3, 0.4)


def _median_ms(fn, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times) * 1000


def measure(label: str, scene, rm, repeat: int) -> dict:
    """One row: fresh plan vs plan_from (and their graph parts) from starts along the answer."""
    planner = Planner(scene, rm)
    q = scene.queries[0]
    first = planner.plan(q.start, q.goal, q.t0)
    if not first.solved:
        print(f"{label}: the first query is {first.status.value}: nothing to replan along")
        return {}
    t = time.perf_counter()
    prepared = planner.prepare(q.goal)
    prepare_ms = (time.perf_counter() - t) * 1000
    goal = np.asarray(q.goal, float)
    plan_ms, from_ms, graph_ms, splice_ms = [], [], [], []
    same = 0
    for frac in FRACTIONS:
        t0 = q.t0 + frac * first.duration
        pose = first.trajectory.at(t0)
        fresh = planner.plan(pose, q.goal, t0)
        again = planner.plan_from(prepared, pose, t0)
        same += (fresh.status, fresh.duration) == (again.status, again.duration)
        plan_ms.append(_median_ms(lambda: planner.plan(pose, q.goal, t0), repeat))  # noqa: B023
        from_ms.append(_median_ms(lambda: planner.plan_from(prepared, pose, t0), repeat))  # noqa: B023
        wrapped = pose.copy()
        if len(wrapped) == 3:
            wrapped[2] = (wrapped[2] + np.pi) % (2 * np.pi) - np.pi
        graph_ms.append(_median_ms(lambda: planner.prepare(goal).splice(planner, wrapped), repeat))  # noqa: B023
        splice_ms.append(_median_ms(lambda: prepared.splice(planner, wrapped), repeat))  # noqa: B023
    graph = prepared.splice(planner, first.trajectory.at(q.t0)).graph
    row = {
        "plan": statistics.median(plan_ms),
        "from": statistics.median(from_ms),
        "graph": statistics.median(graph_ms),
        "splice": statistics.median(splice_ms),
    }
    print(
        f"{label:<22} {len(rm.vertices):>6} {len(graph.poses):>7} {prepare_ms:>10.1f} {row['plan']:>8.1f} "
        f"{row['from']:>8.1f} {row['plan'] / row['from']:>5.2f} {row['graph']:>9.2f} {row['splice']:>9.2f} "
        f"{row['graph'] / row['splice']:>5.1f} {same:>2}/{len(FRACTIONS)}"
    )
    return row


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--sizes", type=int, nargs="+", default=[200, 1000, 5000])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--hall-vertices", type=int, default=2000)
    ap.add_argument("--skip-hall", action="store_true")
    args = ap.parse_args(argv)

    from gfuzzy.timespace.search_kernel import warm

    warm()
    print(
        f"{'setup':<22} {'verts':>6} {'points':>7} {'prepare ms':>10} {'plan ms':>8} {'from ms':>8} {'x':>5} "
        f"{'graph ms':>9} {'splice ms':>9} {'x':>5} same"
    )
    scene = load_scene(ROOT / "scenes" / "building-floor.yaml")
    for rm in grow_roadmaps(scene, args.sizes, RoadmapOptions(seed=args.seed)):
        measure("building-floor", scene, rm, args.repeat)
    if not args.skip_hall:
        with tempfile.TemporaryDirectory() as tmp:
            scene = load_scene(hall_scene(Path(tmp) / "hall.yaml"))
            rm = build_roadmap(scene, RoadmapOptions(vertices=args.hall_vertices, seed=args.seed))
            measure("hall-200 (200 movers)", scene, rm, args.repeat)


if __name__ == "__main__":
    main()
