"""The fuzzy speed layer: the Mamdani controller, its rule bases, speed profiles."""


def __getattr__(name: str):
    # `gfuzzy.fuzzy.X` was the flat module gfuzzy/fuzzy.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one); so do the
    # package's modules, as eager imports once made them
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    from .. import submodule

    flat = import_module(".fuzzy", __name__)
    return getattr(flat, name) if hasattr(flat, name) else submodule(__name__, name)
