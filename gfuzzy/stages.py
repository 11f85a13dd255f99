"""Stages after the search: GA refinement and the fuzzy speed layer (wired in later)."""

from __future__ import annotations


def apply_stages(planner, result, start, goal, t0, options, field_, t_begin):
    return result
