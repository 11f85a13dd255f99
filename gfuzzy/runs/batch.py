"""Batch runs on Dask: every query of every scene, one row per query.

The client (this process) loads the scenes and builds or loads each scene's roadmap once;
each scene and its roadmap then become one task result that the workers fetch (once per
worker), and each query is one task that plans, checks its answer
(:func:`gfuzzy.check.check.check_trajectory`) and returns a :class:`QueryAnswer`: the row plus
the trajectory file. The client saves the trajectory files, so workers on other machines
need no shared folder.

A query whose task raises becomes a row with status ``error`` and the message; so does a
query that kills its worker (the scheduler gives up on it with ``KilledWorker``; it is run
again alone first, so that queries merely queued on the same worker are not blamed).
An interrupt (``KeyboardInterrupt`` in the client, or a SIGINT that
:func:`gfuzzy.errors.check_interrupt` raises again between results) stops the batch and returns the
rows finished so far, each complete. Under the command line's
:func:`gfuzzy.errors.interrupt_handling`, a local cluster starts and closes whole whenever
Ctrl-C comes; used from Python without it, a Ctrl-C may cut its start short (Python's own
``KeyboardInterrupt``). Either way its workers never see a terminal's Ctrl-C.

Planning is deterministic (``gfuzzy.plan`` uses no OMPL randomness, the GA takes its own
seed), so the rows are the same, timings aside, whatever the number of workers.
"""

from __future__ import annotations

import contextlib
import csv
import io
import logging
import math
import time
import traceback
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

from ..atomic import write_atomic, write_atomic_with
from ..errors import (
    InputError,
    LimitError,
    check_interrupt,
    clear_interrupt,
    interrupts_deferred,
    is_interrupt,
)
from ..planner.planner import PlanOptions
from ..roadmap.roadmap import Roadmap
from ..scene.scene import Scene

__all__ = [
    "BatchOptions",
    "BatchRow",
    "BatchResult",
    "COLUMNS",
    "check_time_steps",
    "close_whole",
    "closed_whole",
    "DASK_LOGGERS",
    "QueryAnswer",
    "local_cluster",
    "MAX_LOCAL_WORKERS",
    "quiet_dask_logs",
    "run_batch",
    "trajectory_path",
    "write_table",
]

log = logging.getLogger(__name__)

#: Environment of the local workers: one BLAS/OpenMP thread each, so K workers use K cores.
WORKER_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
#: Most worker processes of a local cluster (each holds the interpreter, numba and a
#: planner: a few hundred MB): ``--workers 100000`` set about starting them all.
MAX_LOCAL_WORKERS = 256
#: A task may be on a dying worker this many times before the scheduler gives it up
#: (Dask's default is 3). The local cluster gives up at once: :func:`run_batch` then runs
#: the query again alone, which tells the culprit from innocent queries queued beside it.
ALLOWED_FAILURES = 0
#: Dask's loggers, with the children Dask gives a level of their own (which wins over the
#: parent's): ``tornado.application`` logs a callback that failed, e.g. the ERROR and
#: traceback of Dask's own ``sync`` when Ctrl-C cuts a wait short before it began.
DASK_LOGGERS = ("distributed", "distributed.client", "tornado", "tornado.application")


@dataclass(frozen=True)
class BatchOptions:
    """Settings of a batch run.

    Attributes
    ----------
    plan : PlanOptions
        The options of every query.
    trajectories : str or None
        Folder where each answer is saved as ``<scene>-<query>.json`` (None: not saved).
    check : bool
        Check every solved answer against the contract's guarantees.
    """

    plan: PlanOptions = field(default_factory=PlanOptions)
    trajectories: str | None = None
    check: bool = True


@dataclass(frozen=True)
class BatchRow:
    """One query's outcome.

    ``status`` is a planner status (``solved``, ``no_path``, ``invalid_query``,
    ``timeout``) or ``error`` when the query failed to run (``error`` then says why).
    ``check`` is ``valid`` or ``invalid`` for a solved answer, ``""`` otherwise.
    ``traceback`` is the failure's traceback for an ``error`` row that is a bug (not an
    `InputError` or `LimitError`): kept for the terminal and the log, never a column of the table.
    """

    scene: str
    query: str
    status: str
    duration: float | None = None
    roadmap_distance: float | None = None
    delay_factor: float | None = None
    planning_seconds: float | None = None
    check: str = ""
    error: str = ""
    traceback: str = field(default="", repr=False)

    @property
    def ran(self) -> bool:
        return self.status != "error"


