"""Exception families.

Three kinds of failure, kept apart so that a bug is never blamed on the user:

* *bad input* raises :class:`InputError` (bad options, poses, command-line values) or
  its subclass :class:`SceneError` (a file, naming the file and the place in it);
* *a request beyond the memory bounds* (a time step far too fine for the scene) raises
  :class:`LimitError`;
* *no solution* is never an exception but a status on the result
  (:class:`gfuzzy.status.Status`).

Both exception families are ``ValueError`` subclasses, so code written against the
older API (``except ValueError``) still catches them. The command line turns these two
families, and only these, into one line on stderr and exit status 2; any other exception
is a bug and shows its traceback.

Ctrl-C on the command line is the fourth kind: one line, exit 130, nothing half-written,
whenever it comes (the section at the end of this module); a SIGTERM the same, exit 143.
"""

from __future__ import annotations

import contextlib
import math
import numbers
import signal
import sys
import threading
from collections.abc import Iterator

from .settings import MAX_MAGNITUDE


class GfuzzyError(Exception):
    """Base class of every error gfuzzy raises on purpose."""


class InputError(GfuzzyError, ValueError):
    """Bad input that is not a file: an option, a pose, a value on the command line."""


class LimitError(GfuzzyError, ValueError):
    """A request the memory bounds refuse (:mod:`gfuzzy.settings` ``MAX_*``): a time step
    far too fine or a horizon far too long for the scene. The message says what to change."""


class TimeStepError(LimitError):
    """The time step (``dt``) is too fine for the roadmap: the query graph would hold too many
    points whatever the query (the option's fault, not a query's)."""


class SceneError(InputError):
    """Bad input: a file (scene, roadmap, trajectory, rule base) that cannot be used.

    Parameters
    ----------
    file : str
        The file the problem is in (``"<string>"`` when parsed from text).
    place : str
        Where in the file, e.g. ``"movers[2].path[1]"``; empty for the whole file.
    message : str
        What is wrong, one line.
    """

    def __init__(self, file: str, place: str, message: str):
        self.file = str(file)
        self.place = place
        self.message = " ".join(str(message).split())
        where = f"{self.file}: {place}" if place else self.file
        super().__init__(f"{where}: {self.message}")


def not_utf8(data: bytes, exc: UnicodeDecodeError) -> str:
    """The message for bytes that are not UTF-8: where, as a line and column a user can go
    to, e.g. ``not UTF-8 text (line 2, column 10: byte 0xe9)``."""
    at = exc.start
    line = data.count(b"\n", 0, at) + 1
    column = at - (data.rfind(b"\n", 0, at) + 1) + 1  # in bytes: the line is not text
    return f"not UTF-8 text (line {line}, column {column}: byte 0x{data[at]:02x})"


def check_number(name: str, value, low: float = 0.0, *, strict: bool = True, finite: bool = True) -> None:
    """The one validation of a numeric option (``PlanOptions``, ``NavOptions``, ...).

    Raises :class:`InputError` naming ``name`` unless ``value`` is a real number above
    ``low`` (at least ``low`` when not ``strict``), finite and at most ``settings.MAX_MAGNITUDE``
    in magnitude unless ``finite`` is False.
    """
    ok = isinstance(value, numbers.Real) and not math.isnan(value) and (not finite or math.isfinite(value))
    if ok:
        ok = value > low if strict else value >= low
    if not ok:
        if strict and low == 0:
            want = "a positive number"
        else:
            want = f"a number {'>' if strict else '>='} {low:g}"
        raise InputError(f"{name} must be {want}, got {value!r}")
    if finite and abs(value) > MAX_MAGNITUDE:  # as a scene file's numbers: beyond, times stop resolving
        raise InputError(f"{name} must be at most {MAX_MAGNITUDE:g}, got {value:g}")


# ------------------------------------------------------------------ Ctrl-C
# Python raises ``KeyboardInterrupt`` in the main thread at its next bytecode, which may run
# inside a callback from native code: a numba kernel unpickling a constant, FCL's distance
# callback, a ctypes callback of llvmlite, a finaliser. There the interrupt comes out as a
# ``SystemError`` whose cause or context is the ``KeyboardInterrupt``, or it is printed as
# "Exception ignored" and dropped, and the command runs on to the end. So while
# :func:`interrupt_handling` is active, every SIGINT is also noted:
#
# * :func:`is_interrupt` recognises an exception that an interrupt caused;
# * :func:`check_interrupt` raises a dropped interrupt again at a safe point (before an atomic write
#   publishes its file, between a batch's results, between a navigation's replans);
# * :func:`interrupts_deferred` holds interrupts off where stopping half-way leaves a mess (a Dask
#   cluster starting or closing, a batch writing the rows it finished): a SIGINT there is
#   only noted, and raised when the outermost such section ends;
# * the noise an interrupt leaves behind (an "Exception ignored" report, a half-built
#   object's finaliser failing at exit) is not printed.
#
# Without :func:`interrupt_handling` (the library used from Python) nothing here changes anything:
# :func:`check_interrupt` never raises and :func:`is_interrupt` knows only the exception chain.

#: Exit status of an interrupted command (128 + SIGINT, as a shell reports it); a SIGTERM
#: (``kill``, ``timeout``, a container stopping) is handled as a Ctrl-C is, and exits 143.
EXIT_INTERRUPTED = 130


