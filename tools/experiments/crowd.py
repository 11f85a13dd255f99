"""The crowd benchmark's table (issue 10's ``tools/bench_crowd.py``), when it exists.

The navigator and its benchmark are built on another branch. When ``tools/bench_crowd.py``
is in the tree, this runs it with a small episode count and includes what it prints;
otherwise the section says it is not there yet (no numbers are invented).
"""

from __future__ import annotations

import subprocess
import sys

from .common import ROOT

SCRIPT = ROOT / "tools" / "bench_crowd.py"
EPISODES = 3
TIMEOUT = 600


def run(ctx) -> str:
    head = "## The crowd benchmark (navigation without knowing the movers' future)\n\n"
    if not SCRIPT.exists():
        return head + (
            "Not in this tree yet: the navigator (`gfuzzy navigate`, issue 10) and its benchmark "
            "`tools/bench_crowd.py` are built on another branch. Once the script is here, "
            f"`make experiments` runs it with {EPISODES} episodes and puts its table in this section."
        )
    cmd = [sys.executable, str(SCRIPT), "--episodes", str(EPISODES)]
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=TIMEOUT)
    if proc.returncode != 0 and "--episodes" in proc.stderr:
        cmd = cmd[:2]  # an older script without --episodes: its own defaults
        proc = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=TIMEOUT)
    shown = " ".join(["python", "tools/bench_crowd.py", *cmd[2:]])
    if proc.returncode != 0:
        tail = (proc.stderr or proc.stdout).strip().splitlines()[-5:]
        return head + f"`{shown}` failed (exit {proc.returncode}); its last lines:\n\n```\n" + "\n".join(tail) + "\n```"
    out = proc.stdout.strip()
    body = out if out.lstrip().startswith("|") else f"```\n{out}\n```"
    return head + f"`{shown}` (run by `make experiments`, outside Dask: it is one script):\n\n{body}"