#: Column order of the results table.
COLUMNS = tuple(f.name for f in fields(BatchRow) if f.name != "traceback")


@dataclass(frozen=True)
class BatchResult:
    """The rows of a batch, in job order (scene order, then query order).

    Attributes
    ----------
    rows : list of BatchRow
        Only finished queries: all of them unless ``interrupted``.
    total : int
        Number of queries in the batch.
    interrupted : bool
        The run was stopped (KeyboardInterrupt) before every query finished.
    seconds : float
        Wall-clock time of the run (tasks submitted to last row).
    """

    rows: list[BatchRow]
    total: int
    interrupted: bool = False
    seconds: float = 0.0

    @property
    def errors(self) -> int:
        return sum(not r.ran for r in self.rows)


@dataclass(frozen=True)
class _Bundle:
    """What a worker needs for one scene; ``token`` keys the worker's planner cache."""

    token: str
    scene: Scene
    roadmap: Roadmap


@dataclass(frozen=True)
class QueryAnswer:
    """What one query's task returns: its row, and its trajectory file's contents
    (:meth:`gfuzzy.trajectory.TrajectoryFile.to_dict`; None for an error row)."""

    row: BatchRow
    trajectory: dict | None = None


def trajectory_path(folder: str | Path, scene: str, query: str) -> Path:
    """``folder/<scene>-<query>.json``."""
    return Path(folder) / f"{scene}-{query}.json"


# ------------------------------------------------------------------ the task (worker side)

_PLANNERS: dict = {}  # token -> Planner: a worker answers a scene's queries with one model
_PLANNER_CACHE = 4


def _planner(bundle: _Bundle):
    from ..planner.planner import Planner

    p = _PLANNERS.get(bundle.token)
    if p is None:
        if len(_PLANNERS) >= _PLANNER_CACHE:
            _PLANNERS.pop(next(iter(_PLANNERS)))
        p = _PLANNERS[bundle.token] = Planner(bundle.scene, bundle.roadmap)
    return p


def _num(v) -> float | None:
    return None if v is None or not math.isfinite(v) else float(v)


def run_query(
    bundle: _Bundle,
    query_index: int,
    options: BatchOptions,
    before: Callable[[str, str], None] | None = None,
) -> QueryAnswer:
    """Plan and check one query; never raises (a failure is an ``error`` row).

    ``before(scene_name, query_name)`` runs first: a hook for tests that inject faults.
    """
    from ..check.check import check_trajectory

    scene = bundle.scene
    q = scene.queries[query_index]
    try:
        if before is not None:
            before(scene.name, q.name)
        res = _planner(bundle).plan(q.start, q.goal, q.t0, options.plan, hold=q.hold)
        verdict = ""
        if res.solved and options.check:
            rep = check_trajectory(scene, res.trajectory.waypoints, q)
            verdict = "valid" if rep.valid else "invalid"
            if not rep.valid:
                log.warning("%s/%s: invalid answer: %s", scene.name, q.name, rep.reason)
        row = BatchRow(
            scene.name,
            q.name,
            res.status.value,
            _num(res.duration),
            _num(res.roadmap_distance),
            _num(res.delay_factor),
            float(res.planning_seconds),
            verdict,
        )
        return QueryAnswer(row, res.to_file(scene.name, q.name).to_dict())
    except Exception as exc:  # noqa: BLE001 - any failure of one query is its row, not the batch's
        return QueryAnswer(_error_row(scene.name, q.name, exc))


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _error_row(scene: str, query: str, exc: BaseException) -> BatchRow:
    """The ``error`` row of a query that raised ``exc``: a bug keeps its traceback."""
    tb = "" if isinstance(exc, (InputError, LimitError)) else "".join(traceback.format_exception(exc))
    if tb:
        log.error("%s/%s failed:\n%s", scene, query, tb.rstrip())
    return BatchRow(scene, query, "error", error=_one_line(exc), traceback=tb)


