"""Ctrl-C on the command line (the Ctrl-C section of gfuzzy.errors): one line, exit 130,
no file, however the interrupt surfaces.

No real signal is sent: each test calls the SIGINT handler the command line installed
(``signal.getsignal``) at a chosen point, or raises what Python raises there, so every run
takes the same path.
"""

from __future__ import annotations

import importlib
import os
import signal
import sys

import pytest
from conftest import ROOT
from helpers import run_main

from gfuzzy.atomic import write_atomic, write_atomic_with
from gfuzzy.cli import main
from gfuzzy.errors import interrupt_handling, interrupt_pending, interrupts_deferred, is_interrupt
from gfuzzy.navigation.navigator import Navigator

SCENE = ROOT / "scenes" / "sim-4s1m.yaml"
ROADMAP = ROOT / "roadmaps" / "sim-4s1m.json"


def _ctrl_c() -> None:
    """What a SIGINT does at this point: the handler in force runs."""
    signal.getsignal(signal.SIGINT)(signal.SIGINT, None)


def _dropped_ctrl_c() -> None:
    """A SIGINT inside a callback from native code (FCL's distance callback, a ctypes
    callback): the ``KeyboardInterrupt`` is printed as "Exception ignored" and dropped."""
    try:
        _ctrl_c()
    except KeyboardInterrupt:
        pass


def _navigate(capsys, out):
    try:
        return run_main(capsys, "navigate", SCENE, "--roadmap", ROADMAP, "-o", out)
    except KeyboardInterrupt:  # left to itself, it would stop the whole test session
        pytest.fail("a KeyboardInterrupt escaped main()")


def _interrupted_once(rc, err, out) -> None:
    assert rc == 130
    assert err.strip() == "interrupted", err
    assert not out.exists()
    assert not list(out.parent.glob(f".{out.stem}*"))  # no temporary left either


def test_an_interrupt_inside_a_numba_kernel_is_one_line(tmp_path, capsys, monkeypatch):
    # a SIGINT while a numba (or AOT-compiled) kernel runs comes out as a SystemError whose
    # cause is the KeyboardInterrupt: it was a traceback and exit 1
    import gfuzzy.timespace.movers_kernel as kernels

    def interrupted_kernel(*args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher(<function safe_runs>) returned a result with an exception set") from exc

    monkeypatch.setattr(kernels, "safe_runs", interrupted_kernel)
    out = tmp_path / "nav.json"
    _interrupted_once(*_navigate(capsys, out)[::2], out)


def test_an_interrupt_that_native_code_drops_still_stops_the_command(tmp_path, capsys, monkeypatch):
    # the command ran on to the end, wrote its file and exited 0
    real = Navigator.step
    calls = []

    def step(self, *args, **kwargs):
        calls.append(1)
        if len(calls) == 2:
            _dropped_ctrl_c()
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Navigator, "step", step)
    out = tmp_path / "nav.json"
    _interrupted_once(*_navigate(capsys, out)[::2], out)
    assert len(calls) == 2  # stopped after the replan it came in, not at the end


def test_a_second_ctrl_c_while_saying_interrupted(tmp_path, capsys, monkeypatch):
    # `timeout -s INT` signals the command and then its whole process group: two SIGINTs,
    # the second while the first was being reported (a KeyboardInterrupt traceback)
    cli_main = importlib.import_module("gfuzzy.cli.main")  # the module, not gfuzzy.cli's main()

    def step(self, *args, **kwargs):
        _ctrl_c()

    real_say = cli_main._say

    def say(msg, stream=None):
        _ctrl_c()
        real_say(msg, stream)

    monkeypatch.setattr(Navigator, "step", step)
    monkeypatch.setattr(cli_main, "_say", say)
    out = tmp_path / "nav.json"
    _interrupted_once(*_navigate(capsys, out)[::2], out)


def test_a_ctrl_c_while_bad_input_is_said_adds_no_second_line(tmp_path, capsys, monkeypatch):
    # the command's last line was out (bad input, exit 2), then came "interrupted", exit 130
    cli_main = importlib.import_module("gfuzzy.cli.main")
    real_say = cli_main._say

    def say(msg, stream=None):
        _ctrl_c()
        real_say(msg, stream)

    monkeypatch.setattr(cli_main, "_say", say)
    missing = tmp_path / "missing.json"
    rc, _, err = run_main(capsys, "check", SCENE, missing)
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and str(missing) in err


def test_the_handling_is_the_callers_again_after_main(tmp_path, capsys):
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    run_main(capsys, "check", SCENE, tmp_path / "missing.json")
    assert (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)) == before
    assert not interrupt_pending()


