"""`gfuzzy batch` and gfuzzy.runs.batch: rows for every query on a real Dask cluster.

One LocalCluster of 2 worker processes serves the whole module; the CLI tests reach it
with --scheduler, so they also cover connecting to an existing cluster.
"""

from __future__ import annotations

import csv
import os
import sys
from pathlib import Path

import pytest
from shared_scenes import LOOP

from gfuzzy import load_scene, plan
from gfuzzy.cli import main
from gfuzzy.errors import LimitError
from gfuzzy.roadmap.roadmap import load_roadmap
from gfuzzy.runs.batch import (
    COLUMNS,
    BatchOptions,
    BatchResult,
    local_cluster,
    run_batch,
    table_csv,
    write_table,
)

ROOT = Path(__file__).resolve().parent.parent
SCENES = ["sim-4s1m", "sim-5s2m", "sealed-room", "wait-corridor"]

cloudpickle = pytest.importorskip("cloudpickle")
# the fault hooks below travel to the workers by value: they need not import this module
cloudpickle.register_pickle_by_value(sys.modules[__name__])


def raise_on_across(scene: str, query: str) -> None:
    if query == "across":
        raise RuntimeError("injected failure")


def limit_on_across(scene: str, query: str) -> None:
    if query == "across":
        raise LimitError("too many samples (injected)")


def exit_on_across(scene: str, query: str) -> None:
    if query == "across":
        os._exit(3)  # the worker process dies under the task, as on a native crash


@pytest.fixture(scope="module")
def client():
    with local_cluster(2) as c:
        yield c


@pytest.fixture(scope="module")
def pairs():
    out = []
    for name in SCENES:
        scene = load_scene(ROOT / "scenes" / f"{name}.yaml")
        out.append((scene, load_roadmap(ROOT / "roadmaps" / f"{name}.json", scene)))
    return out


def n_queries(pairs) -> int:
    return sum(len(s.queries) for s, _ in pairs)


def read_csv(path: Path) -> list[dict]:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def test_a_busy_port_8787_is_not_the_users_concern():
    # the scheduler's HTTP server took port 8787 even without a dashboard, and when another
    # cluster held it distributed warned on stderr "Port 8787 is already in use ..."
    import socket
    import warnings

    holder = socket.socket()
    try:
        holder.bind(("127.0.0.1", 8787))  # if another process holds it, so much the better
        holder.listen()
    except OSError:
        pass
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            with local_cluster(1):
                pass
    finally:
        holder.close()
    assert not [w for w in caught if "already in use" in str(w.message)]