# ------------------------------------------------------------------ the client side


@contextlib.contextmanager
def local_cluster(workers: int, quiet: bool = True) -> Iterator[object]:
    """A ``distributed.Client`` on a new ``LocalCluster`` of ``workers`` processes.

    One thread per worker, BLAS/OpenMP pinned to one thread, no dashboard, and a query
    that kills its worker is given up at once (:data:`ALLOWED_FAILURES`). ``quiet`` keeps
    Dask's informational logs (cluster start and stop, a worker restarting) out of the
    terminal.
    """
    import dask
    from distributed import Client, LocalCluster

    if not 1 <= workers <= MAX_LOCAL_WORKERS:
        raise InputError(f"workers must be between 1 and {MAX_LOCAL_WORKERS}, got {workers}")
    env = dict(WORKER_ENV)
    if quiet:
        env["GFUZZY_BATCH_QUIET"] = "1"
    settings = {
        "distributed.nanny.pre-spawn-environ": env,
        "distributed.scheduler.allowed-failures": ALLOWED_FAILURES,
        "distributed.worker.preload": ["gfuzzy.runs.batch"],  # runs dask_setup in each worker
    }
    if quiet:
        settings["logging"] = {"distributed": "error", "tornado": "critical"}
    cluster = client = None
    with dask.config.set(settings), _quiet_logs(quiet):
        try:
            # no half-started cluster; a Ctrl-C meanwhile is raised as the section ends (the
            # cluster then closes), not held until the first task ends
            with interrupts_deferred(), _sigint_blocked():
                cluster = LocalCluster(
                    n_workers=workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    host="127.0.0.1",
                    # the scheduler serves HTTP (health, metrics) even without a dashboard, on
                    # port 8787 by default: a port the system picks never warns "Port 8787 is
                    # already in use" on the user's terminal when another cluster holds it
                    scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},
                )
                client = Client(cluster)
            yield client
        finally:
            close_whole(client, cluster)


@contextlib.contextmanager
def closed_whole(client) -> Iterator[object]:
    """``client``, closed on leaving by :func:`close_whole`, as :func:`local_cluster` closes its own."""
    try:
        yield client
    finally:
        close_whole(client)


def close_whole(*parts) -> None:
    """Close each of ``parts`` in order (a client, then its cluster; None is skipped), whole.

    The one place for "closed even under Ctrl-C": a SIGINT meanwhile (under
    :func:`gfuzzy.errors.interrupt_handling`) is only noted, and raised once every part is closed.
    """
    with interrupts_deferred():
        for part in parts:
            if part is not None:
                part.close()


@contextlib.contextmanager
def _sigint_blocked() -> Iterator[None]:
    """SIGINT blocked in this (the main) thread while a cluster starts.

    The threads Dask starts meanwhile (its event loop, each nanny's process starter) inherit
    the blocked signal, and so do the worker processes they spawn, then or when a nanny
    restarts one: a terminal's Ctrl-C, which reaches the whole process group, never reaches
    a worker, not even while it imports (before :func:`dask_setup` ignores it; it printed
    a traceback of the import it cut).

    The block does not hold the signal off this process's Python handler: a thread that was
    running before it (one of gfuzzy's native libraries') still takes a SIGINT, and Python
    then runs the handler in this thread at once. :func:`gfuzzy.errors.interrupts_deferred`
    around the start is what keeps it whole (only under
    :func:`gfuzzy.errors.interrupt_handling`); only when no thread takes the signal does it
    wait in the kernel until the block ends.
    """
    import signal
    import threading
    from multiprocessing import resource_tracker

    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # the tracker of the workers' semaphores, started now: started later, from this thread,
    # it would unblock SIGINT here when done (it blocks the signal while it spawns itself)
    resource_tracker.ensure_running()
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def dask_setup(worker) -> None:
    """Worker preload of :func:`local_cluster` (Dask calls it in each new worker process).

    Ctrl-C in a terminal reaches the whole process group: the workers ignore it, and the
    client, which owns the batch, stops it and closes them. With ``GFUZZY_BATCH_QUIET`` set,
    the worker's own Dask log lines (a task cancelled at shutdown) stay out of the terminal.
    """
    import os
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    if os.environ.get("GFUZZY_BATCH_QUIET"):
        quiet_dask_logs()


