"""Does the navigator answer within its time budget with many people in view?

    python tools/bench_nav_budget.py                       # 30, 60, 150, 300 people
    python tools/bench_nav_budget.py --crowds 150 --steps 40 --profile   # where the time goes
    python tools/bench_nav_budget.py --opt time_budget=0.2 prediction_horizon=3
    python tools/bench_nav_budget.py --baseline 747cfd3    # + the navigator of that commit

A room of 10 m x 8 m with four pillars, a 600-vertex roadmap (seeded, built once per run),
and K people (discs of radius 0.2) who walk straight lines at 0.5-1.5 m/s and bounce off
the walls, the pillars and the robot (a fifth of them stand still). They are all in view
(``sense`` = everything). The robot (disc 0.25, vmax 1) shuttles between two opposite
corners, replanning every 0.25 s and following each answer until the next call.

Per crowd size, in one run: the wall-clock time of :meth:`gfuzzy.Navigator.step` (p50 /
p95 / max), the fraction of steps over ``time_budget``, the fraction answered by a
fallback (anything but a fresh plan), how many people the navigator predicted in detail,
and the smallest robot-person gap over the run (people bounce off the robot's disc, so a
gap below zero means the robot drove into someone). The first step of each crowd is not
counted (it loads what stays cached). The figures are wall-clock on a shared machine.
``--baseline REV`` also runs ``gfuzzy/navigation/navigator.py`` as it was at git revision REV (on
today's other modules), on the same crowds in the same run.
"""

from __future__ import annotations

import argparse
import cProfile
import importlib.util
import math
import pstats
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gfuzzy  # noqa: E402
from gfuzzy.navigation.navigator import Navigator, NavOptions  # noqa: E402
from gfuzzy.scene.scene import parse_scene  # noqa: E402

W, H = 10.0, 8.0
PILLARS = [(3.0, 3.0), (7.0, 3.0), (3.0, 5.0), (7.0, 5.0)]
PILLAR_R = 0.3
PERSON_R = 0.2
ROBOT_R = 0.25
CORNERS = [(0.8, 0.8), (9.2, 7.2)]
PERIOD = 0.25


def room():
    doc = {
        "version": 1,
        "name": "budget-room",
        "bounds": [0.0, 0.0, W, H],
        "robot": {"disc": ROBOT_R, "vmax": 1.0},
        "obstacles": [{"disc": {"center": list(c), "radius": PILLAR_R}} for c in PILLARS],
        "movers": [],
        "queries": [{"name": "across", "start": list(CORNERS[0]), "goal": list(CORNERS[1]), "t0": 0.0}],
    }
    return parse_scene(doc, "<budget-room>")


class Crowd:
    """K people walking straight lines, bouncing off walls, pillars and the robot."""

    def __init__(self, k: int, rng: np.random.Generator, robot_xy):
        self.rng = rng
        xy = np.zeros((0, 2))
        while len(xy) < k:  # not inside a pillar or the robot; people may overlap each other
            p = rng.uniform([PERSON_R, PERSON_R], [W - PERSON_R, H - PERSON_R], size=(k, 2))
            ok = np.hypot(*(p - np.asarray(robot_xy)).T) > PERSON_R + ROBOT_R + 0.3
            for c in PILLARS:
                ok &= np.hypot(*(p - np.asarray(c)).T) > PERSON_R + PILLAR_R
            xy = np.vstack([xy, p[ok]])[:k]
        ang = rng.uniform(0, 2 * math.pi, k)
        speed = rng.uniform(0.5, 1.5, k) * (rng.random(k) >= 0.2)
        self.xy = xy
        self.v = np.column_stack([np.cos(ang), np.sin(ang)]) * speed[:, None]
        self.seen_v = self.v.copy()  # the velocity a sensor sees: the last sub-step's motion

    def observe(self) -> np.ndarray:
        return np.column_stack([self.xy, self.seen_v, np.full(len(self.xy), PERSON_R)])

    def _blocked(self, new, robot_xy):
        """Steps that would come closer to the robot (within 0.05 m) or into a pillar."""
        blocked = np.zeros(len(new), dtype=bool)
        for c, reach in [(robot_xy, PERSON_R + ROBOT_R + 0.05)] + [(c, PERSON_R + PILLAR_R) for c in PILLARS]:
            d_new = np.hypot(*(new - np.asarray(c)).T)
            blocked |= (d_new < reach) & (d_new < np.hypot(*(self.xy - np.asarray(c)).T))
        return blocked

    def advance(self, dt: float, robot_xy) -> None:
        new = self.xy + self.v * dt
        for axis, size in ((0, W), (1, H)):
            out = (new[:, axis] < PERSON_R) | (new[:, axis] > size - PERSON_R)
            self.v[out, axis] *= -1.0
        blocked = self._blocked(new, robot_xy)
        self.v[blocked] *= -1.0  # turn back (from the robot: give way) and walk on if free
        new = self.xy + self.v * dt
        stuck = self._blocked(new, robot_xy)  # blocked both ways: stand, then a new heading
        ang = self.rng.uniform(0, 2 * math.pi, int(stuck.sum()))
        self.v[stuck] = np.column_stack([np.cos(ang), np.sin(ang)]) * np.hypot(*self.v[stuck].T)[:, None]
        before = self.xy.copy()
        self.xy[~stuck] = np.clip(new[~stuck], PERSON_R, [W - PERSON_R, H - PERSON_R])
        self.seen_v = (self.xy - before) / dt  # a person standing (stuck) is seen standing


