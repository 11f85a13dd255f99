"""Files for the robotics tools: MCAP for Foxglove and Lichtblick, Nav2 maps."""


def __getattr__(name: str):
    # `gfuzzy.export.X` was the flat module gfuzzy/export.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one); so do the
    # package's modules, as eager imports once made them
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    from .. import submodule

    flat = import_module(".export", __name__)
    return getattr(flat, name) if hasattr(flat, name) else submodule(__name__, name)
