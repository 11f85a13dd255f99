"""Crowd benchmark: the targets of issue 19, measured with ``gfuzzy crowd``'s engine.

    python tools/bench_crowd.py                              # every setting, 100 episodes each
    python tools/bench_crowd.py --episodes 300 --workers 2   # the run of docs/navigator.md
    python tools/bench_crowd.py --only circle-20-visible arena --episodes 50
    python tools/bench_crowd.py --episodes 0 --replays       # the ETH/UCY replays only

Each setting is one ``gfuzzy crowd`` command line (printed above its table), e.g.
``gfuzzy crowd --humans 20 --visible --episodes 300 --workers 2``: CrowdNav's circle
crossing (Chen et al. 2019) or CrowdNav++'s arena (Liu et al. 2023), see
``gfuzzy/navigation/crowd.py``. The table per setting: success, collision and timeout rates, mean
time to goal, discomfort frequency (gap < 0.2 m), intrusion ratio (CrowdNav++), mean
smallest separation, replan p50 / p95 (ms, measured in the workers), then the target.
``--replays`` adds the bundled pedestrian replays through ``gfuzzy navigate`` with
estimated velocities, each checked with ``gfuzzy check``.
Quote the load (``uptime``) with the figures: the replan budget is wall-clock.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gfuzzy.cli.crowds import _table  # noqa: E402
from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.navigation.navigator import NavOptions  # noqa: E402
from gfuzzy.navigation.sensing import SensorOptions  # noqa: E402

#: name: (gfuzzy crowd flags, CrowdSetting keywords, policies, the issue's target)
SETTINGS = {
    "circle-5-invisible": ("--humans 5", {"humans": 5}, ["navigator", "orca", "oracle"],
                           "success >= 0.99, time <= 10.46 s, discomfort <= 0.05"),
    "circle-5-visible": ("--humans 5 --visible", {"humans": 5, "visible": True}, ["navigator", "orca"],
                         "success >= 0.99, discomfort <= 0.03"),
    "circle-20-visible": ("--humans 20 --visible", {"humans": 20, "visible": True}, ["navigator", "orca"],
                          "success >= 0.995, collision <= 0.005, discomfort <= 0.10 (ORCA robot: 0.41 success)"),
    "circle-20-invisible": ("--humans 20", {"humans": 20}, ["navigator", "orca"],
                            "success >= 0.99, collision <= 0.01, discomfort <= 0.10 (ORCA robot: 0.04)"),
    "arena": ("--scenario arena", {"scenario": "arena", "humans": 20}, ["navigator", "orca"],
              "success >= 0.95, intrusion <= 0.04 (CrowdNav++'s policy: 0.92, 4.23 %)"),
    "arena-steady-goals": ("--scenario arena --steady-goals", {"scenario": "arena", "humans": 20, "goal_changes": False},
                           ["navigator", "orca"], "(CrowdNav++'s non-randomised test: its policy 0.92, 4.23 %)"),
    "circle-5-noise": ("--humans 5 --noise 0.05", {"humans": 5, "noise": 0.05}, ["navigator"], "(noise alone)"),
    "circle-5-fov": ("--humans 5 --fov 180", {"humans": 5, "fov": 180.0}, ["navigator"], "(the half view alone)"),
    "circle-5-noise-fov": ("--humans 5 --noise 0.05 --fov 180", {"humans": 5, "noise": 0.05, "fov": 180.0},
                           ["navigator"], "success >= 0.97"),
    "circle-5-social-force-visible": ("--humans 5 --visible --crowd social-force",
                                      {"humans": 5, "visible": True, "crowd": "social-force"},
                                      ["navigator", "social-force"], "(no target: the reacting crowd of the second model)"),
    "circle-5-unicycle": ("--humans 5 --kinematics unicycle", {"humans": 5, "kinematics": "unicycle"}, ["navigator", "oracle"],
                          "success >= 0.99, time <= 11 s"),
    "circle-20-unicycle": ("--humans 20 --kinematics unicycle", {"humans": 20, "kinematics": "unicycle"}, ["navigator", "oracle"],
                           "success >= 0.97"),
    "circle-5-unicycle-reverse": ("--humans 5 --kinematics unicycle --reverse",
                                  {"humans": 5, "kinematics": "unicycle", "reverse": True}, ["navigator"],
                                  "(a drive that may back up; issue 18's setting says nothing of reversing)"),
    "circle-20-unicycle-reverse": ("--humans 20 --kinematics unicycle --reverse",
                                   {"humans": 20, "kinematics": "unicycle", "reverse": True}, ["navigator"],
                                   "(a drive that may back up)"),
}  # fmt: skip


def setting_of(kw: dict, seed: int) -> C.CrowdSetting:
    kw = dict(kw)
    sensor = SensorOptions(noise=kw.pop("noise", 0.0), fov=kw.pop("fov", 360.0), seed=seed)
    return C.CrowdSetting(sensor=sensor, **kw)


def run_setting(name, episodes, seed, client, only_policy=None, clock="wall"):
    flags, kw, policies, target = SETTINGS[name]
    policies = only_policy or policies
    print(f"\n### {name}\n$ gfuzzy crowd {flags} --episodes {episodes} --seed {seed} --policy {' '.join(policies)}"
          f"{' --workers 2' if client is not None else ''}{' --budget-clock cpu' if clock == 'cpu' else ''}")
    try:
        setting = setting_of(kw, seed)
    except C.InputError as exc:
        print(f"not run: {exc}")
        return
    t0 = time.perf_counter()
    rm = C.crowd_roadmap(setting)
    runs = C.episodes(setting, rm, seed, episodes, policies, NavOptions(budget_clock=clock), client)
    print(_table(setting, runs, policies))
    print(f"target: {target}   ({time.perf_counter() - t0:.0f} s, load {os.getloadavg()[0]:.1f})")
    sys.stdout.flush()


def replays(seed: int) -> None:
    print("\n### pedestrian replays through gfuzzy navigate (estimated velocities), checked")
    for name in ("eth-crossing", "zara-crowd"):
        with tempfile.TemporaryDirectory() as d:
            out = Path(d) / f"{name}.json"
            cmd = [sys.executable, "-m", "gfuzzy", "navigate", f"scenes/{name}.yaml", "--seed", str(seed), "-o", str(out)]
            nav = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
            chk = subprocess.run([sys.executable, "-m", "gfuzzy", "check", f"scenes/{name}.yaml", str(out)],
                                 capture_output=True, text=True, cwd=ROOT)  # fmt: skip
            doc = json.loads(out.read_text()) if out.exists() else {}
            print(f"$ gfuzzy navigate scenes/{name}.yaml: {nav.stdout.strip()}")
            print(f"  check: {chk.stdout.strip() or chk.stderr.strip()}  (discomfort {doc.get('discomfort_frequency')},"
                  f" intrusion {doc.get('intrusion_ratio')})")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=0, help="a local Dask cluster of this many processes (0: here)")
    ap.add_argument("--only", nargs="+", choices=sorted(SETTINGS), help="these settings only")
    ap.add_argument("--policy", nargs="+", help="these policies only (in every setting)")
    ap.add_argument("--replays", action="store_true", help="the ETH/UCY replays through navigate")
    ap.add_argument("--budget-clock", choices=("wall", "cpu"), default="wall",
                    help="the navigator's budget on the wall clock (default) or on CPU time (figures independent of load)")
    args = ap.parse_args(argv)
    print(f"load at start: {os.getloadavg()}")
    with contextlib.ExitStack() as stack:
        client = None
        if args.workers > 0 and args.episodes > 0:
            from gfuzzy.runs.batch import local_cluster

            client = stack.enter_context(local_cluster(args.workers))
        if args.episodes > 0:
            for name in args.only or SETTINGS:
                run_setting(name, args.episodes, args.seed, client, args.policy, args.budget_clock)
    if args.replays:
        replays(args.seed)
    return 0


if __name__ == "__main__":
    sys.exit(main())