def baseline_navigator(rev: str):
    """The Navigator class of ``gfuzzy/navigation/navigator.py`` at git revision ``rev``."""
    root = Path(__file__).resolve().parents[1]
    src = subprocess.run(["git", "show", f"{rev}:gfuzzy/navigation/navigator.py"], cwd=root, capture_output=True, text=True, check=True).stdout
    spec = importlib.util.spec_from_loader(f"gfuzzy._navigator_{rev}", loader=None)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "gfuzzy"
    sys.modules[spec.name] = mod  # dataclasses look their module up
    exec(compile(src, f"{rev}:gfuzzy/navigation/navigator.py", "exec"), mod.__dict__)
    return mod.Navigator, mod.NavOptions


def run(k: int, steps: int, seed: int, roadmap, scene, options: NavOptions, nav_class=Navigator) -> dict:
    rng = np.random.default_rng(seed)
    navs = [nav_class(scene, roadmap, CORNERS[1], options), nav_class(scene, roadmap, CORNERS[0], options)]
    which = 0
    pose = np.array(CORNERS[0], dtype=float)
    crowd = Crowd(k, rng, pose)
    t = 0.0
    seconds, modes, detailed = [], {}, []
    gap = math.inf
    for i in range(steps + 1):
        nav = navs[which]
        obs = crowd.observe()
        c0 = time.perf_counter()
        traj = nav.step(t, pose, obs)
        dt_call = time.perf_counter() - c0
        if i > 0:
            seconds.append(dt_call)
            modes[nav.last.mode] = modes.get(nav.last.mode, 0) + 1
            detailed.append(getattr(nav.last, "detailed", len(obs)))
        if nav.reached:
            which = 1 - which
            continue
        # follow the answer for one period, the people walking meanwhile (0.05 s sub-steps)
        for s in range(5):
            tt = t + (s + 1) * PERIOD / 5
            pose = traj.at(np.array([tt]))[0]
            crowd.advance(PERIOD / 5, pose[:2])
            gap = min(gap, float(np.min(np.hypot(*(crowd.xy - pose[:2]).T), initial=math.inf)) - PERSON_R - ROBOT_R)
        t += PERIOD
    sec = np.array(seconds)
    n = len(sec)
    fallback = n - modes.get("plan", 0) - modes.get("goal", 0)
    return {
        "k": k,
        "steps": n,
        "p50": float(np.quantile(sec, 0.5)),
        "p95": float(np.quantile(sec, 0.95)),
        "max": float(sec.max()),
        "over": float(np.mean(sec > options.time_budget)),
        "fallback": fallback / n,
        "modes": modes,
        "detailed": float(np.mean(detailed)),
        "gap": gap,
    }


def parse_opts(items):
    out = {}
    for item in items or []:
        key, _, val = item.partition("=")
        default = getattr(NavOptions(), key)
        if isinstance(default, bool):  # bool("False") is True
            if val.lower() not in ("true", "false", "1", "0"):
                raise SystemExit(f"--opt {item}: expected true or false")
            out[key] = val.lower() in ("true", "1")
        else:
            out[key] = type(default)(val)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--crowds", type=int, nargs="+", default=[30, 60, 150, 300])
    ap.add_argument("--steps", type=int, default=120, help="timed steps per crowd size")
    ap.add_argument("--vertices", type=int, default=600)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--opt", nargs="*", help="NavOptions settings, key=value")
    ap.add_argument("--profile", action="store_true", help="cProfile the steps, print the top 25")
    ap.add_argument("--baseline", metavar="REV", help="also run the navigator of this git revision")
    args = ap.parse_args(argv)
    scene = room()
    roadmap = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=args.vertices, seed=args.seed))
    options = NavOptions(**parse_opts(args.opt))
    print(f"room {W:g} x {H:g} m, {len(roadmap.vertices)} vertices, time_budget {options.time_budget:g} s, "
          f"{args.steps} steps per crowd, seed {args.seed}")  # fmt: skip
    print("| navigator | people | steps | p50 (ms) | p95 (ms) | max (ms) | over budget | fallback | predicted in detail | smallest gap (m) | modes |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    prof = cProfile.Profile() if args.profile else None
    policies = [("this", Navigator, options)]
    if args.baseline:
        nav_class, opt_class = baseline_navigator(args.baseline)
        policies.append((args.baseline, nav_class, opt_class(**parse_opts(args.opt))))
    for k in args.crowds:
        for name, nav_class, opts in policies:
            if prof:
                prof.enable()
            r = run(k, args.steps, args.seed + k, roadmap, scene, opts, nav_class)
            if prof:
                prof.disable()
            modes = ", ".join(f"{m} {c}" for m, c in sorted(r["modes"].items()))
            print(
                f"| {name} | {k} | {r['steps']} | {r['p50'] * 1e3:.0f} | {r['p95'] * 1e3:.0f} | {r['max'] * 1e3:.0f} | "
                f"{r['over']:.2f} | {r['fallback']:.2f} | {r['detailed']:.1f} | {r['gap']:.3f} | {modes} |",
                flush=True,
            )
    if prof:
        pstats.Stats(prof).sort_stats("cumulative").print_stats(25)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
