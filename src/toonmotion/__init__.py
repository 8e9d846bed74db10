"""toonmotion: 2D character animation from one drawing.

The library is layered (see ``docs/architecture.md``): ``geometry`` < ``shape`` < ``rig`` <
``deform`` < ``animate`` < ``capture`` < ``io`` and ``render`` < :mod:`toonmotion.api` < ``cli``.
The public API (:mod:`toonmotion.api`) is re-exported here, loaded on first use so that
``import toonmotion`` stays light::

    import toonmotion
    hero = toonmotion.rig_image("hero.png", skeleton="hero.json")
    toonmotion.save_project("hero", hero)
"""

from importlib import import_module
from typing import Any

from toonmotion.errors import ToonmotionError

__version__ = "0.1.0"

_API = (
    "Animation", "Balloon", "Balls", "Capture", "Character", "ContourCapture", "DeformSettings",
    "EnvironmentItem", "Exported", "FilterSettings", "KeyShapeSpace", "LiftReport", "Markers", "Motion",
    "PoorlyMatched",
    "PosedFrame", "Proxy",
    "RigSettings", "SameDepthOverlap", "SceneMotion", "SketchMatch", "TrackSettings", "VideoCapture",
    "animate_character", "animate_drawing", "animation_frames", "border_colour", "capture_contours",
    "capture_parts",
    "capture_video", "carry_keys", "composite_scene", "correct_regions", "delete_key", "drag_joint",
    "exaggerate",
    "environment_report", "export_animation",
    "export_format", "figure_box", "filter_motion",
    "keyshape_sheet", "keyshape_space", "lift_proxy", "lift_warnings", "load_project", "motion_in_frames",
    "move_key",
    "pick_layer", "pose_character", "pose_view", "preview_proxy", "project_mocap", "redo_edits",
    "render_elements",
    "render_pose", "retarget", "retarget_keyposes", "retarget_keyshapes", "retarget_line_of_action",
    "retarget_parts", "retime", "rig_again", "rig_image", "rotate_joint", "same_depth_overlaps",
    "save_project", "scene_passes", "set_depth", "set_key", "simulate_scene", "sketch_pose",
    "setup_warnings", "suggest_joints", "suggested_sizes", "track_footage", "undo_edits", "write_animation",
)

__all__ = ["ToonmotionError", "__version__", *_API]


def __getattr__(name: str) -> Any:
    if name in _API:
        return getattr(import_module("toonmotion.api"), name)
    raise AttributeError(f"module 'toonmotion' has no attribute {name!r}")
