"""The README's examples run as written: its command-line examples (outputs sent to a
temporary folder) and every ```python block, in order, as one program."""

from __future__ import annotations

import json
import re
import shlex

from conftest import ROOT, run_cli_process, run_python
from helpers import run_main


def _commands() -> list[list[str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## The command line\s+```sh\n(.*?)```", text, re.S).group(1)
    return [
        shlex.split(line, comments=True)
        for line in block.splitlines()
        if line.startswith("gfuzzy ")
    ]


def test_readme_plan_check_and_tracks_examples_run(tmp_path, capsys, monkeypatch):
    """The first example in a real process (``gfuzzy`` as typed), the others in process
    (each command's own process is tested with it): from the repository's root."""
    monkeypatch.chdir(ROOT)
    commands = _commands()
    assert any(c[1] == "tracks" for c in commands) and any(
        "office-polygons" in " ".join(c) for c in commands
    )
    ran = 0
    for argv in commands:
        if argv[1] == "roadmap":  # into out/: a bundled roadmap replaced made `regress` FAIL its expectations
            assert "-o" in argv and argv[argv.index("-o") + 1].startswith("out/"), argv
        # `regress` and `render` have their own tests
        if argv[1] not in ("roadmap", "plan", "check", "tracks"):
            continue
        argv = [a.replace("out/", f"{tmp_path}/") for a in argv[1:]]
        if ran == 0:
            proc = run_cli_process(*argv, cwd=ROOT)
            assert proc.returncode == 0, (argv, proc.stdout, proc.stderr)
        else:
            rc, out, err = run_main(capsys, *argv)
            assert rc == 0, (argv, out, err)
        ran += 1
    assert ran >= 4


def python_blocks(text: str) -> list[tuple[int, str]]:
    """Every ```python block of a Markdown text: (line of its first code line, code)."""
    blocks = []
    for m in re.finditer(r"^```python[ \t]*\n(.*?)^```[ \t]*$", text, re.S | re.M):
        blocks.append((text.count("\n", 0, m.start(1)) + 1, m.group(1)))
    return blocks


def test_python_blocks_are_found():
    text = "a\n```python\nx = 1\n```\n\n```sh\nls\n```\n```python\ny = x\n```\n"
    assert python_blocks(text) == [(3, "x = 1\n"), (10, "y = x\n")]


# Runs the blocks in one namespace, each compiled with README.md's own line numbers, so that
# a traceback points at the README line that failed.
RUNNER = """
import json, sys
blocks = json.loads(sys.argv[1])
namespace = {"__name__": "__main__"}
for line, code in blocks:
    exec(compile("\\n" * (line - 1) + code, "README.md", "exec"), namespace)
"""


#: what the test tools make in the repository (Hypothesis's example database in the working
#: folder): under ``pytest -n`` another worker may make them while the README's code runs
TOOL_CACHES = {".hypothesis", ".pytest_cache", ".ruff_cache", "__pycache__"}


def _listing(folder) -> list[str]:
    """The names in ``folder``, less the test tools' caches."""
    return sorted(q.name for q in folder.iterdir() if q.name not in TOOL_CACHES)


def test_readme_python_blocks_run(tmp_path):
    """Every ```python block of README.md runs, in order, in one namespace (a later block
    may use what an earlier one made), from a folder that holds the repository's files and
    folders (linked), so the README's relative paths (scenes/..., roadmaps/...) work as
    from the repository root, and whatever the code writes lands in the temporary folder."""
    blocks = python_blocks((ROOT / "README.md").read_text(encoding="utf-8"))
    assert blocks, "README.md has no ```python block"
    for entry in ROOT.iterdir():
        if not entry.name.startswith(".") and entry.name not in ("out", "build", "dist"):
            (tmp_path / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    (tmp_path / "out").mkdir()
    before = {p: _listing(p) for p in (ROOT, ROOT / "scenes", ROOT / "roadmaps")}
    # a guard against a hang, not a timing: the blocks take about 27 s of CPU, which a loaded
    # machine (load 12 on 2 cores) stretched to 275 s of wall clock, near the 300 s it had
    proc = run_python(RUNNER, json.dumps(blocks), cwd=tmp_path, timeout=1800)
    assert proc.returncode == 0, f"a README.md python block failed:\n{proc.stdout}\n{proc.stderr}"
    after = {p: _listing(p) for p in before}
    assert after == before, "the README's code wrote into the repository"


def test_no_documented_populate_writes_among_the_bundled_scenes():
    # its copy keeps the scene's name and expectations: in scenes/, the README's own
    # `gfuzzy batch scenes/*.yaml` refused two scenes of one name and `regress` FAILed
    texts = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
    found = 0
    for path in texts:
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.startswith("gfuzzy populate "):
                argv = shlex.split(line, comments=True)
                assert not argv[argv.index("-o") + 1].startswith("scenes/"), (path.name, line)
                found += 1
    assert found >= 2


def _navigator_doc() -> str:
    return (ROOT / "docs" / "navigator.md").read_text(encoding="utf-8")


def _table_rows(text: str, header: str) -> list[list[str]]:
    """The cells of the rows of the markdown table whose header line is ``header``."""
    lines = text.split(header + "\n", 1)[1].splitlines()[1:]  # past the --- line
    return [[c.strip() for c in line.strip("|").split(" | ")] for line in lines[: next(i for i, x in enumerate(lines) if not x.startswith("|"))]]


def test_navigators_settings_table_names_every_option_with_its_default():
    # it lacked budget_clock, backend, commitment, fan, full_speed, fov and look_after
    from dataclasses import fields

    from gfuzzy.navigation.navigator import NavOptions

    documented = {}
    for cells in _table_rows(_navigator_doc(), "| setting | default | meaning |"):
        names = re.findall(r"`(\w+)`", cells[0])
        documented.update(zip(names, cells[1].split(", "), strict=True))
    defaults = {f.name: f.default for f in fields(NavOptions)}
    assert sorted(documented) == sorted(defaults)
    wrong = {
        name: (text, defaults[name])
        for name, text in documented.items()
        if text != str(defaults[name]) and not (type(defaults[name]) in (int, float) and float(text) == defaults[name])
    }
    assert wrong == {}


def test_navigators_modes_key_names_every_mode():
    # it named six of the nine modes a run counts (not kept, goal, look)
    from gfuzzy.navigation.navtypes import NavMode

    (cells,) = [c for c in _table_rows(_navigator_doc(), "| key | meaning |") if c[0] == "`modes`"]
    named = set(re.findall(r"`(\w+)` \(", cells[1]))
    assert named == {m.value for m in NavMode}


def test_navigators_docs_name_every_flag_of_navigate():
    # --backend, --clearance and --mover-clearance were not there
    from gfuzzy.cli.main import _parser

    (sub,) = [a for a in _parser()._actions if a.dest == "command"]
    section = _navigator_doc().split("## `gfuzzy navigate`", 1)[1].split("\n## ", 1)[0]
    missing = [
        a.option_strings
        for a in sub.choices["navigate"]._actions
        if a.option_strings and a.dest != "help" and not any(re.search(rf"(?<![\w-]){o}(?![\w-])", section) for o in a.option_strings)
    ]
    assert missing == []


def test_the_docs_python_imports_resolve():
    # docs/speed-layer.md said `from gfuzzy import tracking` (ImportError): the module is
    # gfuzzy.learning.tracking; the docs' blocks are fragments, but their imports must run
    lines = sorted(
        {
            line.strip()
            for path in sorted((ROOT / "docs").glob("*.md"))
            for _, code in python_blocks(path.read_text(encoding="utf-8"))
            for line in code.splitlines()
            if re.match(r"\s*(from gfuzzy[\w.]* import [\w, ]+$|import gfuzzy[\w.]*$)", line)
        }
    )
    assert len(lines) >= 3, lines
    # in process: an import resolves here as in a fresh one (`from P import M` imports a
    # submodule M it does not find as an attribute); a process cost 2 s of imports
    exec(compile("\n".join(lines), "<docs' imports>", "exec"), {})


_MODULES_AS_ATTRIBUTES = """
import importlib, pkgutil, sys
import gfuzzy
assert "numpy" not in sys.modules  # still light
seen = 0
for pkg in ["gfuzzy", *sys.argv[1:]]:  # gfuzzy first: its own attributes before any import
    flat = pkg.rsplit(".", 1)[-1]  # a package that was a flat module: gfuzzy.check.check
    for info in pkgutil.iter_modules(importlib.import_module(pkg).__path__):
        if info.name.startswith("__"):
            continue
        obj = gfuzzy
        for part in [*pkg.split(".")[1:], info.name]:
            obj = getattr(obj, part)
        name = getattr(obj, "__name__", None)
        # (a package's function named as its module, gfuzzy.cli.main, is what that name holds)
        assert name == f"{pkg}.{info.name}" or name == info.name in (flat, "main"), (pkg, info.name, obj)
        seen += 1
for name in ("nope", "__wrapped__"):
    assert not hasattr(gfuzzy, name) and not hasattr(gfuzzy.check, name)
print(seen)
"""


def test_gfuzzys_modules_are_attributes_after_import_gfuzzy():
    # `import gfuzzy; gfuzzy.errors` (and .scene, .check, .status: 15 names) was an
    # AttributeError once `import gfuzzy` became lazy; before, its eager imports had made every
    # one an attribute (and gfuzzy.check.check, .reach, ... of the packages that were modules)
    # every subpackage's modules too (gfuzzy.navigation.navigator, gfuzzy.collision.geometry,
    # gfuzzy.learning.drivetracking were AttributeErrors; gfuzzy.check.check, .reach, ...)
    packages = sorted(f"gfuzzy.{p.parent.name}" for p in (ROOT / "gfuzzy").glob("*/__init__.py"))
    assert len(packages) >= 14, packages
    proc = run_python(_MODULES_AS_ATTRIBUTES, *packages, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    assert int(proc.stdout) >= 100
