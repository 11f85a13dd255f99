"""Every navigator call of a differential drive's crowd episodes, recorded; its failures classified.

    python tools/crowd_calls.py record calls.json --seed 1 --episodes 0 200      # circle, 5 people, unicycle
    python tools/crowd_calls.py record big.json --episodes 0 3 --time-budget 5   # every search finishes
    python tools/crowd_calls.py classify calls.json [--oracle]
    python tools/crowd_calls.py compare before.json after.json
    python tools/crowd_calls.py record p.json --episodes 0 4 --time-budget 5 --profile 40   # where a call's CPU goes
    python tools/crowd_calls.py record h.json --kinematics holonomic --humans 20 --episodes 0 40   # a disc robot

``record`` runs ``gfuzzy crowd --scenario circle --kinematics unicycle --policy navigator
--budget-clock cpu``'s episodes (``crowd.run_episode``) and wraps :meth:`gfuzzy.Navigator.step`
to keep, per call: the time, the pose, the answer's mode, its message (why no plan), whether
the searches ran out of time, the people predicted in detail, the call's CPU seconds (the
budget's clock), the searches' effort level (:mod:`gfuzzy.navigation.effort`; 0 for a
navigator without it) and a hash of the answer's rows. The file is written (atomically) every ten
episodes, so a run stopped early keeps what it did.

``classify``: success, time, replan CPU p50 / p95, the answers by mode, the evasive ones by
reason, how many episodes began with evasive answers, and per failure the last 2 s of calls
and whether any plan had answered; ``--oracle`` also runs ``gfuzzy.plan`` told the future
(the oracle policy, at its step 0.07 s and at 0.03 s) on each failed episode.

``compare`` (two records of the same episodes, e.g. the code before and after a change run
side by side): the answers' hashes that agree call by call (the same to the bit when every
search finished, ``--time-budget 5``), the CPU per call, the evasive answers, success and
time on the episodes both finish. ``--profile N`` runs :mod:`cProfile` over the calls only (not the
simulation) and prints the N costliest functions by their own time and by their time inclusive,
per call. A tool, not the library's API.
"""

from __future__ import annotations

import argparse
import collections
import cProfile
import hashlib
import json
import pstats
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gfuzzy.atomic import write_atomic  # noqa: E402
from gfuzzy.navigation import crowd as C  # noqa: E402
from gfuzzy.navigation.navigator import Navigator, NavOptions  # noqa: E402
from gfuzzy.navigation.sensing import SensorOptions  # noqa: E402

PLANS = ("plan", "close", "kept", "relaxed")


def _setting(humans: int, seed: int, kinematics: str = "unicycle") -> C.CrowdSetting:
    return C.CrowdSetting(humans=humans, kinematics=kinematics, sensor=SensorOptions(seed=seed))


def record(out: str, humans: int, seed: int, first: int, stop: int, budget: float, profile: int = 0,
           kinematics: str = "unicycle") -> None:  # fmt: skip
    setting = _setting(humans, seed, kinematics)
    rm = C.crowd_roadmap(setting)
    calls: list = []
    episodes: list = []
    current = [first]
    step = Navigator.step

    prof = cProfile.Profile(time.process_time) if profile else None

    def recorded(self, t, pose, obs, *args, **kwargs):
        if prof is not None:
            prof.enable()
        effort = getattr(getattr(self, "_effort", None), "level", 0)  # the level this call's searches run at
        traj = step(self, t, pose, obs, *args, **kwargs)
        if prof is not None:
            prof.disable()
        last = self.last
        calls.append({"episode": current[0], "t": float(t), "pose": [float(v) for v in pose], "mode": str(last.mode),
                      "message": last.message, "out_of_time": bool(last.out_of_time), "detailed": int(last.detailed),
                      "seconds": float(last.seconds), "effort": effort,
                      "hash": hashlib.sha1(np.ascontiguousarray(traj.waypoints).tobytes()).hexdigest()[:16]})  # fmt: skip
        return traj

    def save():
        doc = {"humans": humans, "seed": seed, "kinematics": kinematics, "time_budget": budget, "episodes": episodes,
               "calls": calls}  # fmt: skip
        write_atomic(out, json.dumps(doc))

    Navigator.step = recorded
    try:
        for i in range(first, stop):
            current[0] = i
            ep = C.run_episode(setting, rm, seed, i, ["navigator"], NavOptions(budget_clock="cpu", time_budget=budget))[0]
            episodes.append({"episode": i, "outcome": str(ep.outcome), "time": float(ep.time),
                             "min_separation": float(ep.min_separation)})  # fmt: skip
            print(i, ep.outcome, ep.time, flush=True)
            if (i - first) % 10 == 9:
                save()
    finally:
        Navigator.step = step
    save()
    if prof is not None:
        _print_profile(prof, profile, len(calls))


def _print_profile(prof, n: int, calls: int) -> None:
    stats = pstats.Stats(prof)
    rows = [(tt, ct, nc, f"{Path(f).name}:{line}({name})") for (f, line, name), (_, nc, tt, ct, _) in stats.stats.items()]
    for key, label in ((0, "own"), (1, "inclusive")):
        print(f"--- {calls} calls: the {n} costliest functions by {label} time (ms of CPU per call; calls per call)")
        for tt, ct, nc, where in sorted(rows, key=lambda r: -r[key])[:n]:
            print(f"{tt / calls * 1000:8.2f} {ct / calls * 1000:8.2f} {nc / calls:9.1f}  {where}")


