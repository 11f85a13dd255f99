"""Crowd benchmark: the navigator among people whose future it does not know.

    python tools/bench_crowd.py                        # K = 5 and 10, 100 episodes each
    python tools/bench_crowd.py --episodes 20 --humans 10 --seed 3
    python tools/bench_crowd.py --replays scenes/eth-crossing.yaml scenes/zara-crowd.yaml
    python tools/bench_crowd.py --episodes 0 --social 50       # a crowd that reacts (pysocialforce)
    python tools/bench_crowd.py --opt prediction_horizon=3     # any NavOptions setting
    python tools/bench_crowd.py --workers 2                    # episodes on a local Dask cluster
    python tools/bench_crowd.py --kinematics unicycle --humans 5 20   # a differential drive, wmax 1 rad/s

Protocol: CrowdNav's circle crossing (Chen et al., ICRA 2019), as implemented in
``gfuzzy/crowd.py``: K ORCA humans (radius 0.3, preferred speed 1) cross a circle of
radius 4 and do not see the robot; the robot (disc 0.3, vmax 1) goes from (0, -4) to
(0, 4) within 25 s, replanning every 0.25 s. A collision is decided exactly between
samples (closed-form distance of linearly moving discs). Policies on the same episodes:

* ``navigator``: :class:`gfuzzy.Navigator` through :func:`gfuzzy.navsim.simulate`;
* ``oracle``: :func:`gfuzzy.plan` told the humans' true future (possible because they
  ignore the robot): a lower bound on the time to the goal on the same roadmap;
* ``orca``: CrowdNav's ORCA robot (it assumes the humans yield; they do not).

Per policy and K: success / collision / timeout rates, mean time to goal (successes),
time / oracle (mean of the per-episode ratio over the episodes both solved), mean and
smallest minimum separation, and the navigator's replan latency p50 / p95 / max over every
replan. One 400-vertex roadmap of the empty square is built per run (seeded).

With ``--kinematics unicycle`` the robot is a differential drive (``--wmax``, default
1 rad/s; it starts and ends facing the goal, +y): the navigator's plans, fallbacks and
evasive motions turn only in place and drive only along the heading, and every policy's
answer is held to that (the oracle plans as a unicycle too; ORCA is holonomic, kept as the
reference it is). Episodes run in this process.

Targets (issue 10, benchmark figures): 5 humans success >= 0.99, collision <= 0.01;
10 humans success >= 0.95, collision <= 0.03; time <= 1.15 x oracle; replan p95 <= 100 ms.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import gfuzzy  # noqa: E402
from gfuzzy.crowd import CROWD, circle_crossing, episodes  # noqa: E402
from gfuzzy.navigator import NavOptions  # noqa: E402
from gfuzzy.navsim import min_separation, simulate  # noqa: E402


def as_unicycle(scene, wmax: float):
    """The circle-crossing scene with its robot a differential drive facing the goal (+y)."""
    from dataclasses import replace

    robot = replace(scene.robot, kinematics="unicycle", wmax=wmax)
    queries = tuple(
        replace(q, start=(*q.start[:2], math.pi / 2), goal=(*q.goal[:2], math.pi / 2)) for q in scene.queries
    )
    return replace(scene, robot=robot, queries=queries)


def unicycle_episodes(rm, K, seeds, options, policies, wmax):
    from gfuzzy.crowd import run_episode

    return [run_episode(as_unicycle(circle_crossing(K, s, name=f"crowd-{K}-{s}"), wmax), rm, options, policies)
            for s in seeds]  # fmt: skip


def empty_roadmap(vertices: int, seed: int):
    scene = circle_crossing(0, 1)
    return gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=vertices, seed=seed))


def summarize(K, results, policies):
    lines = []
    oracle_t = np.array([r["oracle"]["time"] if "oracle" in r else math.nan for r in results])
    for p in policies:
        rs = [r[p] for r in results]
        n = len(rs)
        coll = np.array([x["collision"] for x in rs])
        succ = np.array([x["reached"] and not x["collision"] for x in rs])
        tout = ~coll & ~succ
        times = np.array([x["time"] if (x["reached"] and not x["collision"]) else math.nan for x in rs])
        ratio = times / oracle_t
        seps = np.array([x["sep"] for x in rs], dtype=float)
        lat = np.concatenate([x["latency"] for x in rs]) if p == "navigator" else np.zeros(0)
        lat_s = (
            f"{np.quantile(lat, 0.5) * 1e3:6.1f} {np.quantile(lat, 0.95) * 1e3:6.1f} {lat.max() * 1e3:6.1f}"
            if lat.size
            else f"{'-':>6} {'-':>6} {'-':>6}"
        )
        lines.append(
            f"{K:>2} {p:<10} {n:>4} {succ.mean():6.2f} {coll.mean():6.2f} {tout.mean():6.2f} "
            f"{np.nanmean(times) if succ.any() else math.nan:7.2f} "
            f"{np.nanmean(ratio) if np.isfinite(ratio).any() else math.nan:7.3f} "
            f"{np.nanmean(seps):6.3f} {np.nanmin(seps):7.3f}  {lat_s}"
        )
        if p == "navigator":
            modes: dict = {}
            for x in rs:
                for k, v in x["modes"].items():
                    modes[k] = modes.get(k, 0) + v
            lines[-1] += "   " + " ".join(f"{k}:{v}" for k, v in sorted(modes.items()))
    return lines


SOCIAL_CONFIG = """
[scene]
enable_group = false
agent_radius = 0.3
step_width = 0.25
max_speed_multiplier = 1.3
tau = 0.5
resolution = 10
"""


def social_episode(K, seed, roadmap, options):
    """One closed-loop circle-crossing episode in which the humans react to the robot.

    The humans are pysocialforce's extended social force model (Helbing & Molnar 1998,
    Moussaid et al. 2010) with the robot as one more pedestrian, whose state is overwritten
    every step with where the robot is and how it moves; starts and goals as in the ORCA
    protocol. Every 0.25 s the robot observes the humans, replans, and moves; the humans
    then move with the social force's velocity for 0.25 s, so both move linearly between
    samples and the collision test is exact.
    """
    import logging
    import os
    import tempfile

    here = os.getcwd()
    with tempfile.TemporaryDirectory() as scratch:
        os.chdir(scratch)  # pysocialforce writes a file.log into the current folder on import
        try:
            import pysocialforce as psf
        finally:
            os.chdir(here)
    logging.getLogger().setLevel(logging.WARNING)  # it also turns the root logger to DEBUG
    from gfuzzy.crowd import _starts
    from gfuzzy.navigator import Navigator
    from gfuzzy.rng import create_rng
    from gfuzzy.scene import parse_scene

    c = CROWD
    dt = c["time_step"]
    starts, goals = _starts(K, create_rng(seed))
    d = goals - starts
    v0 = d / np.hypot(*d.T)[:, None] * c["v_pref"]
    start, goal = np.array(c["start"]), np.array(c["goal"])
    state = np.vstack([np.column_stack([starts, v0, goals]), [[*start, 0.0, c["robot_vmax"], *goal]]])
    with tempfile.NamedTemporaryFile("w", suffix=".toml", delete=False) as fh:
        fh.write(SOCIAL_CONFIG)
    sim = psf.Simulator(state, config_file=fh.name)
    Path(fh.name).unlink()
    sim.peds.step_width = dt  # the library reads it from the wrong level of its config
    scene0 = circle_crossing(0, 1)
    nav = Navigator(scene0, roadmap, goal, options)
    pose = start.copy()
    t = 0.0
    rows = [[0.0, *pose]]
    track = [sim.peds.pos()[:K].copy()]
    lat = []
    reached = False
    while t < c["time_limit"] - 1e-9:
        pos, vel = sim.peds.pos()[:K], sim.peds.vel()[:K]
        obs = np.column_stack([pos, vel, np.full(K, c["human_radius"])])
        c0 = time.perf_counter()
        traj = nav.step(t, pose, obs)
        lat.append(time.perf_counter() - c0)
        w = traj.waypoints
        inner = w[(w[:, 0] > t + 1e-9) & (w[:, 0] < t + dt - 1e-9)]
        rows.extend(inner.tolist())
        new = traj.at(t + dt)
        rows.append([t + dt, *new])
        st = sim.peds.state
        st[K, 0:2] = pose
        st[K, 2:4] = (new - pose) / dt
        sim.step(1)
        st = sim.peds.state
        st[K, 0:2] = new  # the robot is where it went, not where the forces pushed it
        st[K, 4:6] = goal
        pose = new
        t += dt
        track.append(sim.peds.pos()[:K].copy())
        if np.hypot(*(pose - goal)) <= nav.options.goal_tolerance:
            reached = True
            break
    track = np.array(track)  # (n, K, 2)
    times = np.arange(len(track)) * dt
    doc = {
        "version": 1, "name": "social", "bounds": [-20, -20, 20, 20],
        "robot": {"disc": c["robot_radius"], "vmax": c["robot_vmax"]}, "obstacles": [],
        "movers": [
            {"name": f"h{i}", "disc": c["human_radius"], "trajectory": np.column_stack([times, track[:, i]]).tolist()}
            for i in range(K)
        ],
        "queries": [],
    }
    wps = np.array(rows)
    keep = np.r_[True, np.diff(wps[:, 0]) > 1e-9]
    sep = min_separation(parse_scene(doc, "<social>"), wps[keep])
    return {
        "collision": sep < -1e-9, "reached": reached, "time": t if reached else math.nan, "sep": sep,
        "latency": np.array(lat), "modes": {},
    }


def social(args, rm, options):
    print("\nsocial-force crowd (people react to the robot; closed loop, no oracle)")
    for K in args.humans:
        t0 = time.perf_counter()
        results = [{"navigator": social_episode(K, args.seed + 1000 * K + i, rm, options)} for i in range(args.social)]
        for line in summarize(K, results, ["navigator"]):
            print(line)
        print(f"   ({time.perf_counter() - t0:.0f} s)")


def replays(paths, options, vertices, seed):
    print("\npedestrian replays through navigate (real tracks, checked with gfuzzy.check_trajectory)")
    print(f"{'scene':<22} {'query':<12} {'status':<8} {'time':>6} {'oracle':>6} {'check':<6} {'sep':>6} {'p95 ms':>7}")
    for path in paths:
        scene = gfuzzy.load_scene(path)
        default = Path(path).resolve().parents[1] / "roadmaps" / f"{scene.name}.json"
        if default.exists():
            rm = gfuzzy.load_roadmap(default, scene)
        else:
            rm = gfuzzy.build_roadmap(scene, gfuzzy.RoadmapOptions(vertices=vertices, seed=seed))
        for q in scene.queries:
            res = simulate(scene, rm, q.start, q.goal, q.t0, 0.25, options=options)
            rep = gfuzzy.check_trajectory(scene, res.trajectory.waypoints, q if res.reached else None)
            orc = gfuzzy.plan(scene, rm, q.start, q.goal, q.t0)
            print(
                f"{scene.name:<22} {q.name:<12} {res.status:<8} {res.duration:6.2f} "
                f"{orc.duration if orc.solved else math.nan:6.2f} {str(rep.valid):<6} "
                f"{res.min_separation:6.3f} {res.latency(0.95) * 1e3:7.1f}"
            )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=100, help="episodes per crowd size")
    ap.add_argument("--humans", type=int, nargs="+", default=[5, 10])
    ap.add_argument("--seed", type=int, default=1, help="first episode seed (episode i uses seed + i)")
    ap.add_argument("--vertices", type=int, default=400)
    ap.add_argument("--roadmap-seed", type=int, default=1)
    ap.add_argument("--policies", nargs="+", default=["navigator", "oracle", "orca"])
    ap.add_argument("--social", type=int, default=0, help="episodes per K of a social-force crowd (pysocialforce)")
    ap.add_argument("--replays", nargs="*", default=None, help="scenes to replay through navigate")
    ap.add_argument("--opt", nargs="*", default=[], metavar="NAME=VALUE", help="NavOptions settings, e.g. time_budget=0.2")
    ap.add_argument("--workers", type=int, default=0,
                    help="run the circle-crossing episodes on a local Dask cluster of this many processes "
                         "(0: in this process); each episode's replan latencies are measured in its worker")  # fmt: skip
    ap.add_argument("--kinematics", choices=["holonomic", "unicycle"], default="holonomic",
                    help="the robot's kinematics (unicycle: a differential drive)")
    ap.add_argument("--wmax", type=float, default=1.0, help="unicycle: bound on the turning rate, rad/s")
    args = ap.parse_args(argv)
    settings = {}
    for item in args.opt:
        name, _, value = item.partition("=")
        settings[name] = type(getattr(NavOptions(), name))(float(value))
    options = NavOptions(**settings)
    print(f"options: {options}")
    t_all = time.perf_counter()
    if args.episodes > 0:
        rm = empty_roadmap(args.vertices, args.roadmap_seed)
        print(f"roadmap: {len(rm.vertices)} vertices, {len(rm.edges)} edges; {args.episodes} episodes per K, seeds {args.seed}..")
        header = (
            f"{'K':>2} {'policy':<10} {'n':>4} {'succ':>6} {'coll':>6} {'tout':>6} {'time':>7} "
            f"{'t/orac':>7} {'sep':>6} {'minsep':>7}  {'p50ms':>6} {'p95ms':>6} {'maxms':>6}"
        )
        with contextlib.ExitStack() as stack:
            client = None
            if args.workers > 0:
                from gfuzzy.batch import local_cluster

                client = stack.enter_context(local_cluster(args.workers))
                print(f"on {args.workers} Dask worker process(es)")
            for K in args.humans:
                t0 = time.perf_counter()
                seeds = [args.seed + 1000 * K + i for i in range(args.episodes)]
                if args.kinematics == "unicycle":
                    results = unicycle_episodes(rm, K, seeds, options, args.policies, args.wmax)
                else:
                    results = episodes(client, rm, K, seeds, options, args.policies)
                print(header)
                for line in summarize(K, results, args.policies):
                    print(line)
                print(f"   ({time.perf_counter() - t0:.0f} s)")
                sys.stdout.flush()
    if args.social > 0:
        social(args, empty_roadmap(args.vertices, args.roadmap_seed), options)
    if args.replays is not None:
        paths = args.replays or [
            str(p) for p in sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.yaml"))
            if p.stem in ("eth-crossing", "zara-crowd")
        ]
        replays(paths, options, args.vertices, args.roadmap_seed)
    print(f"total {time.perf_counter() - t_all:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