class _State:
    active = False  # interrupt_handling() is installed
    pending = False  # a SIGINT came and was not handled yet
    defer = 0  # depth of interrupts_deferred() sections
    aftermath = False  # the command that ended (restore=False) was interrupted: its noise stays quiet
    signum = signal.SIGINT  # the signal that interrupted it (SIGINT or SIGTERM)


_state = _State()


def _on_sigint(signum, frame) -> None:
    if not _state.pending:  # the first signal names the interruption
        _state.signum = signum
    _state.pending = True
    if not _state.defer:
        raise KeyboardInterrupt


def interrupt_pending() -> bool:
    """A SIGINT came (under :func:`interrupt_handling`) and no one has handled it yet."""
    return _state.pending


def clear_interrupt() -> None:
    """The pending interrupt is handled (a batch stopped and keeps its finished rows)."""
    _state.pending = False


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if an interrupt is pending, outside :func:`interrupts_deferred`.

    The safe points call it: an interrupt that native code dropped stops the command
    there rather than letting it run to the end.
    """
    if _state.pending and not _state.defer:
        raise KeyboardInterrupt


def is_interrupt(exc: BaseException) -> bool:
    """``exc`` is, or was caused by, an interrupt.

    A ``KeyboardInterrupt``; an exception whose ``__cause__``/``__context__`` chain holds one
    (numba's and CPython's ``SystemError: ... returned a result with an exception set``);
    or, once a SIGINT has come, any ``Exception`` (a half-built object failing after the
    interrupt cut it short).
    """
    seen: set[int] = set()
    e: BaseException | None = exc
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return _state.pending and isinstance(exc, Exception)


@contextlib.contextmanager
def interrupts_deferred(raise_after: bool = True) -> Iterator[None]:
    """A section that a SIGINT does not cut: it is only noted.

    When the outermost section ends normally, a SIGINT noted meanwhile is raised there
    (:func:`check_interrupt`), unless ``raise_after`` is False: the section is the command's
    last word (its "interrupted" or bad-input line), after which an interrupt changes nothing.
    A section left by an exception lets that exception go on (:func:`is_interrupt` then counts it).
    """
    _state.defer += 1
    try:
        yield
    finally:
        _state.defer -= 1
    if raise_after:
        check_interrupt()


def interrupted_status() -> int:
    """The exit status of the interrupted command: 128 + the signal, as a shell reports it
    (:data:`EXIT_INTERRUPTED`, 130, for a Ctrl-C; 143 for a SIGTERM)."""
    return 128 + int(_state.signum)


def say_interrupted() -> int:
    """The command line's last word on a Ctrl-C: the one line ``interrupted`` on stderr
    (``terminated`` after a SIGTERM).

    Said whole (a second Ctrl-C meanwhile, a terminal's repeat, adds nothing under
    :func:`interrupt_handling`); returns :func:`interrupted_status`.
    """
    with interrupts_deferred(raise_after=False):
        sys.stderr.write("terminated\n" if _state.signum == signal.SIGTERM else "interrupted\n")
        sys.stderr.flush()
    return interrupted_status()


def _quiet_unraisable(previous):
    def hook(unraisable) -> None:
        if _state.pending or _state.aftermath or isinstance(unraisable.exc_value, KeyboardInterrupt):
            _state.pending = True  # an interrupt dropped by native code, or its aftermath
            return
        previous(unraisable)

    hook._gfuzzy_outer = previous  # type: ignore[attr-defined] - a later block wraps this one's previous
    return hook


def _quiet_excepthook(previous):
    def hook(kind, value, tb) -> None:
        if value is not None and is_interrupt(value):
            _state.pending = True  # printed by native code (Cython) that then drops it
            return
        previous(kind, value, tb)

    hook._gfuzzy_outer = previous  # type: ignore[attr-defined]
    return hook


@contextlib.contextmanager
def interrupt_handling(restore: bool = True) -> Iterator[None]:
    """Note every SIGINT (see the Ctrl-C section above) while the block runs; main thread only.

    ``restore=False`` ignores SIGINT after the block: the program's own command line, once
    its command is over, exits with the command's status, quietly, whatever Ctrl-C comes
    during interpreter shutdown (Dask's exit handlers); the quiet hooks stay (quiet about an
    interrupted command's aftermath). Either way the next block starts afresh: nothing
    pending, whatever came before.
    """
    if _state.active or threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = (signal.getsignal(signal.SIGINT), sys.unraisablehook, sys.excepthook, signal.getsignal(signal.SIGTERM))
    signal.signal(signal.SIGINT, _on_sigint)
    signal.signal(signal.SIGTERM, _on_sigint)  # a SIGTERM stops the command as a Ctrl-C does
    sys.unraisablehook = _quiet_unraisable(getattr(saved[1], "_gfuzzy_outer", saved[1]))
    sys.excepthook = _quiet_excepthook(getattr(saved[2], "_gfuzzy_outer", saved[2]))
    _state.active, _state.pending, _state.defer, _state.aftermath = True, False, 0, False
    _state.signum = signal.SIGINT
    try:
        yield
    finally:
        if restore:
            signal.signal(signal.SIGINT, saved[0])
            signal.signal(signal.SIGTERM, saved[3])
            sys.unraisablehook, sys.excepthook = saved[1], saved[2]
        else:  # the command is over; Python's finalisation keeps an ignored signal ignored
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)
            _state.aftermath = _state.pending
        _state.active, _state.pending, _state.defer = False, False, 0
