"""The two implementations of the safe-interval search (``PlanOptions.backend``).

``"reference"`` is the pure-Python definition (:func:`gfuzzy.timespace.timespace.sipp`, its
safety from the numpy reference of :meth:`MoverField.unsafe_pairs`); ``"compiled"`` runs the
same loop in machine code (:func:`gfuzzy.timespace.search_kernel.sipp_compiled`, its safety
from the compiled kernels). Same arguments, same answers. The roadmap-time search and the
retiming chains of the stages (:mod:`gfuzzy.planner.retime`) choose theirs here.
"""

from __future__ import annotations

from .movers import MoverField

__all__ = ["BACKENDS", "search_function", "field_for"]

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


def field_for(field_: MoverField, backend: str) -> MoverField:
    """``field_`` with the safety kernels of ``backend`` (:attr:`MoverField.compiled`)."""
    field_.compiled = backend == "compiled"
    return field_
