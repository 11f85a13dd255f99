"""gfuzzy: roadmap-time-space motion planning among moving obstacles.

Pipeline (one module per stage): :mod:`~gfuzzy.scene.scene` -> :mod:`~gfuzzy.roadmap.roadmap` ->
:mod:`~gfuzzy.timespace.timespace` -> :mod:`~gfuzzy.ga` -> :mod:`~gfuzzy.fuzzy.fuzzy` ->
:mod:`~gfuzzy.trajectory`; :mod:`~gfuzzy.planner.planner` runs it, :mod:`~gfuzzy.check.check` verifies
the answer independently.
"""

import importlib
import logging

logging.getLogger(__name__).addHandler(logging.NullHandler())

__version__ = "0.1.0"

#: Where each public name lives: imported on first use (PEP 562), so that ``import gfuzzy``
#: itself is light and the command line's entry point (:mod:`gfuzzy.__main__`) runs before
#: the heavy imports (numpy, FCL, OMPL), which a Ctrl-C may then cut like any later step.
_HOMES = {
    "CheckReport": ".check.check",
    "check_trajectory": ".check.check",
    "GfuzzyError": ".errors",
    "SceneError": ".errors",
    "Navigator": ".navigation.navigator",
    "NavOptions": ".navigation.navigator",
    "NavStep": ".navigation.navigator",
    "Planner": ".planner.planner",
    "PlanOptions": ".planner.planner",
    "PlanResult": ".planner.planner",
    "Status": ".planner.planner",
    "plan": ".planner.planner",
    "Roadmap": ".roadmap.roadmap",
    "RoadmapOptions": ".roadmap.roadmap",
    "build_roadmap": ".roadmap.roadmap",
    "load_roadmap": ".roadmap.roadmap",
    "Scene": ".scene.scene",
    "load_scene": ".scene.scene",
    "parse_scene": ".scene.scene",
    "Track": ".scene.tracks",
    "Tracks": ".scene.tracks",
    "TrackScene": ".scene.tracks",
    "TrackSceneOptions": ".scene.tracks",
    "read_tracks": ".scene.tracks",
    "tracks_scene": ".scene.tracks",
    "Trajectory": ".trajectory",
    "load_trajectory": ".trajectory",
}
__all__ = sorted(_HOMES)


def __getattr__(name: str):
    """A public name, imported from its module the first time it is asked for; or a
    subpackage or module of gfuzzy's (``gfuzzy.errors``, ``gfuzzy.scene``), imported then as
    ``import gfuzzy`` used to import them all."""
    home = _HOMES.get(name)
    if home is None:
        return submodule(__name__, name)
    value = getattr(importlib.import_module(home, __name__), name)
    globals()[name] = value
    return value


def submodule(package: str, name: str):
    """The module ``<package>.<name>`` imported (which binds it in its package), or the
    AttributeError of a name that is none of the package's modules: what a package's
    ``__getattr__`` answers for a name it does not hold itself."""
    missing = AttributeError(f"module {package!r} has no attribute {name!r}")
    if name.startswith("__"):  # (what tools probe for: __wrapped__, __loader__, ...)
        raise missing
    try:
        return importlib.import_module(f"{package}.{name}")
    except ModuleNotFoundError as exc:
        if exc.name != f"{package}.{name}":  # a module it imports is missing: that error
            raise
        raise missing from None


def __dir__() -> list[str]:
    import pkgutil

    modules = {m.name for m in pkgutil.iter_modules(__path__) if not m.name.startswith("_")}
    return sorted({*globals(), *_HOMES, *modules})
