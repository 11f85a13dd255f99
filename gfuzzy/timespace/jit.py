"""The compiled kernels without numba's load: precompiled machine code when it is built,
numba's just-in-time dispatchers otherwise.

:mod:`gfuzzy.timespace.search_kernel` and :mod:`gfuzzy.timespace.movers_kernel` decorate their kernels with
:func:`njit` instead of ``numba.njit``. When a precompiled extension of those kernels is
built (``make warm``: ``python -m gfuzzy.timespace.precompile``) and fresh, the decorator returns
its functions and **numba is never imported**: loading the extension takes about a
millisecond, where importing numba and loading its cache of the same machine code took
0.3-0.9 s, paid by the first compiled query of every process (a CLI call, a batch worker,
a navigator). Without the extension (not built, stale, ``GFUZZY_PRECOMPILED=0``), the
decorator is ``numba.njit`` itself, imported at that moment, exactly as before.

Fresh means: built from the kernel modules' current source, for this Python and this
numpy (the extension's name holds a hash of them, :func:`kernel_key`); a stale
extension is never loaded, so an edited kernel falls back to numba until the next
``make warm``. An extension's functions take exactly the argument types numba compiled
(its signatures are kept in a file beside it); a call with other types (another dtype, a
non-contiguous view) runs numba's dispatcher instead, compiled on demand, so a caller
never gets a wrong answer or a crash from a type the extension was not built for.

Where: ``GFUZZY_KERNEL_DIR`` if set, else ``gfuzzy/__pycache__`` when the package folder
is writable, else ``$XDG_CACHE_HOME/gfuzzy`` (``~/.cache/gfuzzy``), as numba's own cache.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import json
import logging
import os
import sys
import types
from pathlib import Path

import numpy as np

__all__ = ["KERNEL_MODULES", "cold", "kernel_dirs", "kernel_key", "loaded", "njit", "note_cold", "numba_cached"]

log = logging.getLogger(__name__)

#: The modules whose kernels are precompiled (their source is part of the key).
KERNEL_MODULES = ("search_kernel", "movers_kernel", "graph_kernel")

#: Set by :mod:`gfuzzy.timespace.precompile` while it builds: the kernels must then be numba's.
BUILDING = False

_PACKAGE = Path(__file__).resolve().parent
_state: dict[str, object] = {}
_registry: dict[str, dict[str, tuple]] = {}  # module -> kernel name -> (function, options)
_dispatchers: dict[str, dict[str, object]] = {}  # numba's, made for a fallback


def kernel_key() -> str:
    """Hash of what the extension's machine code depends on: the kernel modules' source,
    this module's (the export rules), the Python ABI and numpy's version."""
    h = hashlib.sha256()
    for name in (*KERNEL_MODULES, "jit"):
        h.update((_PACKAGE / f"{name}.py").read_bytes())
    h.update(f"{sys.implementation.cache_tag} {np.__version__} {sys.platform}".encode())
    return h.hexdigest()[:16]


def kernel_dirs() -> list[Path]:
    """The folders searched for the extension, the first the one a build writes to."""
    env = os.environ.get("GFUZZY_KERNEL_DIR")
    if env:
        return [Path(env)]
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "gfuzzy"
    pkg = _PACKAGE / "__pycache__"
    writable = os.access(pkg if pkg.exists() else _PACKAGE, os.W_OK)
    return [pkg, user] if writable else [user, pkg]


def module_name(key: str | None = None) -> str:
    """The extension's module name for ``key`` (default: the current source's)."""
    return f"_gfuzzy_kernels_{key or kernel_key()}"


def _load():
    """The fresh extension and its signatures, or None (not built, stale, disabled)."""
    if os.environ.get("GFUZZY_PRECOMPILED", "1") == "0":
        return None
    name = module_name()
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    for folder in kernel_dirs():
        so, sigs = folder / f"{name}{suffix}", folder / f"{name}.json"
        if so.exists() and sigs.exists():
            try:
                spec = importlib.util.spec_from_file_location(name, so)
                module = importlib.util.module_from_spec(spec)
                spec.loader.exec_module(module)
                return module, json.loads(sigs.read_text(encoding="utf-8"))
            except (ImportError, OSError, ValueError) as exc:  # a broken file: numba instead
                log.warning("precompiled kernels %s not loaded (%s); using numba", so, exc)
                return None
    log.debug("no precompiled kernels %s; using numba", name)
    return None


def loaded():
    """The precompiled extension module in use, or None (numba's dispatchers are)."""
    if "ext" not in _state:
        _state["ext"] = None if BUILDING else _load()
    ext = _state["ext"]
    return ext[0] if ext else None


def numba_cached(stem: str, package_dir: str | os.PathLike) -> bool:
    """Whether numba's on-disk cache holds kernels of module ``stem`` (``search_kernel``,
    ``kernels``) whose source lies in ``package_dir``, where numba keeps them: with
    ``NUMBA_CACHE_DIR``, its folder ``<folder name>_<sha1 of the folder's absolute path>``
    (numba's ``UserProvidedCacheLocator``), so another package's module of that name in a
    shared cache does not count; else the folder's ``__pycache__``. Numba's per-user fallback
    folder for a read-only install is not looked at: there this may say False on a warm cache."""
    folder = os.path.abspath(os.fspath(package_dir))
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        where = Path(env) / f"{os.path.basename(folder)}_{hashlib.sha1(folder.encode()).hexdigest()}"
    else:
        where = Path(folder) / "__pycache__"
    return where.is_dir() and next(where.glob(f"{stem}.*.nbi"), None) is not None


def cold() -> bool:
    """True when the compiled search will be compiled now: no fresh precompiled extension,
    and no numba cache of the search kernels (:func:`numba_cached`)."""
    if loaded() is not None:
        return False
    return not numba_cached("search_kernel", os.path.dirname(os.path.abspath(__file__)))


_noted: list = []


def note_cold(stream=None) -> None:
    """Before the compiled search's first use: say once per process, on stderr, that the
    kernels are being compiled when :func:`cold` (a fresh install's first query waited
    about 30 s in silence; a newcomer measured it). Pipes and logs get it too: a first
    run under CI, its output captured, waited 13 minutes on a loaded machine with no word."""
    stream = stream or sys.stderr
    if _noted or not cold():
        return
    _noted.append(True)
    stream.write("note: compiling the search kernels for this installation (once, about 20-40 s; "
                 "`python -m gfuzzy.timespace.precompile` builds them ahead)\n")  # fmt: skip
    stream.flush()


def _numba_njit(func, options):
    from numba import njit as numba_njit  # only where no precompiled kernel serves

    return numba_njit(**options)(func)


def _dispatcher(func):
    """numba's dispatcher of a kernel whose module holds precompiled or lazy stand-ins:
    compiled over a copy of the module's globals in which every other kernel is numba's
    too (nopython code cannot call the stand-ins)."""
    kernels = _registry.setdefault(func.__module__, {})
    made = _dispatchers.setdefault(func.__module__, {})
    if func.__name__ not in made:
        names = dict(func.__globals__)
        copy = types.FunctionType(func.__code__, names, func.__name__, func.__defaults__, func.__closure__)
        copy.__qualname__, copy.__module__ = func.__qualname__, func.__module__
        made[func.__name__] = _numba_njit(copy, kernels[func.__name__][1])
        for name, (other, _) in kernels.items():
            if name != func.__name__:
                names[name] = _dispatcher(other)
    return made[func.__name__]


def _lazy(func, options):
    """numba's dispatcher of ``func``, made (numba imported) at its first call."""
    made: list = []

    def call(*args, **kwargs):
        if not made:
            made.append(_dispatcher(func))
        return made[0](*args, **kwargs)

    return call


def _checked(func, fast, sig, options):
    """``fast`` (precompiled) for the argument types it was built for, numba otherwise."""
    arrays = tuple((i, np.dtype(dt), nd) for i, (dt, nd) in enumerate(sig) if nd)
    slow = _lazy(func, options)

    def call(*args, **kwargs):
        if kwargs or len(args) != len(sig):
            return slow(*args, **kwargs)
        for i, dt, nd in arrays:
            a = args[i]
            if type(a) is not np.ndarray or a.dtype != dt or a.ndim != nd or not a.flags.c_contiguous:
                return slow(*args)
        return fast(*args)

    return _wrapped(call, func, precompiled=True)


def _wrapped(call, func, precompiled=False):
    call.__name__, call.__qualname__, call.__doc__ = func.__name__, func.__qualname__, func.__doc__
    call.__wrapped__ = func
    call.py_func = func  # as numba's dispatchers have
    call.precompiled = precompiled
    return call


def njit(lazy: bool = False, **options):
    """``numba.njit(**options)``, or the precompiled function when a fresh extension has it.

    ``lazy``: without the extension, numba is imported at the kernel's first call rather
    than here (for a module that is imported on paths that need not call it).

    A kernel compiled only inside other kernels (never called from Python) may have no
    precompiled entry point: called from Python, it is compiled by numba then.
    """

    def wrap(func):
        _registry.setdefault(func.__module__, {})[func.__name__] = (func, options)
        ext = loaded()
        if ext is None:
            if lazy and not BUILDING:
                return _wrapped(_lazy(func, options), func)
            return _numba_njit(func, options)
        export = f"{func.__module__.rsplit('.', 1)[-1]}__{func.__name__}"
        sig = _state["ext"][1].get(export)
        if sig is None:
            return _wrapped(_lazy(func, options), func)
        return _checked(func, getattr(ext, export), sig, options)

    return wrap
