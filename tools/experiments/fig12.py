"""Figure 12: 55 building-floor experiments varying the movers' speed and behaviour.

11 speeds (both movers) x 5 behaviours of the two movers of ``scenes/building-floor.yaml``:

* ``loop``: as in the scene file (A's H-shaped walk, B's rectangle, both cyclic);
* ``reverse``: the same loops walked the other way round;
* ``bounce``: back and forth along the same polylines;
* ``once``: each walks its loop once and parks where it started;
* ``offset``: the loops, A starting half a period ahead and B a quarter.

The 55 scene files are written to a scratch folder and answered as one Dask batch on the
scene's saved roadmap (their static content is the same, so the roadmap fits them all). The
paper plots running time against delay factor and calls the relation roughly linear; we fit
a line and report Pearson's r.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import yaml

from gfuzzy.runs.batch import BatchOptions, run_batch
from gfuzzy.scene.scene import load_scene

from .common import SCENES, bundled, fmt, linear_fit, md_table

SPEEDS = [0.25, 0.4, 0.55, 0.7, 0.85, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0]
BEHAVIOURS = ["loop", "reverse", "bounce", "once", "offset"]
#: Each experiment runs this many times; its running time is the median (the answers are
#: the same every time: planning is deterministic).
REPEAT = 3


def _medians(rows):
    """One row per scene: the first run's answer with the median planning time."""
    from dataclasses import replace
    from types import SimpleNamespace

    by: dict = {}
    for r in rows:
        by.setdefault(r.scene, []).append(r)
    out = []
    for group in by.values():
        if len({(g.status, g.duration) for g in group}) != 1:
            raise RuntimeError(f"{group[0].scene}: repeated runs gave different answers")
        out.append(replace(group[0], planning_seconds=float(np.median([g.planning_seconds for g in group]))))
    return SimpleNamespace(rows=out)


def _polyline_length(path, closed: bool) -> float:
    p = np.asarray(path, float)
    if closed:
        p = np.vstack([p, p[:1]])
    return float(np.hypot(*np.diff(p, axis=0).T).sum())


def variant(doc: dict, behaviour: str, speed: float) -> dict:
    """The building-floor scene document with its movers changed."""
    d = copy.deepcopy(doc)
    d["name"] = f"building-floor-{behaviour}-v{round(speed * 100):03d}"
    d["queries"] = [{k: v for k, v in doc["queries"][0].items() if k != "expect"}]
    for i, m in enumerate(d["movers"]):
        m["speed"] = speed
        if behaviour == "reverse":
            m["path"] = [m["path"][0]] + m["path"][1:][::-1]
        elif behaviour == "bounce":
            m["mode"] = behaviour
        elif behaviour == "once":  # one round of the loop, then parked where it started
            m["mode"] = "once"
            m["path"] = m["path"] + [m["path"][0]]
        elif behaviour == "offset":
            m["offset"] = round(_polyline_length(m["path"], True) * (0.5 if i == 0 else 0.25), 4)
    return d


