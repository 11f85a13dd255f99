"""The fuzzy speed layer: the Mamdani controller, its rule bases, speed profiles."""


def __getattr__(name: str):
    # `gfuzzy.fuzzy.X` was the flat module gfuzzy/fuzzy.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one)
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    return getattr(import_module(".fuzzy", __name__), name)
