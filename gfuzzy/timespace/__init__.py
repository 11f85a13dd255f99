"""The roadmap-time search: movers on the time grid, safe intervals, the safe-interval A* (reference and compiled, precompiled ahead of time), what queries share of the roadmap, a differential drive's graph of heading copies."""


def __getattr__(name: str):
    # `gfuzzy.timespace.X` was the flat module gfuzzy/timespace.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one); so do the
    # package's modules, as eager imports once made them
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    from .. import submodule

    flat = import_module(".timespace", __name__)
    return getattr(flat, name) if hasattr(flat, name) else submodule(__name__, name)
