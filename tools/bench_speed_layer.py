"""The stages' retiming: CPU seconds of a plan with the refinement and the speed layer.

    python tools/bench_speed_layer.py                     # the unicycle scenes, building-floor, fuzz 7-2, 7-0, 7-4, 7-7, 7-11
    python tools/bench_speed_layer.py --fuzz 7:2          # one fuzz scene (tools/fuzz_plan.py --seed 7 --only 2)
    python tools/bench_speed_layer.py --fuzz              # no fuzz scenes

The speed layer (and the refined path's timing) runs the safe-interval search on a chain of
points along the path, a differential drive's once per leg choice and round
(:mod:`gfuzzy.planner.driveblend`). Every query is planned four times in one process, the
same answer expected from each:

* ``search s``: the search alone (no stage), the compiled backend;
* ``old s``: the stages as they were: each chain searched by the pure-Python reference over
  the whole horizon at once, the movers sampled for each search (``--backend reference``,
  one round, no shared samples);
* ``compiled 1 s``: the same with the compiled search and safety kernels (the first change
  alone);
* ``ref s``: ``--backend reference`` now (the chains' horizon grows in rounds, the movers'
  samples shared by a stage's searches);
* ``new s``: the default (``--backend compiled``): the compiled search and safety kernels,
  the horizon in rounds, the samples shared.

``x`` is old / new. ``same``: the four staged answers are identical to the last bit (status
and rows) and, when solved, pass :func:`gfuzzy.check_trajectory`. Times are
``time.process_time()`` of this process around ``gfuzzy.plan`` (the GA included, the same in
every variant); the compiled kernels are loaded before the first measurement.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from gfuzzy.check.check import check_trajectory  # noqa: E402
from gfuzzy.planner import retime  # noqa: E402
from gfuzzy.planner.planner import PlanOptions, plan  # noqa: E402
from gfuzzy.roadmap.roadmap import RoadmapOptions, build_roadmap, default_roadmap_path, load_roadmap  # noqa: E402
from gfuzzy.scene.scene import load_scene, parse_scene  # noqa: E402
from gfuzzy.timespace.movers import MoverField  # noqa: E402
from tools.fuzz_plan import make_scene  # noqa: E402

#: (backend, now) of the staged variants, the old one first: ``now`` False is the code before
#: the rounds and the shared samples.
VARIANTS = (("reference", False), ("compiled", False), ("reference", True), ("compiled", True))
DEFAULT_FUZZ = ["7:2", "7:0", "7:4", "7:7", "7:11"]
BUNDLED = ["building-floor-unicycle", "tb3-arena-unicycle", "building-floor"]


def cases(fuzz: list[str], bundled: list[str]):
    """(label, scene, roadmap, query) of every query of the chosen scenes."""
    for name in bundled:
        scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
        rm = load_roadmap(default_roadmap_path(scene, ROOT / "roadmaps"), scene)
        for q in scene.queries:
            yield f"{name}/{q.name}", scene, rm, q
    for item in fuzz:
        seed, index = (int(x) for x in item.split(":"))
        doc = make_scene(seed, index)
        scene = parse_scene(doc, doc["name"])
        rm = build_roadmap(scene, RoadmapOptions(vertices=150, seed=1))  # as tools/fuzz_plan.py
        for q in scene.queries:
            yield f"{doc['name']}/{q.name}", scene, rm, q


def timed(scene, rm, q, options) -> tuple[float, object]:
    t = time.process_time()
    res = plan(scene, rm, q.start, q.goal, t0=q.t0, hold=q.hold, options=options)
    return time.process_time() - t, res


def _fresh(fields, steps, most):
    """The movers sampled for each search alone, as before :class:`retime.ChainFields`."""
    return MoverField(fields.scene, fields.t0, fields.dt, steps, fields.scene.robot.vmax)


def staged(scene, rm, q, backend: str, now: bool, time_limit: float) -> tuple[float, object]:
    """CPU seconds and answer of the staged plan; ``now`` False: one search per chain over
    the whole horizon, the movers sampled for each (the code before the rounds)."""
    keep, share = retime.CHAIN_SLACK_STEPS, retime.ChainFields.__call__
    if not now:
        retime.CHAIN_SLACK_STEPS = 10**12
        retime.ChainFields.__call__ = _fresh
    try:
        opts = PlanOptions(refine=True, speed_layer=True, time_limit=time_limit, backend=backend)
        return timed(scene, rm, q, opts)
    finally:
        retime.CHAIN_SLACK_STEPS, retime.ChainFields.__call__ = keep, share


def identical(answers, scene, q) -> str:
    """'yes' when every answer has the same status and rows, and the solved one checks."""
    first = answers[0]
    for res in answers[1:]:
        if res.status != first.status:
            return "NO (status)"
        a = None if first.trajectory is None else first.trajectory.waypoints
        b = None if res.trajectory is None else res.trajectory.waypoints
        if (a is None) != (b is None) or (a is not None and not np.array_equal(a, b)):
            return "NO (rows)"
    if first.trajectory is not None and not check_trajectory(scene, first.trajectory.waypoints, q).valid:
        return "NO (check)"
    return "yes"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fuzz", nargs="*", default=DEFAULT_FUZZ, help="fuzz scenes SEED:INDEX (tools/fuzz_plan.py)")
    ap.add_argument("--bundled", nargs="*", default=BUNDLED, help="bundled scene names")
    ap.add_argument("--time-limit", type=float, default=600.0, help="PlanOptions.time_limit (wall s) of every plan")
    args = ap.parse_args(argv)
    print("| query | robot | movers | status | search s | old s | compiled 1 s | ref s | new s | x | stages (new) | same |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    totals = np.zeros(1 + len(VARIANTS))
    warm = True
    bad = 0
    for label, scene, rm, q in cases(args.fuzz, args.bundled):
        if warm:  # load the compiled kernels outside the measurements
            timed(scene, rm, q, PlanOptions(time_limit=args.time_limit))
            warm = False
        t_search, _ = timed(scene, rm, q, PlanOptions(time_limit=args.time_limit))
        runs = [staged(scene, rm, q, backend, now, args.time_limit) for backend, now in VARIANTS]
        secs = [t for t, _ in runs]
        answers = [r for _, r in runs]
        new = answers[-1]
        same = identical(answers, scene, q)
        bad += same != "yes"
        totals += [t_search, *secs]
        stages = ""
        if new.speed_report is not None:
            stages = "layer " + ("applied" if new.speed_report.applied else "not applied")
            if new.speed_report.hasty:
                stages += f" ({new.speed_report.hasty['legs']} hasty legs)"
        robot = f"{scene.robot.shape} {'unicycle' if scene.robot.unicycle else 'holonomic'}"
        print(f"| {label} | {robot} | {len(scene.movers)} | {new.status.value} | {t_search:.2f} | "
              + " | ".join(f"{t:.2f}" for t in secs)
              + f" | {secs[0] / max(secs[-1], 1e-9):.1f} | {stages} | {same} |")  # fmt: skip
        sys.stdout.flush()
    print(f"| all | | | | {totals[0]:.2f} | " + " | ".join(f"{t:.2f}" for t in totals[1:])
          + f" | {totals[1] / max(totals[-1], 1e-9):.1f} | | {'yes' if not bad else f'{bad} NOT the same'} |")  # fmt: skip
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