def quiet_dask_logs(errors: bool = False) -> dict[str, int]:
    """Dask's log lines kept out of the terminal: the one place that sets the levels of
    :data:`DASK_LOGGERS`.

    Every one goes to CRITICAL (tornado's callback errors too, see :data:`DASK_LOGGERS`),
    except that with ``errors`` Dask's own ERROR lines (``distributed``, e.g. a remote
    scheduler lost) still show. Returns the loggers' previous levels, to set back.
    """
    old = {n: logging.getLogger(n).level for n in DASK_LOGGERS}
    for n in DASK_LOGGERS:
        shown = errors and not n.startswith("tornado")
        logging.getLogger(n).setLevel(logging.ERROR if shown else logging.CRITICAL)
    return old


@contextlib.contextmanager
def _quiet_logs(quiet: bool):
    """:func:`quiet_dask_logs` (if ``quiet``) while the block runs, the old levels after."""
    if not quiet:
        yield
        return
    old = quiet_dask_logs()
    try:
        yield
    finally:
        for n, level in old.items():
            logging.getLogger(n).setLevel(level)


def check_time_steps(scenes: Sequence[tuple[Scene, Roadmap]], options: PlanOptions) -> None:
    """Refuse a ``dt`` too fine for a scene's roadmap once, in the client, before any query
    runs (:func:`gfuzzy.planner.prepared.check_time_step`): every query of the scene would
    fail alike, as one ``error`` row each.

    Raises
    ------
    TimeStepError
        Naming the scene file, as :func:`gfuzzy.runs.regress.regress_scene` does.
    """
    from .regress import check_scene_time_step

    for scene, roadmap in scenes:
        check_scene_time_step(scene, roadmap, options)


def run_batch(
    client,
    scenes: Sequence[tuple[Scene, Roadmap]],
    options: BatchOptions | None = None,
    progress: Callable[[int, int], None] | None = None,
    before: Callable[[str, str], None] | None = None,
) -> BatchResult:
    """Answer every query of every scene on a Dask cluster.

    Every query is first run in one concurrent round. A query whose worker died (Dask's
    ``KilledWorker``: it may be the culprit, or an innocent query that was queued on the
    same worker) is then run again *alone*; one that kills its worker alone too is an
    ``error`` row, the others get their real answer.

    Parameters
    ----------
    client : distributed.Client
    scenes : sequence of (Scene, Roadmap)
        Each roadmap built for its scene. Each pair is one task's result that the workers
        fetch from one another (once per worker), so a dead worker's copy is rebuilt
        from the task rather than lost.
    options : BatchOptions, optional
    progress : callable(done, total), optional
        Called in the client after each finished query (and once with 0 at the start).
    before : callable(scene_name, query_name), optional
        Run inside each task before planning (fault injection in tests; must be picklable).

    Raises
    ------
    TimeStepError
        ``options.plan.dt`` too fine for a scene's roadmap (:func:`check_time_steps`), before
        any query is submitted.

    Returns
    -------
    BatchResult
        Rows in job order. Saved trajectories (``options.trajectories``) are written by
        the client as rows arrive; an error row removes a stale file of that query.
    """
    options = options or BatchOptions()
    check_time_steps(scenes, options.plan)
    folder = Path(options.trajectories) if options.trajectories else None
    if folder is not None:
        folder.mkdir(parents=True, exist_ok=True)
    jobs = [(si, qi) for si, (scene, _) in enumerate(scenes) for qi in range(len(scene.queries))]
    bundles = [_Bundle(uuid.uuid4().hex, sc, rm) for sc, rm in scenes]
    total = len(jobs)
    rows: dict[int, BatchRow] = {}
    t0 = time.perf_counter()

    def record(j: int, row: BatchRow, doc: dict | None) -> None:
        with interrupts_deferred():  # a row and its trajectory file both, or neither
            if folder is not None:
                _save(folder, row, doc)
            rows[j] = row
        if progress is not None:
            progress(len(rows), total)

    if progress is not None:
        progress(0, total)
    interrupted = False
    try:
        check_interrupt()
        suspects = _round(client, bundles, jobs, range(total), options, before, record)
        for j in suspects:  # alone now: a query that still kills its worker is the culprit
            if _round(client, bundles, jobs, [j], options, before, record):
                si, qi = jobs[j]
                row = BatchRow(
                    scenes[si][0].name, scenes[si][0].queries[qi].name, "error", error=_KILLED
                )
                record(j, row, None)
    except BaseException as exc:  # noqa: BLE001 - Ctrl-C, however it surfaced (gfuzzy.errors.is_interrupt)
        if not is_interrupt(exc):
            raise
        interrupted = True
        clear_interrupt()
        log.info("interrupted: %d of %d queries finished", len(rows), total)
    return BatchResult(
        [rows[j] for j in sorted(rows)], total, interrupted, time.perf_counter() - t0
    )


