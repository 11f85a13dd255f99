"""Table 1: roadmaps of 100..1000 vertices on building-floor, each extending the last.

One PRM is grown through 100, 200, ... 1000 vertices (``gfuzzy.roadmap.roadmap.grow_roadmaps``,
as ``tools/bench_plan.py`` does), and the scene's query is answered on each roadmap as a
batch on Dask (``gfuzzy.runs.batch``), ``REPEAT`` times per roadmap: the running time is the
median planning time (``PlanResult.planning_seconds``: the search and its graph; the
collision model is built once per worker and scene).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from gfuzzy.roadmap.roadmap import RoadmapOptions, grow_roadmaps
from gfuzzy.runs.batch import BatchOptions, run_batch, trajectory_path

from .common import (
    PAPER_198,
    PAPER_SECONDS,
    Context,
    bundled,
    fmt,
    linear_fit,
    load_doc,
    md_table,
    median,
)

SIZES = list(range(100, 1001, 100))
REPEAT = 3


def run(ctx: Context) -> str:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scene, _ = bundled("building-floor")
    roadmaps = grow_roadmaps(scene, SIZES, RoadmapOptions(seed=ctx.seed))
    q = scene.queries[0]
    named = []
    for rm in roadmaps:  # one scene name per size: the saved answers do not overwrite each other
        named.append((dataclasses.replace(scene, name=f"building-floor-n{len(rm.vertices)}"), rm))
    folder = ctx.scratch / "table1"
    res = run_batch(ctx.client, named * REPEAT, BatchOptions(trajectories=str(folder)))
    by = {}
    for row in res.rows:
        by.setdefault(row.scene, []).append(row)
    lines = []
    xs, ts, dfs = [], [], []
    for sc, rm in named:
        rows = by[sc.name]
        r0 = rows[0]
        n = len(rm.vertices)
        sec = median(r.planning_seconds for r in rows)
        length = None
        if r0.status == "solved":
            wp = np.asarray(load_doc(trajectory_path(folder, sc.name, q.name))["waypoints"])
            length = float(np.hypot(*np.diff(wp[:, 1:3], axis=0).T).sum())
        paper = PAPER_SECONDS.get(n)
        paper_txt = f"{paper:.2f} s" if paper is not None else ""
        if n == 200:
            paper_txt = (
                f"(198 vertices) {PAPER_198['seconds']:.2f} s, roadmap distance {PAPER_198['roadmap_distance']}, "
                f"path {PAPER_198['duration']}, delay factor {PAPER_198['delay_factor']}"
            )
        lines.append([n, len(rm.edges), fmt(r0.roadmap_distance), fmt(length), fmt(r0.duration),
                      fmt(r0.delay_factor, ".3f"), r0.status, fmt(sec * 1000 if sec else None, ".0f"),
                      paper_txt])  # fmt: skip
        if r0.status == "solved":
            xs.append(n)
            ts.append(sec)
            dfs.append(r0.delay_factor)
    a, b, r = linear_fit(xs, ts)
    ratio_ours = ts[-1] / ts[0]
    small = ""
    if ts[0] > ts[1]:
        small = (
            f"The 100-vertex query ({ts[0] * 1000:.0f} ms) is slower than the 200-vertex one "
            f"({ts[1] * 1000:.0f} ms): its answer waits longer (delay factor {dfs[0]:.2f}), and time "
            "grows with the delay factor (Figure 12). "
        )
    quality = _quality(xs, dfs, [float(r[4]) for r in lines if r[6] == "solved"])

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.8))
    ax1.plot(xs, [t * 1000 for t in ts], "o-", label="gfuzzy (this machine), ms")
    ax1.plot(list(PAPER_SECONDS), [v * 1000 for v in PAPER_SECONDS.values()], "s--", label="paper (3 GHz Pentium IV), ms")
    ax1.set_yscale("log")
    ax1.set_xlabel("roadmap vertices")
    ax1.set_ylabel("query time, ms (log)")
    ax1.legend(fontsize=8)
    ax1.grid(alpha=0.3)
    ax2.plot(xs, dfs, "o-", label="gfuzzy")
    ax2.plot([PAPER_198["vertices"]], [PAPER_198["delay_factor"]], "s", label="paper, 198 vertices")
    ax2.set_xlabel("roadmap vertices")
    ax2.set_ylabel("delay factor")
    ax2.legend(fontsize=8)
    ax2.grid(alpha=0.3)
    fig.suptitle("Table 1: building-floor, roadmaps grown 100 -> 1000 vertices")
    fig.tight_layout()
    ctx.img.mkdir(parents=True, exist_ok=True)
    fig.savefig(ctx.img / "table1.png", dpi=110)
    plt.close(fig)

    table = md_table(
        ["vertices", "edges", "roadmap distance", "path length m", "duration s", "delay factor", "status",
         "query ms (median of 3)", "paper"],  # fmt: skip
        lines,
    )
    return f"""## Table 1: roadmap size on the building floor

