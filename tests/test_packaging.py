"""What a packager gets: the sdist and the wheel hold every module, and an installed wheel works.

`make` installs gfuzzy editable, which hides a wheel that lacks a subpackage; these tests build
the sdist and the wheel from it (as `python -m build` does for a packager), compare their file
lists with the source tree, install the wheel into a fresh virtualenv WITHOUT `-e`, and run the
`gfuzzy` command of that install from a folder where the source tree is not importable.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest
from conftest import ROOT

PACKAGE = ROOT / "gfuzzy"

pytestmark = pytest.mark.long  # a virtualenv, an install and a cold numba compile: started first


def _source_files() -> set[str]:
    """Every file of the package a wheel must carry, as ``gfuzzy/...`` paths."""
    keep = {".py", ".txt", ".json", ".typed"}
    return {
        p.relative_to(ROOT).as_posix()
        for p in PACKAGE.rglob("*")
        if p.is_file() and p.suffix in keep and "__pycache__" not in p.parts
    }


#: what the build's copy of the repository leaves out: version control, virtualenvs, caches
#: (numba's, the precompiled kernels) and earlier builds' outputs
NOT_SOURCE = (".git", ".venv", "out", "build", "dist", "*.egg-info", "__pycache__", ".*_cache", ".hypothesis")


@pytest.fixture(scope="module")
def dist(tmp_path_factory) -> Path:
    """The sdist and the wheel, built from a copy of the repository: the build writes
    ``gfuzzy.egg-info`` into its source folder, and the repository is not written by tests
    (tests/test_readme.py checks that, and may run at the same time under ``pytest -n``)."""
    out = tmp_path_factory.mktemp("dist")
    src = tmp_path_factory.mktemp("src") / "gfuzzy"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(*NOT_SOURCE), symlinks=True)
    proc = subprocess.run(
        [sys.executable, "-m", "build", "--outdir", str(out), str(src)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return out


def test_wheel_and_sdist_hold_every_module_and_data_file(dist):
    expected = _source_files()
    assert {"gfuzzy/cli/main.py", "gfuzzy/ga/refine.py", "gfuzzy/py.typed"} <= expected
    (wheel,) = dist.glob("gfuzzy-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        in_wheel = {n for n in zf.namelist() if n.startswith("gfuzzy/")}
    assert expected - in_wheel == set(), f"missing from the wheel: {sorted(expected - in_wheel)}"
    (sdist,) = dist.glob("gfuzzy-*.tar.gz")
    with tarfile.open(sdist) as tf:
        in_sdist = {n.split("/", 1)[1] for n in tf.getnames() if "/" in n}
    assert expected - in_sdist == set(), f"missing from the sdist: {sorted(expected - in_sdist)}"
    assert {"pyproject.toml", "README.md", "LICENSE"} <= in_sdist
    # the bundled examples (gfuzzy examples DIR): the repository's folders in the sdist, and
    # copied by setup.py's build step into the wheel's package
    examples = {"scenes/building-floor.yaml", "scenes/maps/depot.pgm", "roadmaps/building-floor.json",
                "data/pedestrians/biwi_eth.txt"}  # fmt: skip
    assert examples <= in_sdist
    with zipfile.ZipFile(wheel) as zf:
        assert {f"gfuzzy/examples/{name}" for name in examples} <= set(zf.namelist())


def _venv_with(wheel: Path, venv: Path, *, deps: bool) -> tuple[Path, dict]:
    """A fresh virtualenv at ``venv`` with ``wheel`` installed (not editable); its bin folder
    and the environment to run it in. ``deps=False`` installs the wheel alone and lets the
    venv import the packages this test runs on (a ``.pth`` line naming their folders; the
    editable gfuzzy among them is not imported: its own ``.pth`` files are not read there)."""
    # without pip of its own: this run's pip installs into it (``--python``); ensurepip's
    # install of pip into every such virtualenv cost 6 s of CPU (19 s on the busy machine)
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True, timeout=300)
    bindir = venv / ("Scripts" if os.name == "nt" else "bin")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    env["MPLBACKEND"] = "Agg"
    install = [sys.executable, "-m", "pip", "--python", str(bindir / "python"), "install", "--quiet", str(wheel)]
    if not deps:
        import site
        import sysconfig

        purelib = subprocess.run(
            [str(bindir / "python"), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            capture_output=True, text=True, check=True, timeout=120,
        ).stdout.strip()  # fmt: skip
        ours = dict.fromkeys([sysconfig.get_paths()["purelib"], *site.getsitepackages()])
        Path(purelib, "_test_env_packages.pth").write_text("\n".join(ours) + "\n")
        install[6:6] = ["--no-deps"]
    proc = subprocess.run(install, capture_output=True, text=True, timeout=900, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return bindir, env


def _plans_refines_and_checks(bindir: Path, env: dict, venv: Path, work: Path, *, refine: bool) -> None:
    """What a user of the installed package does first: ``gfuzzy examples``, then a plan of
    the bundled building floor (the speed layer, with ``refine`` the GA too) and its check,
    run from a folder where only the install can be imported."""
    work.mkdir()
    out = work / "answer.json"

    def gfuzzy(*args):
        return subprocess.run(
            [str(bindir / "gfuzzy"), *map(str, args)],
            cwd=work, capture_output=True, text=True, timeout=600, env=env,
        )

    where = subprocess.run(
        [str(bindir / "python"), "-c", "import gfuzzy, sys; sys.stdout.write(gfuzzy.__file__)"],
        cwd=work, capture_output=True, text=True, timeout=120, env=env,
    )
    assert Path(where.stdout).is_relative_to(venv), where.stdout + where.stderr

    # the wheel carries the bundled examples: the README's scenes, roadmaps and data, copied out
    copied = gfuzzy("examples", "ex")
    assert copied.returncode == 0, copied.stdout + copied.stderr
    scene = work / "ex" / "scenes" / "building-floor.yaml"
    assert (work / "ex" / "roadmaps" / "building-floor.json").is_file()
    assert (work / "ex" / "data" / "pedestrians" / "biwi_eth.txt").is_file()

    # without precompiled kernels the first query compiles them with numba, before its
    # planning clock (tens of seconds on a loaded machine): a long limit all the same
    planned = gfuzzy("plan", scene, *(["--refine"] if refine else []), "--speed-layer", "--time-limit", "900", "-o", out)
    assert planned.returncode == 0, planned.stdout + planned.stderr
    answer = json.loads(out.read_text())
    assert answer["status"] == "solved" and len(answer["waypoints"]) > 2
    assert "speed_layer" in answer.get("stats", {}), sorted(answer)
    assert ("refine" in answer.get("stats", {})) == refine, sorted(answer.get("stats", {}))
    checked = gfuzzy("check", scene, out)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "valid" in checked.stdout


def test_installed_wheel_plans_and_checks(dist, tmp_path):
    """The wheel alone, installed over this run's packages, with the precompiled search
    kernels `make warm` built (``GFUZZY_KERNEL_DIR``; the installed sources are the same, so
    is their key): seconds, where the cold install below takes minutes."""
    (wheel,) = dist.glob("gfuzzy-*.whl")
    venv = tmp_path / "venv"
    bindir, env = _venv_with(wheel, venv, deps=False)
    from gfuzzy.timespace import jit

    for folder in jit.kernel_dirs():
        if (folder / f"{jit.module_name()}.json").exists():
            env["GFUZZY_KERNEL_DIR"] = str(folder)
            break
    _plans_refines_and_checks(bindir, env, venv, tmp_path / "elsewhere", refine=False)


@pytest.mark.slow
def test_a_cold_installed_wheel_plans_refines_and_checks(dist, tmp_path):
    """A user's ``pip install gfuzzy-*.whl`` into an empty virtualenv: the dependencies
    resolved from pyproject's ranges, no precompiled kernels, no numba cache (the search's
    and the GA's kernels compiled by the first plan). Minutes: `make slow` runs it."""
    (wheel,) = dist.glob("gfuzzy-*.whl")
    venv = tmp_path / "venv"
    bindir, env = _venv_with(wheel, venv, deps=True)
    _plans_refines_and_checks(bindir, env, venv, tmp_path / "elsewhere", refine=True)


