"""Scene-file regression runs: answer every query, check every answer, test every ``expect``."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TextIO

from ..check.check import check_trajectory
from ..errors import LimitError, TimeStepError, check_interrupt
from ..planner.planner import Planner, PlanOptions
from ..scene.scene import Query, Scene
from ..status import Status

__all__ = ["RegressionRow", "check_scene_time_step", "regress_scene", "run_regression"]


@dataclass(frozen=True)
class RegressionRow:
    """One query's outcome in a regression run."""

    scene: str
    query: str
    status: str
    duration: float | None
    delay_factor: float | None
    seconds: float
    valid: bool | None  # None: nothing to check
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems


def _expectation_problems(query: Query, status: str, duration, delay) -> list[str]:
    out = []
    exp = query.expect
    if exp is None:
        return out
    if exp.status is not None and status != exp.status:
        out.append(f"status {status}, expected {exp.status}")
    if exp.max_duration is not None and status == Status.SOLVED and duration > exp.max_duration + 1e-9:
        out.append(f"duration {duration:.3f} > max {exp.max_duration:g}")
    if exp.max_delay_factor is not None and status == Status.SOLVED and delay > exp.max_delay_factor + 1e-9:
        out.append(f"delay factor {delay:.3f} > max {exp.max_delay_factor:g}")
    return out


def check_scene_time_step(scene: Scene, roadmap, options: PlanOptions | None) -> None:
    """Refuse a ``dt`` too fine for ``scene``'s roadmap before any of its queries runs
    (:func:`gfuzzy.planner.prepared.check_time_step`): a :class:`~gfuzzy.errors.TimeStepError`
    naming the scene file, as one of its queries would."""
    from ..planner.prepared import check_time_step

    try:
        check_time_step(scene.robot, roadmap, options or PlanOptions())
    except TimeStepError as exc:
        raise TimeStepError(f"{scene.source}: {exc}") from None


def regress_scene(scene: Scene, roadmap, options: PlanOptions | None = None) -> list[RegressionRow]:
    """Answer and check every query of ``scene``.

    A query beyond the memory bounds raises :class:`~gfuzzy.errors.LimitError` naming the
    scene file and the query (a :class:`~gfuzzy.errors.TimeStepError`, the same for every
    query, names the scene file only). A solved answer must pass :func:`gfuzzy.check.check.check_trajectory` (with the query's
    start, goal and t0), and every answer must meet the query's ``expect`` block.
    """
    check_scene_time_step(scene, roadmap, options)
    planner = Planner(scene, roadmap)
    rows = []
    for i, q in enumerate(scene.queries):
        check_interrupt()  # a Ctrl-C native code dropped stops the run between queries
        try:
            res = planner.plan(q.start, q.goal, q.t0, options, hold=q.hold)
        except TimeStepError as exc:  # dt's, for every query alike: the scene, not a query
            raise TimeStepError(f"{scene.source}: {exc}") from None
        except LimitError as exc:  # which of many scenes and queries asked too much (a hold of 1e6 s)
            raise LimitError(f"{scene.source}: queries[{i}] ({q.name}): {exc}") from None
        problems = []
        valid = None
        if res.solved:
            rep = check_trajectory(scene, res.trajectory.waypoints, q)
            valid = rep.valid
            if not rep.valid:
                problems.append(f"invalid: {rep.reason}")
        problems += _expectation_problems(q, res.status.value, res.duration, res.delay_factor)
        rows.append(
            RegressionRow(
                scene.name,
                q.name,
                res.status.value,
                res.duration,
                res.delay_factor,
                res.planning_seconds,
                valid,
                tuple(problems),
            )
        )
    return rows


def format_row(row: RegressionRow) -> str:
    def num(v, fmt):
        return "-" if v is None or not math.isfinite(v) else format(v, fmt)

    check = {True: "valid", False: "INVALID", None: "-"}[row.valid]
    verdict = "ok" if row.ok else "FAIL: " + "; ".join(row.problems)
    return (
        f"{row.scene:<22} {row.query:<16} {row.status:<13} {num(row.duration, '8.2f'):>8} "
        f"{num(row.delay_factor, '6.3f'):>6} {row.seconds * 1000:8.0f} {check:<7} {verdict}"
    )


HEADER = f"{'scene':<22} {'query':<16} {'status':<13} {'duration':>8} {'delay':>6} {'ms':>8} {'check':<7} verdict"


def run_regression(
    scenes: Iterable[Scene],
    roadmap_for: Callable[[Scene], object],
    options: PlanOptions | None,
    out: TextIO,
) -> bool:
    """Run every scene, print one row per query to ``out``; True when all met. A scene
    without queries gets one line saying so, and no roadmap (``roadmap_for`` is not asked).
    The header comes once the first scene's ``dt`` is known to fit its roadmap: a ``dt`` too
    fine prints nothing before its error (:func:`check_scene_time_step`)."""
    header = [HEADER]

    def say(line: str) -> None:
        if header:
            out.write(header.pop() + "\n")
        out.write(line + "\n")

    all_ok = True
    n = failed = 0
    for scene in scenes:
        if not scene.queries:
            say(f"{scene.name:<22} (no queries: nothing answered, no roadmap built or loaded)")
            continue
        roadmap = roadmap_for(scene)
        check_scene_time_step(scene, roadmap, options)
        if header:  # the first scene's dt fits: the table starts now, before its queries run
            out.write(header.pop() + "\n")
            out.flush()
        for row in regress_scene(scene, roadmap, options):
            say(format_row(row))
            out.flush()
            n += 1
            if not row.ok:
                failed += 1
                all_ok = False
    say(f"{n - failed} of {n} queries met their expectations")
    return all_ok