def test_a_sigterm_stops_the_command_as_a_ctrl_c_does_with_its_own_line_and_status(tmp_path, capsys, monkeypatch):
    # a SIGTERM (kill, timeout, a scheduler) killed the process where it stood: an atomic
    # write's temporary stayed beside the output; now: one line, 143, no file, no temporary
    def step(self, *args, **kwargs):
        signal.getsignal(signal.SIGTERM)(signal.SIGTERM, None)

    monkeypatch.setattr(Navigator, "step", step)
    out = tmp_path / "nav.json"
    rc, _, err = _navigate(capsys, out)
    assert (rc, err.strip()) == (143, "terminated"), (rc, err)
    assert not out.exists() and not list(tmp_path.iterdir())
    # the next command starts afresh: a Ctrl-C is "interrupted", 130 again
    monkeypatch.setattr(Navigator, "step", lambda self, *a, **k: _ctrl_c())
    _interrupted_once(*_navigate(capsys, out)[::2], out)


def test_a_real_sigterm_during_a_roadmap_build_is_one_line(tmp_path):
    """The signal itself, sent to a real process while OMPL builds: no traceback, exit 143,
    neither the roadmap nor a temporary written."""
    import subprocess
    import time

    out = tmp_path / "rm.json"
    proc = subprocess.Popen([sys.executable, "-m", "gfuzzy", "roadmap", str(SCENE), "-n", "200000", "-o", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)  # fmt: skip
    time.sleep(4.0)  # past the imports (a SIGTERM before main takes over kills it, writing nothing)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err[-2000:]
    assert err.strip().splitlines()[-1] == "terminated" and "Traceback" not in err, err[-2000:]
    assert list(tmp_path.iterdir()) == []


def test_is_interrupt_follows_the_exception_chain():
    def chained(how: str) -> BaseException:
        try:
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as ki:
                if how == "cause":
                    raise SystemError("returned a result with an exception set") from ki
                raise SystemError("returned a result with an exception set")  # noqa: B904 - the context
        except SystemError as exc:
            return exc

    assert is_interrupt(KeyboardInterrupt())
    assert is_interrupt(chained("cause")) and is_interrupt(chained("context"))
    assert not is_interrupt(SystemError("a bug"))
    assert not is_interrupt(ValueError("a bug"))


def test_an_atomic_write_publishes_nothing_after_a_dropped_interrupt(tmp_path):
    out = tmp_path / "a.txt"
    with interrupt_handling():
        _dropped_ctrl_c()
        with pytest.raises(KeyboardInterrupt):
            write_atomic(out, "text\n")
        assert not list(tmp_path.iterdir())
        with pytest.raises(KeyboardInterrupt), interrupts_deferred():  # a section that must finish:
            write_atomic(out, "text\n")  # raised as it ends, not before
        assert out.read_text() == "text\n"
    write_atomic(out, "again\n")  # outside handling: nothing pending
    assert out.read_text() == "again\n"


# ------------------------------------------------------------------ deferred sections, repeated calls


def test_a_ctrl_c_in_a_deferred_section_is_raised_when_the_outermost_ends():
    # it was only noted: with no check_interrupt after, the command ran on and exited 0
    ran = []
    with interrupt_handling():
        with pytest.raises(KeyboardInterrupt):
            with interrupts_deferred():
                with interrupts_deferred():
                    _ctrl_c()
                    ran.append("inner")
                ran.append("outer")  # the inner section's end does not cut the outer one
            ran.append("after")
        assert ran == ["inner", "outer"]
        with interrupts_deferred(raise_after=False):  # a command's last line: nothing after it
            _ctrl_c()
    assert not interrupt_pending()


def test_any_exception_after_a_ctrl_c_counts_as_the_interrupt():
    # a half-built object failing after the interrupt cut it short is not a bug to show
    with interrupt_handling():
        assert not is_interrupt(RuntimeError("a bug"))
        _dropped_ctrl_c()
        assert is_interrupt(RuntimeError("a half-built object"))
    assert not is_interrupt(RuntimeError("a bug"))


class _Unraisable:
    def __init__(self, exc):
        self.exc_value, self.exc_type, self.exc_traceback = exc, type(exc), None
        self.err_msg, self.object = "Exception ignored in", None


def test_the_noise_an_interrupt_leaves_is_not_printed(monkeypatch):
    shown = []  # what Python's own hooks would have printed
    monkeypatch.setattr(sys, "unraisablehook", lambda u: shown.append(u.exc_value))
    monkeypatch.setattr(sys, "excepthook", lambda kind, value, tb: shown.append(value))
    bug = RuntimeError("a finaliser's own bug")
    with interrupt_handling():
        sys.unraisablehook(_Unraisable(bug))
        assert shown == [bug]  # not an interrupt: shown
        sys.unraisablehook(_Unraisable(KeyboardInterrupt()))  # a callback dropped it
        assert interrupt_pending()
        sys.unraisablehook(_Unraisable(RuntimeError("its aftermath")))
    with interrupt_handling():
        sys.excepthook(SystemError, _caused_by(KeyboardInterrupt()), None)  # printed by Cython, then dropped
        assert interrupt_pending()
    assert shown == [bug]


def _caused_by(ki: KeyboardInterrupt) -> SystemError:
    exc = SystemError("returned a result with an exception set")
    exc.__cause__ = ki
    return exc


@pytest.fixture
def own_command_line(monkeypatch):
    """``main()`` as the program's own entry point (argv None) leaves SIGINT ignored and its
    quiet hooks installed: give the test session its own back."""
    saved = (signal.getsignal(signal.SIGINT), sys.unraisablehook, sys.excepthook)
    yield lambda *args: (monkeypatch.setattr(sys, "argv", ["gfuzzy", *map(str, args)]), main())[1]
    signal.signal(signal.SIGINT, saved[0])
    sys.unraisablehook, sys.excepthook = saved[1], saved[2]


def test_the_own_command_line_ignores_ctrl_c_once_the_command_is_over(tmp_path, own_command_line):
    assert own_command_line("check", SCENE, tmp_path / "missing.json") == 2
    assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN


def test_a_second_call_of_main_starts_afresh(tmp_path, capsys, monkeypatch, own_command_line):
    # a Ctrl-C during the first call (argv None) was still pending in the second, which had
    # none: "interrupted", exit 130
    cli_main = importlib.import_module("gfuzzy.cli.main")
    real_say = cli_main._say

    def say(msg, stream=None):
        monkeypatch.setattr(cli_main, "_say", real_say)
        _ctrl_c()
        real_say(msg, stream)

    monkeypatch.setattr(cli_main, "_say", say)
    assert own_command_line("check", SCENE, tmp_path / "missing.json") == 2
    assert not interrupt_pending()
    out = tmp_path / "p.json"
    assert own_command_line("plan", SCENE, "--roadmap", ROADMAP, "-o", out) == 0
    assert out.is_file() and "interrupted" not in capsys.readouterr().err


# ------------------------------------------------------------------ pairs of files


def test_plan_finishes_its_json_and_csv_then_stops(tmp_path, capsys, monkeypatch):
    # the Ctrl-C that came while the JSON was written was noted and then dropped: exit 0
    from gfuzzy.trajectory import TrajectoryFile

    real = TrajectoryFile.save

    def save(self, path):
        monkeypatch.setattr(TrajectoryFile, "save", real)
        _ctrl_c()
        return real(self, path)

    monkeypatch.setattr(TrajectoryFile, "save", save)
    out = tmp_path / "p.csv"
    rc, _, err = run_main(capsys, "plan", SCENE, "--roadmap", ROADMAP, "-o", out)
    assert rc == 130 and err.strip().splitlines()[-1] == "interrupted"
    assert out.is_file() and out.with_suffix(".json").is_file()  # both, not one


def test_the_map_export_publishes_its_image_and_yaml_both(tmp_path, monkeypatch):
    # a Ctrl-C between the two renames left the new image beside the old YAML
    from gfuzzy import load_scene
    from gfuzzy.export.mapexport import export_nav2_map

    scene = load_scene(SCENE)
    yaml_path = tmp_path / "m.yaml"
    export_nav2_map(scene, yaml_path, 0.1)
    real = os.replace
    done = []

    def replace(a, b):
        real(a, b)
        done.append(b)
        if len(done) == 1:
            _ctrl_c()

    monkeypatch.setattr(os, "replace", replace)
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        export_nav2_map(scene, yaml_path, 0.05)
    monkeypatch.setattr(os, "replace", real)
    fresh = tmp_path / "fresh" / "m.yaml"
    export_nav2_map(scene, fresh, 0.05)
    assert yaml_path.read_text() == fresh.read_text()
    assert (tmp_path / "m.pgm").read_bytes() == fresh.with_suffix(".pgm").read_bytes()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fresh", "m.pgm", "m.yaml"]


def test_the_map_export_stops_before_publishing_after_a_dropped_interrupt(tmp_path, monkeypatch):
    import gfuzzy.export.mapexport as mapexport
    from gfuzzy import load_scene

    real = mapexport.rasterise

    def rasterise(*args):
        _dropped_ctrl_c()
        return real(*args)

    monkeypatch.setattr(mapexport, "rasterise", rasterise)
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        mapexport.export_nav2_map(load_scene(SCENE), tmp_path / "m.yaml", 0.1)
    assert not list(tmp_path.iterdir())


def test_a_second_ctrl_c_while_a_failed_write_cleans_up_leaves_no_temporary(tmp_path, monkeypatch):
    real = os.unlink

    def unlink(path, *args, **kwargs):
        monkeypatch.setattr(os, "unlink", real)
        _ctrl_c()  # the second SIGINT, as the cleanup starts
        real(path, *args, **kwargs)

    def write(tmp):
        open(tmp, "w").write("half")
        monkeypatch.setattr(os, "unlink", unlink)
        _ctrl_c()  # the first, mid-write

    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        write_atomic_with(tmp_path / "out.json", write)
    assert not list(tmp_path.iterdir())


def test_regress_stops_between_queries_after_a_dropped_interrupt(monkeypatch):
    from gfuzzy import load_scene
    from gfuzzy.planner.planner import Planner
    from gfuzzy.roadmap.roadmap import load_roadmap
    from gfuzzy.runs.regress import regress_scene

    scene = load_scene(SCENE)
    assert len(scene.queries) > 1
    real = Planner.plan
    calls = []

    def plan(self, *args, **kwargs):
        calls.append(1)
        _dropped_ctrl_c()
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Planner, "plan", plan)
    with interrupt_handling(), pytest.raises(KeyboardInterrupt):
        regress_scene(scene, load_roadmap(ROADMAP, scene))
    assert len(calls) == 1