def test_a_build_drops_what_an_earlier_build_left(tmp_path, monkeypatch):
    """`pip install .` and `pip wheel .` build in the repository's ``build/``: a module or an
    example scene an earlier build copied there went into every later wheel after it was
    moved or deleted from the source (found by s39-newuser). setup.py's build step, run
    in-process into a build folder holding such leftovers (seconds: no wheel is made)."""
    import setuptools
    from setuptools.dist import Distribution

    kept: dict = {}
    monkeypatch.setattr(setuptools, "setup", lambda **kw: kept.update(kw))
    exec(compile((ROOT / "setup.py").read_text(), str(ROOT / "setup.py"), "exec"), {"__file__": str(ROOT / "setup.py")})
    lib = tmp_path / "lib"
    for stale in ("gfuzzy/moved_away.py", "gfuzzy/examples/scenes/deleted.yaml"):
        (lib / stale).parent.mkdir(parents=True, exist_ok=True)
        (lib / stale).write_text("left by an earlier build\n")
    monkeypatch.chdir(ROOT)  # build_py reads the package from the current folder; it writes only to lib
    dist = Distribution({"name": "gfuzzy", "packages": ["gfuzzy"]})
    dist.script_name = "setup.py"
    cmd = kept["cmdclass"]["build_py"](dist)
    cmd.build_lib = str(lib)
    cmd.ensure_finalized()
    cmd.run()
    assert (lib / "gfuzzy" / "__init__.py").is_file() and (lib / "gfuzzy/examples/scenes/building-floor.yaml").is_file()
    assert not (lib / "gfuzzy" / "moved_away.py").exists()
    assert not (lib / "gfuzzy/examples/scenes/deleted.yaml").exists()