def run(ctx):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, rm = bundled("building-floor")
    doc = yaml.safe_load((SCENES / "building-floor.yaml").read_text())
    folder = ctx.scratch / "fig12"
    folder.mkdir(parents=True, exist_ok=True)
    pairs, meta = [], {}
    for beh in BEHAVIOURS:
        for v in SPEEDS:
            d = variant(doc, beh, v)
            path = folder / f"{d['name']}.yaml"
            path.write_text(yaml.safe_dump(d, sort_keys=False))
            scene = load_scene(path)
            pairs.append((scene, rm))
            meta[scene.name] = (beh, v)
    batch = run_batch(ctx.client, pairs * REPEAT, BatchOptions())
    res = _medians(batch.rows)
    solved = [r for r in res.rows if r.status == "solved"]
    df = np.array([r.delay_factor for r in solved])
    ms = np.array([r.planning_seconds * 1000 for r in solved])
    a, b, r = linear_fit(df, ms)
    a_log, b_log, r_log = linear_fit(df, np.log(ms))
    rho = _spearman(df, ms)

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    markers = dict(zip(BEHAVIOURS, "osD^v", strict=True))
    for beh in BEHAVIOURS:
        pts = [(x.delay_factor, x.planning_seconds * 1000, meta[x.scene][1]) for x in solved if meta[x.scene][0] == beh]
        if pts:
            p = np.array(pts)
            sc = ax.scatter(p[:, 0], p[:, 1], c=p[:, 2], cmap="viridis", vmin=min(SPEEDS), vmax=max(SPEEDS),
                            marker=markers[beh], edgecolors="k", linewidths=0.4, label=beh)  # fmt: skip
    xs = np.linspace(df.min(), df.max(), 50)
    ax.plot(xs, a + b * xs, "k--", lw=1, label=f"least squares, r = {r:.2f}")
    fig.colorbar(sc, ax=ax, label="movers' speed")
    ax.set_xlabel("delay factor")
    ax.set_ylabel("running time, ms")
    ax.set_title(f"Figure 12: {len(res.rows)} building-floor experiments")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    ctx.img.mkdir(parents=True, exist_ok=True)
    fig.savefig(ctx.img / "fig12.png", dpi=110)
    plt.close(fig)

    per_beh = []
    for beh in BEHAVIOURS:
        rows = [x for x in res.rows if meta[x.scene][0] == beh]
        ok = [x for x in rows if x.status == "solved"]
        dfs = [x.delay_factor for x in ok]
        per_beh.append([beh, f"{len(ok)}/{len(rows)}",
                        f"{min(dfs):.2f}-{max(dfs):.2f}" if dfs else "-",
                        fmt(float(np.median([x.planning_seconds * 1000 for x in ok])) if ok else None, ".0f"),
                        ", ".join(f"{meta[x.scene][1]:g}: {x.status}" for x in rows if x.status != "solved") or "-"])  # fmt: skip
    per_speed = []
    for v in SPEEDS:
        rows = [x for x in solved if meta[x.scene][1] == v]
        per_speed.append([f"{v:g}", len(rows), fmt(float(np.mean([x.delay_factor for x in rows])) if rows else None, ".2f"),
                          fmt(float(np.mean([x.planning_seconds * 1000 for x in rows])) if rows else None, ".0f")])  # fmt: skip
    verdict = _verdict(r, rho, r_log)
    return f"""## Figure 12: running time against delay factor (55 experiments)

`python -m tools.experiments fig12`. The building floor's two movers at 11 speeds
({", ".join(f"{v:g}" for v in SPEEDS)}; the robot's vmax is 1) and in 5 behaviours (`loop` as in
the scene file; `reverse`: the loops the other way round; `bounce`: back and forth; `once`: one
round of the loop, then parked where it started; `offset`: the loops with A half a period and B a quarter ahead):
{len(res.rows)} scenes written to a scratch folder and answered as one Dask batch on the scene's
saved 200-vertex roadmap, each {REPEAT} times. {len(solved)} solved (the same answers each time);
running time is the median planning time of each experiment.

![Figure 12: running time against delay factor](img/fig12.png)

{md_table(["behaviour", "solved", "delay factors", "median ms", "not solved (speed: status)"], per_beh)}

{md_table(["movers' speed", "solved", "mean delay factor", "mean ms"], per_speed)}

The unsolved variants are answers, not failures of the run: in `once`, mover A ends its round
at its start (3.2, 2.5), right in front of the central passage P2, and stays there, so once it
is parked the only route is closed for good; only when the movers are slow does the robot get
through P2 before A parks. The `reverse` variants that are not solved have no safe trajectory
on the roadmap within the planning horizon, and an independent search agrees
(`python tools/check_reverse.py`): a breadth-first search over every (point, step) of the
whole roadmap, without safe intervals, heuristic or time windows, finds no way to the goal
within the same horizon at 1.6, 1.8 and 2. The verdict is the roadmap's: at 1.6 a
3000-vertex roadmap grown from the same seed solves it (20.93 s) while a 1000-vertex one
does not; at 1.8 and 2, where the movers are nearly twice as fast as the robot, neither does,
even with a 600 s horizon.

**Is time roughly linear in the delay factor?** Least squares over the {len(solved)} solved
experiments: ms = {a:.1f} + {b:.1f} x delay factor, Pearson r = {r:.2f} (Spearman rank correlation
{rho:.2f}; log(time) against delay factor: r = {r_log:.2f}). {verdict}
"""


def _spearman(x, y) -> float:
    rx = np.argsort(np.argsort(x))
    ry = np.argsort(np.argsort(y))
    return float(np.corrcoef(rx, ry)[0, 1])


def _verdict(r: float, rho: float, r_log: float) -> str:
    if not math.isfinite(r):
        return "Too few solved experiments to say."
    if round(r, 2) >= 0.8:
        return (
            "Yes: a later arrival costs proportionally more search, as the paper found, because the "
            "search must rule out every earlier arrival (it expands the time-space corridor up to the "
            "arrival time), and the movers' safety is computed over a longer window."
        )
    if round(r, 2) >= 0.5 or round(rho, 2) >= 0.5:
        return (
            "Only loosely: time grows with the delay factor (the search rules out every earlier "
            "arrival first), but the spread at equal delay factor is wide: the cost also depends on "
            "how many (point, time) pairs the movers make unsafe, which changes with their speed and "
            "paths, and timings on a shared 2-core machine are noisy at tens of milliseconds."
        )
    return (
        "No, not on our scene: the running time hardly follows the delay factor. Most of our query "
        "time is fixed cost (the graph, the movers' safety over the first time window), so a later "
        "arrival adds comparatively little, and timing noise on a shared machine at tens of "
        "milliseconds is of the same size as the trend."
    )