_SLOW_IMPORT = '''
import builtins
import os
import signal

_real = builtins.__import__


def _importing(name, *args, **kwargs):
    if name == os.environ["CUT_AT"] and not _importing.done:  # a Ctrl-C as it is imported
        _importing.done = True
        signal.getsignal(signal.SIGINT)(signal.SIGINT, None)
    return _real(name, *args, **kwargs)


_importing.done = False
builtins.__import__ = _importing
'''


def _entry_points() -> dict[str, list[str]]:
    """The two ways to run the program: pyproject's console script and ``python -m gfuzzy``."""
    import tomllib

    with open(ROOT / "pyproject.toml", "rb") as fh:
        module, func = tomllib.load(fh)["project"]["scripts"]["gfuzzy"].split(":")
    script = f"import sys; from {module} import {func}; sys.exit({func}())"  # what pip's script runs
    return {"console script": ["-c", script], "python -m": ["-m", "gfuzzy"]}


def _sigint_default() -> None:
    """The child starts with SIGINT at its default, as from a terminal: a suite started in the
    background of a shell without job control (``make test &`` in a script) passes SIGINT on
    ignored, and Python then installs no handler of its own (``getsignal`` gives SIG_IGN)."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


@pytest.mark.parametrize("cut_at", ["errors", "argparse", "numpy"])
@pytest.mark.parametrize("entry", ["console script", "python -m"])
def test_a_ctrl_c_while_gfuzzy_imports_is_one_line(tmp_path, entry, cut_at):
    # the first half second of every command (numpy, FCL, OMPL imported) was Python's own:
    # a KeyboardInterrupt traceback. A sitecustomize of this test's runs the SIGINT handler
    # in force as the entry's own first import (gfuzzy.errors: it was before run()'s try),
    # the command line's first (argparse, before main takes the signal: a console script of
    # gfuzzy.cli:main fails here) or numpy's (inside main's handling) begins
    import subprocess

    (tmp_path / "sitecustomize.py").write_text(_SLOW_IMPORT)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(tmp_path), str(ROOT)]), CUT_AT=cut_at)
    out = tmp_path / "x.json"
    run = subprocess.run(
        [sys.executable, *_entry_points()[entry], "plan", str(SCENE), "--roadmap", str(ROADMAP), "-o", str(out)],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, preexec_fn=_sigint_default,
    )  # fmt: skip
    _interrupted_once(run.returncode, run.stderr, out)


def test_an_import_error_an_interrupt_caused_is_the_one_line_too(monkeypatch, capsys):
    # an extension whose init a Ctrl-C cut short raises its own error, caused by the interrupt
    import builtins

    import gfuzzy.__main__ as entry

    real = builtins.__import__

    def importing(name, *args, **kwargs):
        if name == "cli.main":  # run()'s `from .cli.main import main`
            try:
                raise KeyboardInterrupt
            except KeyboardInterrupt as exc:
                raise ImportError("initialization of an extension cut short") from exc
        return real(name, *args, **kwargs)

    handler = signal.getsignal(signal.SIGINT)
    monkeypatch.setattr(builtins, "__import__", importing)
    try:
        assert entry.run() == 130
    finally:
        signal.signal(signal.SIGINT, handler)
    assert capsys.readouterr().err == "interrupted\n"


def test_the_entry_point_lets_any_other_error_through(monkeypatch):
    import gfuzzy.__main__ as entry

    monkeypatch.setattr(sys.modules["gfuzzy.cli.main"], "main", lambda: 1 / 0)
    with pytest.raises(ZeroDivisionError):
        entry.run()
