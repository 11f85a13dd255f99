"""gfuzzy: roadmap-time-space motion planning among moving obstacles.

Pipeline (one module per stage): :mod:`~gfuzzy.scene.scene` -> :mod:`~gfuzzy.roadmap.roadmap` ->
:mod:`~gfuzzy.timespace.timespace` -> :mod:`~gfuzzy.ga` -> :mod:`~gfuzzy.fuzzy.fuzzy` ->
:mod:`~gfuzzy.trajectory`; :mod:`~gfuzzy.planner.planner` runs it, :mod:`~gfuzzy.check.check` verifies
the answer independently.
"""

import logging

from .check.check import CheckReport, check_trajectory
from .errors import GfuzzyError, SceneError
from .navigation.navigator import Navigator, NavOptions, NavStep
from .planner.planner import Planner, PlanOptions, PlanResult, Status, plan
from .roadmap.roadmap import Roadmap, RoadmapOptions, build_roadmap, load_roadmap
from .scene.scene import Scene, load_scene, parse_scene
from .scene.tracks import Track, Tracks, TrackScene, TrackSceneOptions, read_tracks, tracks_scene
from .trajectory import Trajectory, load_trajectory

logging.getLogger(__name__).addHandler(logging.NullHandler())

__version__ = "0.1.0"

__all__ = [
    "CheckReport",
    "GfuzzyError",
    "NavOptions",
    "NavStep",
    "Navigator",
    "PlanOptions",
    "PlanResult",
    "Planner",
    "Roadmap",
    "RoadmapOptions",
    "Scene",
    "SceneError",
    "Status",
    "Track",
    "TrackScene",
    "TrackSceneOptions",
    "Tracks",
    "Trajectory",
    "build_roadmap",
    "check_trajectory",
    "load_roadmap",
    "load_scene",
    "load_trajectory",
    "parse_scene",
    "plan",
    "read_tracks",
    "tracks_scene",
]
