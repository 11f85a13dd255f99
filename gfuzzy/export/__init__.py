"""Files for the robotics tools: MCAP for Foxglove and Lichtblick, Nav2 maps."""


def __getattr__(name: str):
    # `gfuzzy.export.X` was the flat module gfuzzy/export.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one)
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    return getattr(import_module(".export", __name__), name)
