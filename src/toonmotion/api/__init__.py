"""toonmotion's public library API: the calls every front end makes.

The command line (:mod:`toonmotion.cli`) and the editor parse what the user gave, call one of
these, and report. Each is a thin, documented wrapper; the work sits in the layers below
(``docs/architecture.md``). They are re-exported from the package, so ``toonmotion.rig_image(...)`` works.

Examples
--------
>>> import numpy as np
>>> import toonmotion
>>> from toonmotion.samples import sample_character
>>> drawing, skeleton = sample_character()
>>> hero = toonmotion.rig_image(drawing, skeleton=skeleton)
>>> frame = toonmotion.pose_character(hero, toonmotion.rotate_joint(hero, "right_elbow", 0.8))
>>> frame.deformation.U.shape == hero.mesh.V.shape
True
>>> picture = toonmotion.render_pose(hero, frame)
>>> picture.dtype, picture.shape[2]
(dtype('uint8'), 4)
"""

from __future__ import annotations

from types import ModuleType

from toonmotion.animate.animation import Animation, SameDepthOverlap, exaggerate, same_depth_overlaps
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.animate.motion import Motion
from toonmotion.api.animation import (
    animate_character,
    carry_keys,
    delete_key,
    filter_motion,
    motion_in_frames,
    move_key,
    retime,
    set_key,
)
from toonmotion.api.capture import track_footage
from toonmotion.api.environment import EnvironmentItem, environment_report
from toonmotion.api.export import Exported, export_animation, export_format
from toonmotion.api.keyshape_retarget import (
    animate_drawing,
    retarget_keyposes,
    retarget_keyshapes,
    retarget_line_of_action,
    retarget_parts,
)
from toonmotion.api.keyshapes import (
    capture_contours,
    capture_parts,
    capture_video,
    keyshape_sheet,
    keyshape_space,
    pick_layer,
)
from toonmotion.api.posing import (
    PosedFrame,
    drag_joint,
    pose_character,
    pose_view,
    render_pose,
    rotate_joint,
    sketch_pose,
)
from toonmotion.api.proxy3d import lift_animation, lift_proxy, lift_warnings, preview_proxy, project_mocap
from toonmotion.api.rigging import correct_regions, redo_edits, rig_again, rig_image, set_depth, undo_edits
from toonmotion.api.scene3d import (
    animation_frames,
    composite_scene,
    render_elements,
    scene_passes,
    scene_warnings,
    simulate_scene,
)
from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.footage import (
    Capture,
    PoorlyMatched,
    figure_box,
    setup_warnings,
    suggest_joints,
    suggested_sizes,
)
from toonmotion.capture.foreground import border_colour
from toonmotion.capture.retarget import retarget
from toonmotion.capture.search_tuning import SearchTuning
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.io.project import load_project, save_project
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.space import KeyShapeSpace
from toonmotion.keyshape.video import VideoCapture
from toonmotion.proxy3d.camera_fit import CameraWeights
from toonmotion.proxy3d.lift import LiftReport
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton import SkeletonWeights
from toonmotion.render.sequence import write_animation
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.sketch import SketchMatch
from toonmotion.scene.elements import Balloon, Balls, Cape, Rain, Scarf, Skirt
from toonmotion.scene.simulate import SceneMotion

# The public API is what this module imports from the library (functions, classes, settings
# types), listed here, not by hand: ``toonmotion`` re-exports it, the docs' API reference renders
# it, and tests/test_api.py checks the three agree.
__all__ = sorted(
    name for name, value in globals().items()
    if not name.startswith("_") and not isinstance(value, ModuleType)
    and getattr(value, "__module__", "").startswith("toonmotion.")
)