def _make(*args, env=None) -> str:
    """``make ARGS`` on the repository's Makefile, from its root: the output (skips without make)."""
    if shutil.which("make") is None:
        pytest.skip("no make here")
    proc = subprocess.run(["make", "--no-print-directory", "-f", str(ROOT / "Makefile"), *args],
                          cwd=ROOT, capture_output=True, text=True, timeout=60, env=env)  # fmt: skip
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def test_make_installs_without_byte_compiling_every_file(tmp_path):
    """`make`'s pip installs leave the byte-compiling to the imports (``--no-compile``):
    pip compiled all 6,500 files it installed, 80 s of the 110-145 s of a fresh install on
    the busy 2-core machine, where the suite imports a tenth of them."""
    stamp = tmp_path / "venv" / ".installed"
    recipe = _make("-n", f"VENV={tmp_path / 'venv'}", str(stamp))
    installs = [line for line in recipe.splitlines() if "pip install" in line]
    assert len(installs) == 2 and all("--no-compile" in line for line in installs), recipe


def test_make_lets_python_write_the_bytecode_of_what_it_imports():
    """...which needs Python to write it: a shell that sets PYTHONDONTWRITEBYTECODE (this
    machine's does) made every test process compile gfuzzy again, and every pytest worker
    rewrite every test module, and with ``--no-compile`` every process compile numpy, scipy
    and numba too. `make`'s recipes run without it."""
    env = dict(os.environ, PYTHONDONTWRITEBYTECODE="1")
    shown = _make("--eval", "_show_env:\n\t@echo \"[$$PYTHONDONTWRITEBYTECODE]\"", "_show_env", env=env)
    assert shown.strip() == "[]", shown
