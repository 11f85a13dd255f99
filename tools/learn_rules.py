"""Learn the fuzzy speed rule base by the three-stage self-organising GA (SOGARG).

Trains on the synthetic paths of gfuzzy.learning.tracking (S-curve, zig-zag, corner,
hairpin, arc) plus, when a planner and roadmaps are available, the paths it
plans on the bundled scenes; writes gfuzzy/data/rules_learned.txt and prints the
table, the cost per stage, and the training-set figures against the expert rules.

    python tools/learn_rules.py [--seed S] [--workers W] [--out FILE] [--quick]
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from bench_tracking import scene_paths  # tools/ is on sys.path when run as a script

from gfuzzy.fuzzy import fuzzy
from gfuzzy.learning import learn as sogarg
from gfuzzy.learning import tracking

ROOT = Path(__file__).resolve().parent.parent
TRAINING = ("s_curve", "zigzag", "corner", "hairpin", "arc")
CORNERS = (60, 120, 150)  # degrees: single corners that fill the input space


def corner(degrees: float, leg: float = 4.0):
    """Two legs of ``leg`` metres meeting at a left turn of ``degrees``."""
    a = np.radians(degrees)
    return np.array([[0.0, 0.0], [leg, 0.0], [leg + leg * np.cos(a), leg * np.sin(a)]])


def figures(rb, paths, limits):
    rows = []
    for p in paths:
        s, v = fuzzy.speed_limit(p, limits.vmax, limits.amax, rb)
        r = tracking.track(p, (s, v), limits)
        rows.append(
            (r.traversal_time, r.max_lateral_error, r.mean_lateral_error, r.violations.steps)
        )
    return [sum(col) / len(rows) for col in zip(*rows, strict=True)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=2007)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", type=Path, default=ROOT / "gfuzzy" / "data" / "rules_learned.txt")
    ap.add_argument("--quick", action="store_true", help="tiny run, for a smoke test")
    ap.add_argument("--no-scenes", action="store_true", help="synthetic paths only")
    args = ap.parse_args()

    synth = tracking.synthetic_paths()
    paths = [synth[k] for k in TRAINING]
    names = list(TRAINING)
    for deg in CORNERS:
        paths.append(corner(deg))
        names.append(f"corner_{deg}")
    if not args.no_scenes:
        for name, p in scene_paths(ROOT):
            paths.append(p)
            names.append(name)
    print(f"training paths: {', '.join(names)}")

    options = sogarg.LearnOptions()
    if args.quick:
        options = dataclasses.replace(options, population=6, generations=(1, 2, 1))
    limits = tracking.UnicycleLimits()
    sim = tracking.TrackingOptions()
    t0 = time.perf_counter()
    learn = functools.partial(
        sogarg.learn_rules,
        paths,
        options=options,
        limits=limits,
        tracking_options=sim,
        seed=args.seed,
    )
    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as pool:

            def map_fn(f, items):
                # Few large chunks: each task ships the training set to a worker.
                return pool.map(f, items, chunksize=max(1, len(items) // (2 * args.workers)))

            res = learn(map_fn=map_fn)
    else:
        res = learn()
    elapsed = time.perf_counter() - t0

    print(f"\nlearned in {elapsed:.1f} s, {res.evaluations} simulated rule bases, seed {args.seed}")
    for stage, hist in enumerate(res.history, start=1):
        print(
            f"  stage {stage}: cost {hist[0]:.4f} -> {hist[-1]:.4f} over {len(hist) - 1} generations"
        )
    print(f"\n{res.rulebase.n_rules} rules:\n{res.rulebase.table()}\n")
    print(f"{'training set (means)':<22}{'time s':>8}{'max err':>9}{'mean err':>9}{'viol':>6}")
    for label, rb in (("expert", fuzzy.expert_rules()), ("learned", res.rulebase)):
        t, emax, emean, viol = figures(rb, paths, limits)
        print(f"{label:<22}{t:>8.2f}{emax:>9.3f}{emean:>9.3f}{viol:>6.1f}")
    t, emax, emean, viol = [
        sum(col) / len(paths)
        for col in zip(
            *[
                (r.traversal_time, r.max_lateral_error, r.mean_lateral_error, r.violations.steps)
                for r in (tracking.track(p, None, limits) for p in paths)
            ],
            strict=True,
        )
    ]
    print(f"{'constant vmax':<22}{t:>8.2f}{emax:>9.3f}{emean:>9.3f}{viol:>6.1f}")

    comment = (
        f"Learned by tools/learn_rules.py (SOGARG, seed {args.seed}, "
        f"population {options.population}, generations {options.generations}) on: "
        + ", ".join(names)
        + f".\nFinal stage-3 cost {res.cost:.4f}."
    )
    if not args.quick:
        fuzzy.save_rules(res.rulebase, args.out, comment)
        print(f"\nwrote {args.out}")


if __name__ == "__main__":
    main()
