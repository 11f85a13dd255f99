"""The static roadmap: OMPL's PRM, certified edges, narrow passages, spanners, roadmap files."""


def __getattr__(name: str):
    # `gfuzzy.roadmap.X` was the flat module gfuzzy/roadmap.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one)
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    return getattr(import_module(".roadmap", __name__), name)
