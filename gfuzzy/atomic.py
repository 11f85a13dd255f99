"""Atomic file writes: a temporary file beside the target, then a rename.

A reader sees the old file or the new one, never half of one; a failed write leaves the
old file and no temporary behind. An interrupt that native code dropped on the way
(:func:`gfuzzy.errors.check_interrupt`) stops the write before the rename: an interrupted command
publishes nothing it computed after the Ctrl-C.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from .errors import check_interrupt, interrupts_deferred

__all__ = ["remove_quietly", "write_atomic", "write_atomic_with"]


def write_atomic_with(path: str | os.PathLike, write: Callable[[str], None]) -> None:
    """Call ``write(tmp)`` on a temporary path beside ``path`` (same suffix, so writers
    that pick a format from it still do), then rename it over ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    except OSError as exc:  # name the file asked for, not the temporary one
        raise OSError(exc.errno, exc.strerror, str(path)) from exc
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp creates 0600; give the usual permissions
        check_interrupt()
        try:
            os.replace(tmp, path)
        except OSError as exc:
            raise OSError(exc.errno, exc.strerror, str(path)) from exc
    except BaseException:
        with interrupts_deferred():  # a second Ctrl-C leaves no temporary behind
            remove_quietly(tmp)
        raise


def remove_quietly(*paths: str | os.PathLike) -> None:
    """Remove each of ``paths`` that exists (a failed write's leftovers); never raises ``OSError``."""
    for p in paths:
        try:
            os.unlink(p)
        except OSError:
            pass


def write_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically."""

    def write(tmp: str) -> None:
        with open(tmp, "w", encoding="utf-8") as fh:
            fh.write(text)

    write_atomic_with(path, write)
