"""Ctrl-C on the command line: one line, exit 130, nothing half-written, whenever it comes.

Python raises ``KeyboardInterrupt`` in the main thread at its next bytecode, which may run
inside a callback from native code: a numba kernel unpickling a constant, FCL's distance
callback, a ctypes callback of llvmlite, a finaliser. There the interrupt comes out as a
``SystemError`` whose cause or context is the ``KeyboardInterrupt``, or it is printed as
"Exception ignored" and dropped, and the command runs on to the end. So while
:func:`handling` is active, every SIGINT is also noted:

* :func:`is_interrupt` recognises an exception that an interrupt caused;
* :func:`check` raises a dropped interrupt again at a safe point (before an atomic write
  publishes its file, between a batch's results, between a navigation's replans);
* :func:`deferred` holds interrupts off where stopping half-way leaves a mess (a Dask
  cluster starting or closing, a batch writing the rows it finished): a SIGINT there is
  only noted, and the next :func:`check` outside raises it;
* the noise an interrupt leaves behind (an "Exception ignored" report, a half-built
  object's finaliser failing at exit) is not printed.

Without :func:`handling` (the library used from Python) nothing here changes anything:
:func:`check` never raises and :func:`is_interrupt` knows only the exception chain.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading
from collections.abc import Iterator

__all__ = ["EXIT_INTERRUPTED", "check", "clear", "deferred", "handling", "is_interrupt", "pending"]

#: Exit status of an interrupted command (128 + SIGINT, as a shell reports it).
EXIT_INTERRUPTED = 130


class _State:
    active = False  # handling() is installed
    pending = False  # a SIGINT came and was not handled yet
    defer = 0  # depth of deferred() sections


_state = _State()


def _on_sigint(signum, frame) -> None:
    _state.pending = True
    if not _state.defer:
        raise KeyboardInterrupt


def pending() -> bool:
    """A SIGINT came (under :func:`handling`) and no one has handled it yet."""
    return _state.pending


def clear() -> None:
    """The pending interrupt is handled (a batch stopped and keeps its finished rows)."""
    _state.pending = False


def check() -> None:
    """Raise ``KeyboardInterrupt`` if an interrupt is pending, outside :func:`deferred`.

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
def deferred() -> Iterator[None]:
    """A section that a SIGINT does not cut: it is only noted (:func:`check` raises it after)."""
    _state.defer += 1
    try:
        yield
    finally:
        _state.defer -= 1


def _quiet_unraisable(previous):
    def hook(unraisable) -> None:
        if _state.pending or isinstance(unraisable.exc_value, KeyboardInterrupt):
            _state.pending = True  # an interrupt dropped by native code, or its aftermath
            return
        previous(unraisable)

    return hook


def _quiet_excepthook(previous):
    def hook(kind, value, tb) -> None:
        if value is not None and is_interrupt(value):
            _state.pending = True  # printed by native code (Cython) that then drops it
            return
        previous(kind, value, tb)

    return hook


@contextlib.contextmanager
def handling(restore: bool = True) -> Iterator[None]:
    """Note every SIGINT (see the module) while the block runs; in the main thread only.

    ``restore=False`` leaves the handling installed after the block, deferring every later
    SIGINT: the program's own command line keeps it to the end of the process, so that a
    Ctrl-C after the command's last line (interpreter shutdown, Dask's exit handlers) is
    quiet too.
    """
    if _state.active or threading.current_thread() is not threading.main_thread():
        yield
        return
    saved = (signal.getsignal(signal.SIGINT), sys.unraisablehook, sys.excepthook)
    signal.signal(signal.SIGINT, _on_sigint)
    sys.unraisablehook = _quiet_unraisable(saved[1])
    sys.excepthook = _quiet_excepthook(saved[2])
    _state.active, _state.pending, _state.defer = True, False, 0
    try:
        yield
    finally:
        if restore:
            signal.signal(signal.SIGINT, saved[0])
            sys.unraisablehook, sys.excepthook = saved[1], saved[2]
            _state.active, _state.pending = False, False
        else:  # the command is over: a later SIGINT is only noted
            _state.defer += 1