_KILLED = "the worker died while running this query (a crash in native code, or killed)"


def _hold(bundle: _Bundle) -> _Bundle:
    return bundle


def _round(client, bundles, jobs, ids, options, before, record) -> list[int]:
    """Run the jobs ``ids`` concurrently; record each row; return the ids whose worker died."""
    from distributed import KilledWorker, as_completed

    futures = {}
    held = {}
    killed = []
    try:
        for j in ids:
            si, qi = jobs[j]
            if si not in held:
                held[si] = client.submit(
                    _hold, bundles[si], pure=False, key=f"gfuzzy-scene-{uuid.uuid4().hex}"
                )
            fut = client.submit(
                run_query,
                held[si],
                qi,
                options,
                before,
                key=f"gfuzzy-query-{j}-{uuid.uuid4().hex}",
                retries=0,
                pure=False,
            )
            futures[fut] = j
        for fut in as_completed(list(futures)):
            j = futures[fut]
            try:
                ans = fut.result()
                row, doc = ans.row, ans.trajectory
            except KilledWorker:
                killed.append(j)
                continue
            except Exception as exc:  # noqa: BLE001 - a lost cluster, a bad pickle: this query's row
                scene = bundles[jobs[j][0]].scene
                row, doc = _error_row(scene.name, scene.queries[jobs[j][1]].name, exc), None
            record(j, row, doc)
            check_interrupt()  # one that native code or a finaliser dropped stops here
    finally:
        with contextlib.suppress(Exception):
            client.cancel(list(futures) + list(held.values()))
    return sorted(killed)


def _save(folder: Path, row: BatchRow, doc: dict | None) -> None:
    import json

    from ..trajectory import _finite

    path = trajectory_path(folder, row.scene, row.query)
    if doc is None:
        path.unlink(missing_ok=True)  # no answer: never leave a previous run's file behind
        return
    write_atomic(path, json.dumps(_finite(doc), indent=1) + "\n")


# ------------------------------------------------------------------ the table


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v)
    return str(v)


def table_csv(rows: Sequence[BatchRow]) -> str:
    """The rows as CSV text with the header :data:`COLUMNS`."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(COLUMNS)
    for r in rows:
        w.writerow([_cell(getattr(r, c)) for c in COLUMNS])
    return buf.getvalue()


def write_table(
    rows: Sequence[BatchRow], path: str | Path, parquet: bool | None = None
) -> list[Path]:
    """Write the rows as CSV to ``path`` and, when pyarrow is importable (or ``parquet``
    is True), as Parquet beside it (same name, ``.parquet``); both atomically.

    Returns
    -------
    list of Path
        The files written.
    """
    path = Path(path)
    write_atomic(path, table_csv(rows))
    out = [path]
    if parquet is None:
        try:
            import pyarrow  # noqa: F401
        except ImportError:
            parquet = False
        else:
            parquet = True
    if parquet:
        import pyarrow as pa
        import pyarrow.parquet as pq

        cols = {c: [asdict(r)[c] for r in rows] for c in COLUMNS}
        types = {c: pa.float64() if c in _FLOAT_COLUMNS else pa.string() for c in COLUMNS}
        table = pa.table({c: pa.array(cols[c], type=types[c]) for c in COLUMNS})
        pq_path = path.with_suffix(".parquet")
        write_atomic_with(pq_path, lambda tmp: pq.write_table(table, tmp))
        out.append(pq_path)
    return out


_FLOAT_COLUMNS = ("duration", "roadmap_distance", "delay_factor", "planning_seconds")
