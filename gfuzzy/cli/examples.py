"""``gfuzzy examples DIR``: copy the bundled scenes, roadmaps and pedestrian data into DIR.

A wheel carries them as ``gfuzzy/examples/`` (``setup.py`` copies them in at build time);
an editable install or a run from the source tree reads them from the repository. Either
way the user gets the folders the README's commands name (``scenes/``, ``roadmaps/``,
``data/pedestrians/``), so those commands run as written from DIR.
"""

from __future__ import annotations

import os
import shlex
import shutil
import sys
import tempfile
from pathlib import Path

from .common import EXIT_OK, BadInput, _say

#: The folders copied, as the repository and the wheel hold them.
EXAMPLES = ("scenes", "roadmaps", "data")


def add_examples(sub) -> None:
    """``gfuzzy examples``."""
    e = sub.add_parser(
        "examples",
        help="copy the bundled scenes, roadmaps and pedestrian data into a folder, to run the README's commands",
    )
    e.add_argument("folder", metavar="DIR", help="where to copy them (created if missing; its parent must exist)")
    e.set_defaults(func=cmd_examples)


def examples_root() -> Path | None:
    """The folder holding the bundled examples: the installed package's ``examples/``, or
    the source tree the package is imported from (None when neither has them)."""
    package = Path(__file__).resolve().parent.parent
    for root in (package / "examples", package.parent):
        if all((root / name).is_dir() for name in EXAMPLES):
            return root
    return None


def cmd_examples(args) -> int:
    root = examples_root()
    if root is None:
        raise BadInput("gfuzzy examples: this installation carries no examples (build the wheel from the source tree)")
    dest = Path(args.folder)
    if dest.exists() and not dest.is_dir():
        raise BadInput(f"{dest}: is a file, not a folder")
    if not dest.resolve().parent.is_dir():
        raise BadInput(f"{dest}: folder {dest.resolve().parent} does not exist")
    taken = [name for name in EXAMPLES if (dest / name).exists()]
    if taken:
        raise BadInput(f"{dest / taken[0]}: already exists (give a new or empty folder)")
    made = not dest.exists()
    try:
        dest.mkdir(exist_ok=True)
        # copied beside their place first, then moved in: an error leaves nothing half-copied
        stage = Path(tempfile.mkdtemp(prefix=".gfuzzy-examples-", dir=dest))
        try:
            for name in EXAMPLES:
                shutil.copytree(root / name, stage / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
            for name in EXAMPLES:
                os.replace(stage / name, dest / name)
        finally:
            shutil.rmtree(stage, ignore_errors=True)
    except OSError as exc:
        for name in EXAMPLES:
            shutil.rmtree(dest / name, ignore_errors=True)
        if made:
            shutil.rmtree(dest, ignore_errors=True)
        raise BadInput(f"{dest}: cannot copy the examples: {exc.strerror or exc}") from None
    n = sum(1 for name in EXAMPLES for p in (dest / name).rglob("*") if p.is_file())
    _say(
        f"{dest}: {n} files ({', '.join(f'{name}/' for name in EXAMPLES)}); try: "
        f"cd {shlex.quote(str(dest))} && gfuzzy plan scenes/building-floor.yaml -o answer.json",
        sys.stdout,
    )
    return EXIT_OK
