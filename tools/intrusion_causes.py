"""Where a crowd run's intrusions come from: each intruding step, classified by the decision
that put the robot there.

    python tools/intrusion_causes.py --episodes 20                 # the arena, seed 1
    python tools/intrusion_causes.py --scenario circle --humans 5 --episodes 50

Runs ``gfuzzy crowd``'s episodes (people who ignore the robot: their walks are known in
advance) with the navigator (``--budget-clock cpu``), and for every step whose start
intrudes (CrowdNav++: the robot's centre within 0.6 m of a person's true centre 0.25 ..
1.25 s later) prints how often each cause occurs. The cause is read off the decision one
step before (which chose where the robot stands now): its answer (``plan``, ``close``,
``relaxed``, ...), whether the path space's soft cost dropped the ghosts (``plain``) or
not (``ghosted``), whether that decision's own observation of the person already
predicted the intrusion (``knew``: the straight walk from the estimated velocity) or not
(``surprise``: the person turned, slowed or sped up), whether the robot was already in
that person's way then (``already-in-way``) or walked into it (``entered``), and the
person's observed speed; ``unseen`` when the person was not observed. The navigator's
policy is wrapped to record its decisions (a tool, not the library's API).
"""

from __future__ import annotations

import argparse
import collections
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.navigation import crowdpolicies as CP  # noqa: E402
from gfuzzy.navigation import pathspace as PS  # noqa: E402
from gfuzzy.navigation.navigator import NavOptions  # noqa: E402
from gfuzzy.navigation.sensing import SensorOptions  # noqa: E402
from gfuzzy.navigation.socialmetrics import INTRUSION_DISTANCE, INTRUSION_SAMPLE  # noqa: E402

SAMPLES = 5  # INTRUSION_HORIZON / INTRUSION_SAMPLE


def _record(log: list, dropped: dict) -> None:
    """Wrap the navigator's policy and the path space's soft cost to record each decision."""
    call, cost = CP.NavigatorPolicy.__call__, PS.PathSpace._path_space_cost

    def soft_cost(self, t, pose, obs, infl, found, deadline):
        out = cost(self, t, pose, obs, infl, found, deadline)
        dropped["plain"] = out is not found
        return out

    def decide(self, t, pose, obs):
        dropped["plain"] = False
        traj = call(self, t, pose, obs)
        log.append((np.array(pose, float)[:2].copy(), np.array(obs, float).reshape(-1, 5), str(self.nav.last.mode),
                    dropped["plain"]))
        return traj

    PS.PathSpace._path_space_cost = soft_cost
    CP.NavigatorPolicy.__call__ = decide


def _intrudes(xy: np.ndarray, future: np.ndarray) -> bool:
    return bool((np.hypot(*(future - xy).T) < INTRUSION_DISTANCE).any())


def _cause(log: list, k: int, track: np.ndarray) -> tuple:
    """The cause of an intrusion at step k by the person of ``track`` (T, 2)."""
    pose, _, _, _ = log[k]
    before, obs, mode, plain = log[k - 1]
    near = np.hypot(*(obs[:, :2] - track[k - 1]).T) < 0.05 if len(obs) else np.zeros(0, bool)
    if not near.any():
        return (mode, "unseen")
    o = obs[np.argmax(near)]
    lags = INTRUSION_SAMPLE * np.arange(1, SAMPLES + 1)
    knew = _intrudes(pose, o[:2] + (INTRUSION_SAMPLE + lags)[:, None] * o[2:4])
    already = _intrudes(before, o[:2] + lags[:, None] * o[2:4])
    return (mode, "plain" if plain else "ghosted", "knew" if knew else "surprise",
            "already-in-way" if already else "entered", "slow" if np.hypot(*o[2:4]) < 0.5 else "walking")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="arena", choices=["circle", "square", "arena"])
    ap.add_argument("--humans", type=int, default=20)
    ap.add_argument("--episodes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    setting = C.CrowdSetting(args.scenario, args.humans, sensor=SensorOptions(velocity="estimated", seed=args.seed))
    roadmap = C.crowd_roadmap(setting)
    log: list = []
    _record(log, {})
    causes: collections.Counter = collections.Counter()
    decisions = 0
    for i in range(args.episodes):
        log.clear()
        ep = C.run_episode(setting, roadmap, args.seed, i, ["navigator"], NavOptions(budget_clock="cpu"))[0]
        world = C._World(setting, C.layout(setting, np.random.default_rng([args.seed, i])),
                         np.random.default_rng([args.seed, i, 1]), False)  # the walks run_episode used
        for _ in range(len(log) + SAMPLES + 1):
            world.step()
        tracks = world.tracks()  # (K, T, 2)
        decisions += len(log)
        for k, (pose, *_rest) in enumerate(log):
            d = np.hypot(*(tracks[:, k + 1:k + 1 + SAMPLES] - pose).transpose(2, 0, 1))  # (K, 5)
            hit = np.nonzero((d < INTRUSION_DISTANCE).any(axis=1))[0]
            if len(hit):
                who = hit[np.argmin(d[hit].min(axis=1))]
                causes[_cause(log, k, tracks[who]) if k else ("first step",)] += 1
        print(f"episode {i}: {ep.outcome.value}, intrusion ratio {ep.intrusion_ratio:.3f}", flush=True)
    print(f"{decisions} decisions, {sum(causes.values())} intruding steps")
    for cause, n in causes.most_common():
        print(f"{n:5d}  {' / '.join(cause)}")


if __name__ == "__main__":
    main()