def test_workers_run_one_blas_thread(client):
    env = client.run(lambda: {k: os.environ.get(k) for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")})
    assert len(env) == 2
    for values in env.values():
        assert values == {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
    assert all(v == 1 for v in client.nthreads().values())


def _sigint_ignored() -> bool:
    import signal

    return signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def test_workers_leave_ctrl_c_to_the_client(client):
    # Ctrl-C reaches the whole process group; only the client may act on it
    assert list(client.run(_sigint_ignored).values()) == [True, True]


def _sigint_blocked() -> bool:
    import signal

    return signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, [])


def test_workers_never_see_ctrl_c_not_even_while_they_start(client):
    # ignoring it in dask_setup came after the worker's imports: a Ctrl-C while a worker
    # started printed the traceback of the import it cut; blocked, it waits unseen
    assert list(client.run(_sigint_blocked).values()) == [True, True]


def test_a_quiet_cluster_keeps_tornados_callback_errors_out_of_the_terminal(client):
    # Ctrl-C while the client waited, before Dask's sync() had begun its wait: its cancel
    # callback failed (a NameError in distributed.utils.sync) and tornado.application, whose
    # own level (ERROR) won over the quiet parent's, printed the error and its traceback
    import logging

    assert not logging.getLogger("tornado.application").isEnabledFor(logging.ERROR)
    assert not logging.getLogger("distributed.client").isEnabledFor(logging.WARNING)


def test_quiet_dask_logs_sets_every_dask_logger_and_gives_the_old_levels_back():
    import logging

    from gfuzzy.runs.batch import DASK_LOGGERS, quiet_dask_logs

    before = {n: logging.getLogger(n).level for n in DASK_LOGGERS}
    try:
        assert quiet_dask_logs() == before
        assert {logging.getLogger(n).level for n in DASK_LOGGERS} == {logging.CRITICAL}
        quiet_dask_logs(errors=True)  # the command line's: Dask's own errors still show
        assert {n: logging.getLogger(n).level for n in DASK_LOGGERS} == {
            "distributed": logging.ERROR,
            "distributed.client": logging.ERROR,
            "tornado": logging.CRITICAL,
            "tornado.application": logging.CRITICAL,
        }
    finally:
        for n, level in before.items():
            logging.getLogger(n).setLevel(level)


def test_the_command_line_and_the_workers_quiet_dask_through_the_one_function(monkeypatch, tmp_path):
    # the levels were set in three places (cmd_batch, _quiet_logs, dask_setup), each a little
    # differently; now quiet_dask_logs is the only one
    import signal

    import gfuzzy.runs.batch as batch

    calls = []
    monkeypatch.setattr(batch, "quiet_dask_logs", lambda errors=False: calls.append(errors) or {})
    monkeypatch.setenv("GFUZZY_BATCH_QUIET", "1")
    handler = signal.getsignal(signal.SIGINT)
    try:
        batch.dask_setup(None)
    finally:
        signal.signal(signal.SIGINT, handler)
    with batch._quiet_logs(True):
        pass
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", "tcp://127.0.0.1:1",
                 "--connect-timeout", "0.2", "-o", str(tmp_path / "rows.csv")])  # fmt: skip
    assert code == 2  # nothing listens there; the levels were set before connecting
    assert calls == [False, False, True]


def test_rows_match_plan_and_saved_answers_check(client, pairs, tmp_path):
    res = run_batch(client, pairs, BatchOptions(trajectories=str(tmp_path / "traj")))
    assert not res.interrupted and res.errors == 0
    assert len(res.rows) == res.total == n_queries(pairs)
    # job order, and the very answers of an in-process plan (planning is deterministic)
    want = [(s, q) for s, _ in pairs for q in s.queries]
    assert [(r.scene, r.query) for r in res.rows] == [(s.name, q.name) for s, q in want]
    rm = {s.name: r for s, r in pairs}
    statuses = set()
    for row, (scene, q) in zip(res.rows, want, strict=True):
        ref = plan(scene, rm[scene.name], q.start, q.goal, q.t0)
        assert row.status == ref.status.value
        assert row.duration == ref.duration
        assert row.delay_factor == ref.delay_factor
        statuses.add(row.status)
        path = tmp_path / "traj" / f"{scene.name}-{q.name}.json"
        assert path.is_file()
        if row.status == "solved":
            assert row.check == "valid"
            src = ROOT / "scenes" / f"{scene.name}.yaml"
            assert main(["check", str(src), str(path)]) == 0
        else:
            assert row.check == ""
    assert {"solved", "no_path"} <= statuses  # sealed-room has an unreachable goal


def test_a_raising_query_is_an_error_row(client, pairs, tmp_path):
    folder = tmp_path / "traj"
    folder.mkdir()
    stale = folder / "sim-4s1m-across.json"
    stale.write_text("{}")
    res = run_batch(client, pairs[:2], BatchOptions(trajectories=str(folder)), before=raise_on_across)
    bad = [r for r in res.rows if r.status == "error"]
    assert [(r.scene, r.query) for r in bad] == [("sim-4s1m", "across")]
    assert "RuntimeError: injected failure" in bad[0].error
    # a bug keeps its traceback (naming the frame that raised), out of the one-line table
    assert "Traceback" in bad[0].traceback and "raise_on_across" in bad[0].traceback
    assert "traceback" not in COLUMNS and "\n" not in table_csv(bad).split("\n", 1)[1].rstrip()
    assert len(res.rows) == n_queries(pairs[:2])
    assert all(r.status == "solved" for r in res.rows if r.query != "across")
    assert not stale.exists()  # no answer: the previous run's file is gone