`python -m tools.experiments table1`. One PRM grown through 100, 200, ... 1000 vertices
(seed {ctx.seed}), each roadmap extending the previous one; the query `s-to-g` answered on
each as a Dask batch, {REPEAT} times (median planning time; the collision model is built
once per worker, as a kept `Planner` does). "duration" is the paper's path length in time
units; "path length" is the distance travelled in the plane.

{table}

![Table 1: query time and delay factor against roadmap size](img/table1.png)

What the figures say:

* **Time against size.** A straight line through our times (ms = {a * 1000:.1f} + {b * 1e6:.1f} x vertices / 1000)
  has Pearson r = {r:.3f}: roughly linear in the roadmap's size, as the paper's. From 100 to
  1000 vertices ours grows {ratio_ours:.1f}x, the paper's 11.8x (0.33 -> 3.90 s). {small}The
  search is A*-ordered and runs on a spanner of the roadmap, so it expands a corridor rather
  than the whole roadmap, and the graph it builds (every edge cut into one-step pieces) grows
  with the edges the spanner keeps.
* **Absolute time.** Ours is {min(ts) * 1000:.0f}-{max(ts) * 1000:.0f} ms against 330-3900 ms on a
  3 GHz Pentium IV. The machines are two decades apart and the implementations unrelated (ours is
  numpy + a Python search loop), and the scene is our reading of the paper's floor
  (see `scenes/building-floor.yaml`): the ratio says nothing precise about the methods.
* **Quality against size.** {quality}
  The paper's single figure, 2.22 at 198 vertices (35.14 time units over a 15.82 roadmap
  distance), is far above ours: our search returns the earliest arrival the graph and dt allow,
  and in our reading of the scene the movers block the corridor less (see the Figure 12 section:
  faster or differently moving movers push our delay factor up too).
"""


def _quality(xs, dfs, durations) -> str:
    """The delay-factor trend in words, from the figures (no claim the data does not make)."""
    i, j = int(np.argmin(dfs)), int(np.argmax(dfs))
    rest = [d for n, d in zip(xs, dfs, strict=True) if n >= 200]
    k = int(np.argmin(durations))
    text = (
        f"The delay factor is lowest at {xs[i]} vertices ({dfs[i]:.3f}) and highest at {xs[j]} "
        f"({dfs[j]:.3f}); the earliest arrival is on the {xs[k]}-vertex roadmap ({durations[k]:.2f} s)."
    )
    if rest and max(rest) - min(rest) < 0.05 * min(rest):
        text += (
            f" From 200 vertices on, every roadmap gives {min(rest):.2f}-{max(rest):.2f}: the one real "
            "step is from 100 to 200 vertices, where the sparse roadmap's corridor makes the robot wait "
            "or detour; beyond that the answer hardly changes while the time keeps growing, so the "
            "smallest adequate roadmap (about 200 vertices here) is the best trade."
        )
    else:
        text += " The delay factor does not settle as the roadmap grows: the corridor the search picks changes with the roadmap."
    return text
