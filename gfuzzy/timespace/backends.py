"""The two implementations of the safe-interval search (``PlanOptions.backend``).

``"reference"`` is the pure-Python definition (:func:`gfuzzy.timespace.timespace.sipp`, its
safety from the numpy reference of :meth:`MoverField.unsafe_pairs`); ``"compiled"`` runs the
same loop in machine code (:func:`gfuzzy.timespace.search_kernel.sipp_compiled`, its safety
from the compiled kernels). Same arguments, same answers. The roadmap-time search and the
retiming chains of the stages (:mod:`gfuzzy.planner.retime`) choose theirs here.
"""

from __future__ import annotations

from .movers import MoverField

__all__ = ["BACKENDS", "search_function", "compile_if_cold", "field_for"]

#: Implementations of the search (PlanOptions.backend).
BACKENDS = ("compiled", "reference")


def search_function(backend: str):
    """The search of ``backend``; numba loads only for the compiled one."""
    if backend == "reference":
        from .timespace import sipp

        return sipp
    from .jit import note_cold

    note_cold()
    from .search_kernel import sipp_compiled

    return sipp_compiled


_compiled: list = []  # compile_if_cold ran in this process


def compile_if_cold() -> bool:
    """On a fresh installation (:func:`gfuzzy.timespace.jit.cold`: no precompiled extension,
    no numba cache) compile the search kernels now, once per process, outside any planning
    budget: a fresh ``pip install``'s first ``gfuzzy plan`` of the building floor answered
    ``timeout`` after 2 minutes on a busy 2-core machine, its 60 s spent compiling.
    ``Planner.plan`` calls this (the navigator warms them before its budget too).
    Otherwise nothing: loading the kernels (the extension, or numba's cache) stays in the
    first query's time, as measured. Whether it compiled them."""
    if _compiled:
        return False
    _compiled.append(True)
    from .jit import cold, note_cold

    if not cold():
        return False
    note_cold()
    from . import graph_kernel, search_kernel

    search_kernel.warm()
    graph_kernel.warm()
    return True


def field_for(field_: MoverField, backend: str) -> MoverField:
    """``field_`` with the safety kernels of ``backend`` (:attr:`MoverField.compiled`)."""
    field_.compiled = backend == "compiled"
    return field_
