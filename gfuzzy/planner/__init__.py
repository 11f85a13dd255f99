"""A query end to end: the planner, the stages after the search (GA, speed layer), re-timing, goals prepared for many starts, a differential drive's simple motions."""


def __getattr__(name: str):
    # `gfuzzy.planner.X` was the flat module gfuzzy/planner.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one)
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    return getattr(import_module(".planner", __name__), name)