def test_a_query_beyond_the_memory_bounds_is_an_error_row_without_a_traceback(client, pairs):
    # a LimitError (a query's hold of 1e6 s: too many mover samples) is a request refused, as
    # an InputError is, not a bug: its traceback was printed on the terminal
    res = run_batch(client, pairs[:1], before=limit_on_across)
    (bad,) = [r for r in res.rows if r.status == "error"]
    assert bad.error == "LimitError: too many samples (injected)" and bad.traceback == ""


def test_a_killed_worker_is_an_error_row(client, pairs):
    res = run_batch(client, pairs[:2], before=exit_on_across)
    bad = [r for r in res.rows if r.status == "error"]
    assert [(r.scene, r.query) for r in bad] == [("sim-4s1m", "across")]
    assert "worker died" in bad[0].error
    assert len(res.rows) == n_queries(pairs[:2])
    assert all(r.status == "solved" for r in res.rows if r.query != "across")
    client.wait_for_workers(2, timeout=60)  # the nannies restart the dead workers


def test_interrupt_keeps_the_finished_rows(client, pairs, tmp_path):
    def progress(done, total):
        if done == 2:
            raise KeyboardInterrupt

    res = run_batch(client, pairs, progress=progress)
    assert res.interrupted
    assert len(res.rows) == 2 < res.total
    out = tmp_path / "partial.csv"
    write_table(res.rows, out, parquet=False)
    rows = read_csv(out)
    assert len(rows) == 2 and all(r["status"] in ("solved", "no_path") for r in rows)


def test_cli_batch_on_a_scheduler(client, tmp_path):
    out = tmp_path / "rows.csv"
    scenes = [ROOT / "scenes" / f"{n}.yaml" for n in SCENES[:3]]
    code = main(["batch", *map(str, scenes), "--scheduler", client.scheduler.address,
                 "-o", str(out), "--trajectories", str(tmp_path / "t")])  # fmt: skip
    assert code == 0
    rows = read_csv(out)
    assert list(rows[0]) == list(COLUMNS)
    assert len(rows) == sum(len(load_scene(p).queries) for p in scenes)
    for r in rows:
        path = tmp_path / "t" / f"{r['scene']}-{r['query']}.json"
        assert path.is_file()
        if r["status"] == "solved":
            assert r["check"] == "valid" and float(r["duration"]) > 0
            assert main(["check", str(ROOT / "scenes" / f"{r['scene']}.yaml"), str(path)]) == 0


def test_cli_exit_1_on_an_error_row(client, tmp_path, monkeypatch, capsys):
    import gfuzzy.runs.batch as batch

    real = batch.run_batch
    monkeypatch.setattr(batch, "run_batch", lambda *a, **k: real(*a, **k, before=raise_on_across))
    out = tmp_path / "rows.csv"
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler",
                 client.scheduler.address, "-o", str(out)])  # fmt: skip
    assert code == 1
    assert {r["query"]: r["status"] for r in read_csv(out)} == {"diagonal": "solved", "across": "error"}
    err = capsys.readouterr().err
    assert "across: error: RuntimeError: injected failure" in err
    assert "Traceback" in err and "raise_on_across" in err  # the bug shows where it happened


def _two_scenes_interrupted(client, tmp_path, monkeypatch, first_done):
    """``gfuzzy batch`` of two scenes on ``client`` with ``first_done()`` run when the first
    query is done (the progress callback): (the table's path, the exit status)."""
    import gfuzzy.cli.experiments as cli  # the module of cmd_batch

    def progress(label):
        def cb(done, total):
            if done == 1:
                first_done()

        return cb

    monkeypatch.setattr(cli, "_progress", progress)
    out = tmp_path / "rows.csv"
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), str(ROOT / "scenes" / "sim-5s2m.yaml"),
                 "--scheduler", client.scheduler.address, "-o", str(out)])  # fmt: skip
    return out, code


def test_cli_interrupt_writes_a_partial_table(client, tmp_path, monkeypatch, capsys):
    def first_done():
        raise KeyboardInterrupt

    out, code = _two_scenes_interrupted(client, tmp_path, monkeypatch, first_done)
    assert code == 130
    rows = read_csv(out)
    assert len(rows) == 1 and rows[0]["status"] == "solved"
    assert "interrupted" in capsys.readouterr().err


