"""Where a crowd crossing's time goes: each successful episode's time cut into pieces.

    python tools/time_audit.py --episodes 200                      # circle, 5 humans, seed 1
    python tools/time_audit.py --episodes 200 --policy navigator oracle
    python tools/time_audit.py --episodes 200 --path-space 0

Runs ``gfuzzy crowd``'s episodes (``--budget-clock cpu``, people who ignore the robot)
and records where the robot stood at every step. The time to the goal T (whole steps of
0.25 s) is, exactly, the straight run at ``vmax`` plus four pieces:

    T = (d0 - r) / vmax + over + detour + slow + wait

with d0 the start's distance to the goal and r the success radius (the robot's radius;
d0 - r is 7.7 m on the circle): ``over`` the distance run past the success circle in the last step
(the step is whole), ``detour`` the path's length less its progress towards the goal,
``slow`` the steps' shortfall from ``vmax`` while moving, ``wait`` the steps it stood
(moved under 0.02 m). ``start`` and ``arrival`` are the shortfall from ``vmax`` of the
first four steps and of the last four, waits included (a wait counts a whole step). ``zigzag`` is the path's length less that of its
positions a second apart (turns inside a second, from one plan to the next), ``turning``
the sum of the heading changes between steps (rad). The policy is wrapped to record the
poses (a tool, not the library's API).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.navigation.navigator import NavOptions  # noqa: E402

#: A step moving less than this (m) is a wait.
STILL = 0.02
#: Columns of the table, in order.
PIECES = ("time", "line", "over", "detour", "slow", "wait", "start", "arrival", "zigzag", "turning")


def audit(poses, goal, radius: float, vmax: float, dt: float) -> dict:
    """The pieces (s, but ``turning``: rad) of one successful episode's time from the
    robot's positions ``poses`` (n + 1, 2) at its n steps' ends (the start first)."""
    d = np.hypot(*np.diff(poses, axis=0).T)
    r = np.hypot(*(poses - goal).T)
    moving = d >= STILL
    short = np.where(moving, dt - d / vmax, dt)
    second = poses[:: max(1, round(1.0 / dt))]
    second = np.vstack([second, poses[-1:]])
    step = np.diff(poses, axis=0)[moving]
    heading = np.arctan2(step[:, 1], step[:, 0])
    turn = np.abs((np.diff(heading) + np.pi) % (2 * np.pi) - np.pi)
    return {
        "time": len(d) * dt, "line": (r[0] - radius) / vmax, "over": (radius - r[-1]) / vmax,
        "detour": float(np.sum(d + np.diff(r))) / vmax, "slow": float(np.sum(short[moving])),
        "wait": dt * float(np.sum(~moving)), "start": float(short[:4].sum()), "arrival": float(short[-4:].sum()),
        "zigzag": float(d.sum() - np.hypot(*np.diff(second, axis=0).T).sum()) / vmax, "turning": float(turn.sum()),
    }  # fmt: skip


def _recorder(store: list):
    """Wrap the policies' calls so that each records the pose it was called at."""
    from gfuzzy.navigation import crowdpolicies as CP

    for cls in (CP.NavigatorPolicy, CP.OraclePolicy):
        call = cls.__call__

        def wrapped(self, t, pose, obs, *rest, _call=call):
            traj = _call(self, t, pose, obs, *rest)
            store.append((float(t), np.asarray(pose, float)[:2].copy(), traj))
            return traj

        cls.__call__ = wrapped


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--humans", type=int, default=5)
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--first", type=int, default=0, help="first episode")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--policy", nargs="+", default=["navigator", "oracle"], choices=["navigator", "oracle"])
    ap.add_argument("--path-space", type=float, default=NavOptions.path_space)
    ap.add_argument("--personal-space", type=float, default=NavOptions.personal_space)
    args = ap.parse_args(argv)
    setting = C.CrowdSetting(scenario="circle", humans=args.humans)
    opts = NavOptions(budget_clock="cpu", path_space=args.path_space, personal_space=args.personal_space)
    roadmap = C.crowd_roadmap(setting)
    c = C.CROWD
    store: list = []
    _recorder(store)
    rows = {p: [] for p in args.policy}
    for i in range(args.first, args.first + args.episodes):
        for p in args.policy:
            store.clear()
            ep = C.run_episode(setting, roadmap, args.seed, i, [p], opts)[0]
            if ep.reached:
                end = store[-1][2].at(min(store[-1][0] + c["time_step"], store[-1][2].t_end))[:2]
                poses = np.vstack([[s[1] for s in store], end])
                rows[p].append(audit(poses, np.asarray(c["goal"]), c["robot_radius"], c["robot_vmax"], c["time_step"]))
    print("policy     n    " + " ".join(f"{k:>8s}" for k in PIECES))
    for p, got in rows.items():
        mean = {k: np.mean([g[k] for g in got]) if got else float("nan") for k in PIECES}
        print(f"{p:9s} {len(got):4d}  " + " ".join(f"{mean[k]:8.3f}" for k in PIECES))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
