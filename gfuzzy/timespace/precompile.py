"""Build the precompiled kernels that :mod:`gfuzzy.timespace.jit` loads instead of numba.

    python -m gfuzzy.timespace.precompile            # what `make warm` runs
    python -m gfuzzy.timespace.precompile --dir D    # into D (else see gfuzzy.timespace.jit.kernel_dirs)

It compiles the kernels with numba's just-in-time compiler first (filling numba's on-disk
cache, which the fallback uses), on the warm-up search of
:func:`gfuzzy.timespace.search_kernel.warm`, which calls every kernel the Python drivers call; then
compiles each kernel numba compiled, with the one signature numba gave it, ahead of time
(``numba.pycc``) into one extension module, named by :func:`gfuzzy.timespace.jit.kernel_key`, and
writes those signatures beside it. A kernel numba compiled for two signatures is left
out (it stays numba's, with a warning). Older extensions in the folder are removed.

Building needs a C compiler and takes 5-15 s; without a compiler the kernels stay
numba's (the build fails with a message, planning is unaffected).
"""

from __future__ import annotations

import argparse
import importlib
import json
import logging
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from . import jit

__all__ = ["build", "main"]

log = logging.getLogger(__name__)


def _signature(sig) -> list[list]:
    """``[[dtype, ndim], ...]`` of a numba signature's arguments (ndim 0: a scalar)."""
    from numba import types
    from numba.np.numpy_support import as_dtype

    out = []
    for t in sig.args:
        if isinstance(t, types.Array):
            if t.layout != "C":
                raise TypeError(f"only C-contiguous arrays are precompiled, got {t}")
            out.append([as_dtype(t.dtype).str, t.ndim])
        else:
            out.append([as_dtype(t).str, 0])
    return out


def _start_beside(modules: list[str]) -> subprocess.Popen | None:
    """``import M; M.warm()`` for each of ``modules``, in one second process started now
    (numba's kernels: ``GFUZZY_PRECOMPILED=0`` as here), or None without modules."""
    if not modules:
        return None
    code = "import importlib, sys\nfor m in sys.argv[1:]:\n    importlib.import_module(m).warm()\n"
    env = dict(os.environ, GFUZZY_PRECOMPILED="0")
    return subprocess.Popen([sys.executable, "-c", code, *modules], env=env)


def _finish_beside(proc: subprocess.Popen | None) -> None:
    """Wait for :func:`_start_beside`'s process; a failure is logged, not raised (the
    build's own result stands; `make warm` warms those modules again after it)."""
    if proc is not None and proc.wait() != 0:
        log.warning("warming %s beside the build failed (exit status %d)", " ".join(proc.args[3:]), proc.returncode)


def _build_here(folder: Path, target_cpu: str = "", beside: list[str] | None = None) -> Path:
    """Build in this process, whose kernel modules must not be imported yet. ``beside``:
    modules whose ``warm()`` runs in a second process while the ahead-of-time compile runs
    here (after numba's compile of the search kernels, whose on-disk cache they load)."""
    if any(f"{__package__}.{m}" in sys.modules for m in jit.KERNEL_MODULES) and jit.loaded() is not None:
        raise RuntimeError("the kernel modules are already loaded from an extension: build in a fresh process")
    jit.BUILDING = True
    jit._state.clear()
    from numba.core.registry import CPUDispatcher
    from numba.pycc import CC

    from . import graph_kernel, search_kernel

    search_kernel.warm()  # numba compiles (or loads from its cache) every kernel the drivers call
    graph_kernel.warm()
    side = _start_beside(beside or [])
    try:
        return _compile_ahead(folder, target_cpu, CC, CPUDispatcher)
    finally:
        _finish_beside(side)


def _compile_ahead(folder: Path, target_cpu: str, CC, CPUDispatcher) -> Path:
    """The extension of every kernel numba compiled with one signature, written to ``folder``."""
    key = jit.kernel_key()
    name = jit.module_name(key)
    cc = CC(name)
    cc.target_cpu = target_cpu
    cc.verbose = False
    signatures = {}
    for short in jit.KERNEL_MODULES:
        module = importlib.import_module(f"{__package__}.{short}")
        for attr, value in sorted(vars(module).items()):
            if not isinstance(value, CPUDispatcher) or value.py_func.__module__ != module.__name__:
                continue
            sigs = value.nopython_signatures
            if len(sigs) != 1:
                if sigs:
                    log.info("%s.%s has %d signatures: left to numba", short, attr, len(sigs))
                continue
            export = f"{short}__{attr}"
            signatures[export] = _signature(sigs[0])
            cc.export(export, sigs[0])(value.py_func)
    folder.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp:
        cc.output_dir = tmp
        cc.compile()
        built = next(Path(tmp).glob(f"{name}*"))
        for old in folder.glob("_gfuzzy_kernels_*"):
            if not old.name.startswith(f"{name}."):  # other keys: older source
                old.unlink(missing_ok=True)
        target = folder / built.name
        os.replace(built, target)
        sig_tmp = Path(tmp) / f"{name}.json"  # written last: the loader needs both files
        sig_tmp.write_text(json.dumps(signatures, indent=1), encoding="utf-8")
        os.replace(sig_tmp, folder / f"{name}.json")
    return target


def build(folder: str | os.PathLike | None = None, target_cpu: str = "") -> Path:
    """Build the extension in a fresh Python process (so that the kernels are numba's).

    Parameters
    ----------
    folder : path, optional
        Where to write it (default: the first of :func:`gfuzzy.timespace.jit.kernel_dirs`).
    target_cpu : str
        LLVM CPU name (``""``: generic for this architecture, ``"host"``: this machine's).

    Returns
    -------
    Path
        The extension module's file.
    """
    folder = Path(folder) if folder else jit.kernel_dirs()[0]
    env = dict(os.environ, GFUZZY_PRECOMPILED="0")
    code = "import sys\nfrom gfuzzy.timespace.precompile import main\nsys.exit(main(sys.argv[1:]))\n"
    args = [sys.executable, "-c", code, "--dir", str(folder), "--cpu", target_cpu]
    out = subprocess.run(args, env=env, capture_output=True, text=True, check=False)
    if out.returncode != 0:
        raise RuntimeError(f"building the precompiled kernels failed:\n{out.stderr}")
    return Path(out.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    """``python -m gfuzzy.timespace.precompile [--dir D] [--cpu NAME]``: build, print the file."""
    parser = argparse.ArgumentParser(prog="python -m gfuzzy.timespace.precompile", description=__doc__.split("\n\n")[0])
    parser.add_argument("--dir", type=Path, default=None, help="output folder (default: see gfuzzy.timespace.jit)")
    parser.add_argument("--cpu", default="", help="LLVM target CPU ('' generic, 'host' this machine)")
    parser.add_argument("--beside", nargs="+", default=[], metavar="MODULE",
                        help="modules whose warm() runs in a second process during the ahead-of-time compile")  # fmt: skip
    args = parser.parse_args(argv)
    os.environ["GFUZZY_PRECOMPILED"] = "0"
    path = _build_here(args.dir or jit.kernel_dirs()[0], args.cpu, args.beside)
    sys.stdout.write(f"{path}\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