def _ctrl_c() -> None:
    """What a SIGINT does at this point: the handler in force runs."""
    import signal

    signal.getsignal(signal.SIGINT)(signal.SIGINT, None)


def test_cli_interrupt_while_the_cluster_starts_writes_the_empty_table(tmp_path, monkeypatch, capsys):
    # it left a half-started cluster (Dask's INFO lines as it was reaped at exit) and no table
    import distributed

    real = distributed.LocalCluster

    def starting(*args, **kwargs):
        _ctrl_c()
        return real(*args, **kwargs)

    monkeypatch.setattr(distributed, "LocalCluster", starting)
    out = tmp_path / "rows.csv"
    try:
        code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--workers", "1", "-o", str(out)])
    except KeyboardInterrupt:  # left to itself, it would stop the whole test session
        pytest.fail("a KeyboardInterrupt escaped main()")
    assert code == 130
    assert out.read_text().splitlines() == [",".join(COLUMNS)]
    assert f"interrupted: wrote the 0 finished of 2 queries to {out}" in capsys.readouterr().err


def test_cli_an_interrupt_native_code_drops_stops_the_batch(client, tmp_path, monkeypatch, capsys):
    # printed as "KeyboardInterrupt: " (an exception ignored in a finaliser or callback), it
    # was lost: the whole batch ran on and exited 0
    def first_done():
        try:
            _ctrl_c()
        except KeyboardInterrupt:
            pass

    out, code = _two_scenes_interrupted(client, tmp_path, monkeypatch, first_done)
    assert code == 130
    assert len(read_csv(out)) == 1
    assert capsys.readouterr().err.strip().startswith("interrupted: wrote the 1 finished of")


def test_cli_interrupt_while_the_client_closes_keeps_every_row(client, tmp_path, monkeypatch, capsys):
    # `--scheduler`: the Ctrl-C cut the client's closing and threw every finished row away
    # ("wrote the 0 finished of 2 queries", a header-only table beside 2 trajectory files)
    import distributed

    real = distributed.Client.close
    closing = []

    def close(self, *args, **kwargs):
        # the batch's own client only (another test's client, collected now, closes too)
        ours = self is not client and getattr(self.scheduler, "address", None) == client.scheduler.address
        if ours:
            monkeypatch.setattr(distributed.Client, "close", real)
            closing.append(self)
            _ctrl_c()
        return real(self, *args, **kwargs)

    monkeypatch.setattr(distributed.Client, "close", close)
    out, folder = tmp_path / "rows.csv", tmp_path / "t"
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", client.scheduler.address,
                 "-o", str(out), "--trajectories", str(folder)])  # fmt: skip
    assert code == 130
    rows = read_csv(out)
    assert len(rows) == 2
    assert sorted(p.name for p in folder.iterdir()) == sorted(f"{r['scene']}-{r['query']}.json" for r in rows)
    assert "interrupted: wrote the 2 finished of 2 queries" in capsys.readouterr().err
    assert closing[0].status == "closed"  # closed whole all the same


def test_cli_interrupt_while_the_table_is_written(client, tmp_path, monkeypatch, capsys):
    # noted while the CSV was written, then dropped: the batch said nothing of it and exited 0
    import gfuzzy.runs.batch as batch

    real = batch.table_csv

    def table_csv(rows):
        _ctrl_c()
        return real(rows)

    monkeypatch.setattr(batch, "table_csv", table_csv)
    out = tmp_path / "rows.csv"
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", client.scheduler.address,
                 "-o", str(out)])  # fmt: skip
    assert code == 130
    assert len(read_csv(out)) == 2  # written whole: the CSV, and the Parquet with it when pyarrow is here
    assert out.with_suffix(".parquet").exists() == _has_pyarrow()
    assert capsys.readouterr().err.strip() == f"interrupted: wrote the 2 finished of 2 queries to {_written(out)}"


def _has_pyarrow() -> bool:
    import importlib.util

    return importlib.util.find_spec("pyarrow") is not None


def _written(out: Path) -> str:
    return ", ".join(map(str, [out, *([out.with_suffix(".parquet")] if _has_pyarrow() else [])]))


