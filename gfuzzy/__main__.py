"""``python -m gfuzzy`` is the same program as ``gfuzzy`` (its console script runs :func:`run`)."""

import signal
import sys


def run() -> int:
    """The ``gfuzzy`` program: :func:`gfuzzy.cli.main` on the process's command line.

    The command line is imported here, not before, and so is everything the handling below
    needs: a Ctrl-C while it imports (numpy, FCL, OMPL, the first half second of every command)
    or before :func:`gfuzzy.cli.main` takes over the signal is the same one line,
    ``interrupted``, and exit status 130 as any later one. Only Python's own start and the
    package's (``gfuzzy/__init__.py``: its logging set-up) come before.
    """
    try:
        from .cli.main import main

        return main()
    except BaseException as exc:  # noqa: BLE001 - an interrupt that main's own handling never saw
        from .errors import is_interrupt, say_interrupted  # (again, if it was cut short)

        if not is_interrupt(exc):  # (or an import error it caused: an extension's init cut short)
            raise
        signal.signal(signal.SIGINT, signal.SIG_IGN)  # the process ends: a second one changes nothing
        return say_interrupted()


if __name__ == "__main__":
    sys.exit(run())
