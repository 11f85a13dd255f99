"""The ``gfuzzy`` command line (README.md and docs/formats.md).

Exit statuses: 0 success, 1 a valid request with a negative answer (no path, invalid
trajectory, missed expectation), 2 bad input. Bad input prints exactly one line on stderr
naming the file and the place in it, and writes nothing.

Modules: :mod:`.common` (bad input, shared steps), :mod:`.planning` (roadmap, plan,
check, render, regress), :mod:`.experiments` (tracks, batch, navigate), :mod:`.export`
(export), :mod:`.main`
(the parser and :func:`main`, the ``gfuzzy`` entry point).
"""

from .main import main

__all__ = ["main"]