def test_a_row_and_its_trajectory_file_are_recorded_together(client, pairs, tmp_path, monkeypatch):
    # a Ctrl-C right after a trajectory file was saved must not lose its row
    import gfuzzy.runs.batch as batch
    from gfuzzy.errors import interrupt_handling

    real = batch._save

    def save(folder, row, doc):
        real(folder, row, doc)
        monkeypatch.setattr(batch, "_save", real)
        _ctrl_c()

    monkeypatch.setattr(batch, "_save", save)
    folder = tmp_path / "t"
    with interrupt_handling():
        res = run_batch(client, pairs[:1], BatchOptions(trajectories=str(folder)))
    assert res.interrupted and len(res.rows) == 1
    assert [p.name for p in folder.iterdir()] == [f"{res.rows[0].scene}-{res.rows[0].query}.json"]


class _Closable:
    def __init__(self, closed: list, name: str, ctrl_c: bool = False):
        self.closed, self.name, self.ctrl_c = closed, name, ctrl_c

    def close(self) -> None:
        if self.ctrl_c:
            _ctrl_c()
        self.closed.append(self.name)


def test_close_whole_closes_every_part_then_raises_the_ctrl_c_that_came_meanwhile():
    from gfuzzy.errors import interrupt_handling
    from gfuzzy.runs.batch import close_whole

    closed: list = []
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        close_whole(_Closable(closed, "client", ctrl_c=True), None, _Closable(closed, "cluster"))
    assert closed == ["client", "cluster"]


def test_a_scheduler_client_is_closed_by_the_one_close_whole(monkeypatch):
    # local_cluster's deferred close and closed_whole were twins; both are close_whole now
    import gfuzzy.runs.batch as batch

    seen = []
    monkeypatch.setattr(batch, "close_whole", lambda *parts: seen.append(parts))
    client = _Closable([], "client")
    with batch.closed_whole(client) as c:
        assert c is client
    assert seen == [(client,)]


def test_a_ctrl_c_while_the_local_cluster_starts_lets_it_start_whole_then_stops(monkeypatch):
    # the Ctrl-C was held until the first task ended (`crowd --workers`: a whole episode);
    # without the deferral it cut the start and left a half-started cluster
    import distributed

    from gfuzzy.errors import interrupt_handling

    real = distributed.LocalCluster
    made, ran = [], []

    def starting(*args, **kwargs):
        _ctrl_c()
        made.append(real(*args, **kwargs))
        return made[-1]

    monkeypatch.setattr(distributed, "LocalCluster", starting)
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        with local_cluster(1):
            ran.append(1)
    assert not ran
    assert len(made) == 1 and made[0].status.name == "closed"


def test_a_ctrl_c_while_the_local_client_closes_still_closes_the_cluster(monkeypatch):
    import distributed

    from gfuzzy.errors import interrupt_handling

    real = distributed.Client.close
    seen = []

    def close(self, *args, **kwargs):
        monkeypatch.setattr(distributed.Client, "close", real)
        _ctrl_c()
        return real(self, *args, **kwargs)

    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        with local_cluster(1) as c:
            seen.append(c.cluster)
            monkeypatch.setattr(distributed.Client, "close", close)
    assert seen[0].status.name == "closed"


@pytest.mark.parametrize(
    "extra, message",
    [
        # named by the command, as every other command's options are (it began "--workers: ...")
        (["--workers", "0"], "gfuzzy batch: --workers must be at least 1 (local worker processes), got 0"),
        (["--workers", "1", "--scheduler", "tcp://127.0.0.1:1"], "not allowed with"),
        (["-o", "{tmp}/missing/rows.csv"], "does not exist"),
        (["-o", "{tmp}/rows.txt"], ".csv"),
        (["--trajectories", "{tmp}/no/such/dir"], "does not exist"),
    ],
)
def test_cli_bad_arguments(tmp_path, capsys, extra, message):
    extra = [e.format(tmp=tmp_path) for e in extra]
    if "-o" not in extra:
        extra += ["-o", str(tmp_path / "rows.csv")]
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), *extra])
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("scene, dt", [("sim-4s1m", "1e-9"), ("tb3-arena-unicycle", "1e-7")])
def test_cli_a_time_step_too_fine_is_refused_once_before_any_query(tmp_path, capsys, scene, dt):
    # it was one error row per query (a worker's TimeStepError) and exit 1, after the cluster
    # started; plan, regress and navigate name --dt in one line and exit 2
    path = ROOT / "scenes" / f"{scene}.yaml"
    code = main(["batch", str(path), "--dt", dt, "--workers", "1", "-o", str(tmp_path / "rows.csv")])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert err.startswith(f"gfuzzy batch: --dt {float(dt):g}: {path}: the time step is too fine for this roadmap"), err
    assert list(tmp_path.iterdir()) == []


