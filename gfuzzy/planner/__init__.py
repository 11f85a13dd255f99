"""A query end to end: the planner, the stages after the search (GA, speed layer), re-timing, goals prepared for many starts, a differential drive's simple motions."""


def __getattr__(name: str):
    # `gfuzzy.planner.X` was the flat module gfuzzy/planner.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one); so do the
    # package's modules, as eager imports once made them
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    from .. import submodule

    flat = import_module(".planner", __name__)
    return getattr(flat, name) if hasattr(flat, name) else submodule(__name__, name)
