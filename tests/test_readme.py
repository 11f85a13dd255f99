"""The README's command-line examples run as written (outputs sent to a temporary folder)."""

from __future__ import annotations

import re
import shlex

from conftest import ROOT, run_cli_process


def _commands() -> list[list[str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## The command line\s+```sh\n(.*?)```", text, re.S).group(1)
    return [
        shlex.split(line, comments=True)
        for line in block.splitlines()
        if line.startswith("gfuzzy ")
    ]


def test_readme_plan_check_and_tracks_examples_run(tmp_path):
    commands = _commands()
    assert any(c[1] == "tracks" for c in commands) and any(
        "office-polygons" in " ".join(c) for c in commands
    )
    ran = 0
    for argv in commands:
        # `roadmap` would overwrite the bundled roadmap, `regress` and `render` have their own tests
        if argv[1] not in ("plan", "check", "tracks"):
            continue
        argv = [a.replace("out/", f"{tmp_path}/") for a in argv[1:]]
        proc = run_cli_process(*argv, cwd=ROOT)
        assert proc.returncode == 0, (argv, proc.stdout, proc.stderr)
        ran += 1
    assert ran >= 4