def test_cli_bad_scene_names_file_and_place(tmp_path, capsys):
    bad = ROOT / "tests" / "bad_scenes" / "bad_mode.yaml"
    out = tmp_path / "rows.csv"
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), str(bad), "-o", str(out),
                 "--trajectories", str(tmp_path / "t")])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert "bad_mode.yaml" in err and "mode" in err and len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_two_scenes_of_one_name(tmp_path, capsys):
    scene = ROOT / "scenes" / "sim-4s1m.yaml"
    code = main(["batch", str(scene), str(scene), "-o", str(tmp_path / "rows.csv")])
    assert code == 2
    assert "repeats" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_parquet_beside_the_csv(tmp_path):
    pa = pytest.importorskip("pyarrow.parquet")
    from gfuzzy.runs.batch import BatchRow

    rows = [BatchRow("s", "q", "solved", 1.5, 1.0, 1.5, 0.1, "valid"), BatchRow("s", "r", "error", error="boom")]
    written = write_table(rows, tmp_path / "rows.csv")
    assert written == [tmp_path / "rows.csv", tmp_path / "rows.parquet"]
    table = pa.read_table(tmp_path / "rows.parquet").to_pylist()
    assert table[0]["duration"] == 1.5 and table[1]["duration"] is None and table[1]["error"] == "boom"


