"""Pictures and animations of scenes and trajectories."""


def __getattr__(name: str):
    # `gfuzzy.render.X` was the flat module gfuzzy/render.py: its names stay reachable,
    # loaded on first use (so importing a sibling module never loads this one)
    if name.startswith("__"):
        raise AttributeError(name)
    from importlib import import_module

    return getattr(import_module(".render", __name__), name)
