"""Ctrl-C on the command line (the Ctrl-C section of gfuzzy.errors): one line, exit 130,
no file, however the interrupt surfaces.

No real signal is sent: each test calls the SIGINT handler the command line installed
(``signal.getsignal``) at a chosen point, or raises what Python raises there, so every run
takes the same path.
"""

from __future__ import annotations

import importlib
import signal

import pytest
from conftest import ROOT
from helpers import run_main

from gfuzzy.atomic import write_atomic
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
    before = signal.getsignal(signal.SIGINT)
    run_main(capsys, "check", SCENE, tmp_path / "missing.json")
    assert signal.getsignal(signal.SIGINT) is before
    assert not interrupt_pending()


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
        with interrupts_deferred():  # a section that must finish: noted, not raised
            write_atomic(out, "text\n")
    assert out.read_text() == "text\n"
    write_atomic(out, "again\n")  # outside handling: nothing pending
    assert out.read_text() == "again\n"