def test_cli_unreachable_scheduler(tmp_path, capsys):
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", "tcp://127.0.0.1:1",
                 "--connect-timeout", "1", "-o", str(tmp_path / "rows.csv")])  # fmt: skip
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert err.startswith("--scheduler tcp://127.0.0.1:1: cannot connect") and len(err.splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_cli_scheduler_address_that_is_not_dask(tmp_path, capsys):
    """Something that answers but does not speak Dask (an HTTP server, Dask's dashboard
    port): one line naming the option and exit 2. Before: a traceback (its reply read as a
    frame length, an exabyte to allocate) and exit 1."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    server.settimeout(10)

    def answer():
        try:
            while True:
                conn, _ = server.accept()
                with conn:
                    conn.settimeout(2)
                    try:
                        conn.recv(65536)
                    except OSError:
                        pass
                    conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4)
        except OSError:  # closed, or nobody came for 10 s
            return

    threading.Thread(target=answer, daemon=True).start()
    address = f"tcp://127.0.0.1:{server.getsockname()[1]}"
    try:
        code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", address,
                     "--connect-timeout", "3", "-o", str(tmp_path / "rows.csv")])  # fmt: skip
    finally:
        server.close()
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert err.startswith(f"--scheduler {address}: cannot connect") and len(err.splitlines()) == 1, err
    assert list(tmp_path.iterdir()) == []


class _RecordingClient:
    """A test double of ``distributed.Client``: notes the connection in ``events``, or
    refuses it like an unreachable scheduler."""

    def __init__(self, events: list, reachable: bool):
        self.events, self.reachable = events, reachable

    def __call__(self, address, timeout=None):
        self.events.append("connect")
        if not self.reachable:
            raise OSError(f"Timed out trying to connect to {address} after {timeout} s")
        return self

    def close(self):
        self.events.append("close")


@pytest.mark.parametrize("reachable", [False, True], ids=["unreachable", "reachable"])
def test_cli_connects_to_the_scheduler_before_any_roadmap(tmp_path, capsys, monkeypatch, reachable):
    """``--scheduler`` is connected to before a roadmap is built or loaded: an unreachable one
    is one line naming the option and exit 2, with no roadmap work. Before: every scene's
    roadmap was built first (a scene without a roadmap file: 3 s of building, then the
    refusal)."""
    import distributed

    import gfuzzy.cli.experiments as experiments
    import gfuzzy.runs.batch as batch

    events: list = []
    monkeypatch.setattr(distributed, "Client", _RecordingClient(events, reachable))
    monkeypatch.setattr(experiments, "_roadmap_for", lambda sc, args: events.append("roadmap"))
    monkeypatch.setattr(batch, "check_time_steps", lambda pairs, options: events.append("dt"))
    monkeypatch.setattr(batch, "run_batch", lambda client, pairs, *a, **k: events.append("run") or BatchResult([], 0))
    code = main(["batch", str(ROOT / "scenes" / "sim-4s1m.yaml"), "--scheduler", "tcp://10.255.255.1:8786",
                 "-o", str(tmp_path / "rows.csv")])  # fmt: skip
    err = capsys.readouterr().err.strip()
    if reachable:
        assert code == 0 and events == ["connect", "roadmap", "dt", "run", "close"], (events, err)
    else:
        assert code == 2 and events == ["connect"], events
        assert err.startswith("--scheduler tcp://10.255.255.1:8786: cannot connect") and len(err.splitlines()) == 1
        assert list(tmp_path.iterdir()) == []


def test_cli_passes_the_plan_options(client, tmp_path):
    from gfuzzy.planner.planner import PlanOptions

    out = tmp_path / "rows.csv"
    src = ROOT / "scenes" / "sim-5s2m.yaml"
    code = main(["batch", str(src), "--scheduler", client.scheduler.address, "-o", str(out),
                 "--refine", "--ga-seed", "3", "--dt", "0.05"])  # fmt: skip
    assert code == 0
    scene = load_scene(src)
    rm = load_roadmap(ROOT / "roadmaps" / "sim-5s2m.json", scene)
    opts = PlanOptions(refine=True, seed=3, dt=0.05)
    for row in read_csv(out):
        q = scene.query(row["query"])
        ref = plan(scene, rm, q.start, q.goal, q.t0, opts)
        assert row["status"] == ref.status.value
        assert float(row["duration"]) == ref.duration


def test_batch_keeps_each_querys_hold(client, tmp_path):
    import yaml

    from gfuzzy import build_roadmap, check_trajectory
    from gfuzzy.roadmap.roadmap import RoadmapOptions
    from gfuzzy.scene.scene import parse_scene

    scene = parse_scene(yaml.safe_load(LOOP))
    rm = build_roadmap(scene, RoadmapOptions(vertices=60, seed=1))
    res = run_batch(client, [(scene, rm)], BatchOptions(trajectories=str(tmp_path)))
    (row,) = res.rows
    q = scene.queries[0]
    held = plan(scene, rm, q.start, q.goal, hold=q.hold)
    assert row.status == "solved" and row.check == "valid"
    assert row.duration == held.duration
    assert row.duration > plan(scene, rm, q.start, q.goal).duration  # it waited to park safely
    from gfuzzy.trajectory import load_trajectory

    saved = load_trajectory(tmp_path / "loop-park.json")
    assert check_trajectory(scene, saved.waypoints, q).valid


def test_crowd_episodes_on_the_cluster_match_in_process(client):
    from gfuzzy.navigation import crowd as C

    setting = C.CrowdSetting(humans=4)
    rm = C.crowd_roadmap(setting)
    policies = ["oracle", "orca"]  # deterministic (the navigator's budget is wall-clock)
    here = C.episodes(setting, rm, 7, 2, policies)
    there = C.episodes(setting, rm, 7, 2, policies, client=client)
    assert len(there) == 2
    for a, b in zip(here, there, strict=True):
        for x, y in zip(a, b, strict=True):
            assert x.policy == y.policy and x.outcome == y.outcome and x.social == y.social
            assert x.time == y.time or (x.time != x.time and y.time != y.time)
            assert x.min_separation == y.min_separation
    assert here[0][0].time != here[1][0].time  # two different crowds