def _load(path: str) -> dict:
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    doc["by"] = collections.defaultdict(list)
    for c in doc["calls"]:
        doc["by"][c["episode"]].append(c)
    return doc


def _summary(doc: dict, names=None) -> str:
    eps = [e for e in doc["episodes"] if names is None or e["episode"] in names]
    calls = [c for e in eps for c in doc["by"][e["episode"]]]
    ok = [e["time"] for e in eps if e["outcome"] == "success"]
    sec = np.array([c["seconds"] for c in calls]) * 1000
    modes = collections.Counter(c["mode"] for c in calls)
    mean = f"{np.mean(ok):.2f}" if ok else "-"
    return (f"n {len(eps)}, success {len(ok) / len(eps):.3f}, time {mean} s, replan CPU p50 / p95 "
            f"{np.percentile(sec, 50):.1f} / {np.percentile(sec, 95):.1f} ms, evasive {modes['evasive']} of {len(calls)}"
            f" ({sum(c['out_of_time'] for c in calls if c['mode'] == 'evasive')} out of time)")  # fmt: skip


def classify(path: str, oracle: bool) -> None:
    doc = _load(path)
    calls = doc["calls"]
    print(_summary(doc))
    print("answers:", dict(collections.Counter(c["mode"] for c in calls).most_common()))
    why = collections.Counter(c["message"].split(":")[0][:60] for c in calls if c["mode"] == "evasive")
    print("evasive, why:", dict(why.most_common()))
    lead = [next((i for i, c in enumerate(cs) if c["mode"] != "evasive"), len(cs)) for cs in doc["by"].values()]
    print(f"episodes whose first answer is evasive: {sum(x > 0 for x in lead)} of {len(lead)}; "
          f"4 or more in a row from the start: {sum(x >= 4 for x in lead)}")  # fmt: skip
    failed = [e for e in doc["episodes"] if e["outcome"] != "success"]
    setting = rm = None
    for e in failed:
        cs = doc["by"][e["episode"]]
        planned = [c for c in cs if c["mode"] in PLANS]
        print(f"episode {e['episode']}: {e['outcome']} at {cs[-1]['t'] + 0.25:.2f} s, smallest gap {e['min_separation']:.3f} m;"
              f" plans answered {len(planned)} of {len(cs)} calls, the last at {planned[-1]['t'] if planned else None}")  # fmt: skip
        for c in cs[-8:]:
            print(f"   {c['t']:6.2f} s {c['mode']:8s} {c['seconds'] * 1000:5.1f} ms  effort {c.get('effort', 0)}"
                  f"  {c['message'][:60]}")  # fmt: skip
        if oracle:
            if rm is None:
                setting = _setting(doc["humans"], doc["seed"], doc.get("kinematics", "unicycle"))
                rm = C.crowd_roadmap(setting)
            for dt in (None, 0.03):
                o = C.run_episode(setting, rm, doc["seed"], e["episode"], ["oracle"], oracle_dt=dt)[0]
                print(f"   oracle (dt {dt or 0.07}): {o.outcome}, {o.time} s, smallest gap {o.min_separation:.3f} m")


def compare(a_path: str, b_path: str) -> None:
    a, b = _load(a_path), _load(b_path)
    names = {e["episode"] for e in a["episodes"]} & {e["episode"] for e in b["episodes"]}
    same = total = 0
    for i in names:
        for x, y in zip(a["by"][i], b["by"][i], strict=False):
            total += 1
            same += x["hash"] == y["hash"]
            if x["hash"] != y["hash"]:
                break  # the runs part here: later calls start from other poses
    print(f"answers the same call by call until the runs part: {same} of {total} compared")
    print(f"{a_path}: {_summary(a, names)}")
    print(f"{b_path}: {_summary(b, names)}")
    ta = {e["episode"]: e["time"] for e in a["episodes"] if e["outcome"] == "success"}
    tb = {e["episode"]: e["time"] for e in b["episodes"] if e["outcome"] == "success"}
    both = sorted(set(ta) & set(tb) & names)
    d = np.array([tb[i] - ta[i] for i in both])
    if len(d):
        print(f"both arrive: {len(both)}, {np.mean([ta[i] for i in both]):.2f} -> {np.mean([tb[i] for i in both]):.2f} s "
              f"({d.mean():+.3f} +- {d.std() / np.sqrt(len(d)):.3f})")  # fmt: skip
    print("saved:", sorted(names & set(tb) - set(ta)), "lost:", sorted(names & set(ta) - set(tb)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record")
    r.add_argument("out")
    r.add_argument("--humans", type=int, default=5)
    r.add_argument("--seed", type=int, default=1)
    r.add_argument("--episodes", type=int, nargs=2, default=(0, 40), metavar=("FIRST", "STOP"))
    r.add_argument("--time-budget", type=float, default=0.1)
    r.add_argument("--profile", type=int, default=0, metavar="N")
    r.add_argument("--kinematics", choices=("unicycle", "holonomic"), default="unicycle")
    c = sub.add_parser("classify")
    c.add_argument("record")
    c.add_argument("--oracle", action="store_true")
    p = sub.add_parser("compare")
    p.add_argument("before")
    p.add_argument("after")
    args = ap.parse_args(argv)
    if args.cmd == "record":
        record(args.out, args.humans, args.seed, *args.episodes, args.time_budget, args.profile, args.kinematics)
    elif args.cmd == "classify":
        classify(args.record, args.oracle)
    else:
        compare(args.before, args.after)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
