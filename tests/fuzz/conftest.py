"""The generated-bad-input suite's profiles, valid starting files, and its report.

Two Hypothesis profiles: ``quick`` (the default; a few derandomized cases per test, run by
``make test``) and ``long`` (``make fuzz``: ``TOONMOTION_FUZZ_EXAMPLES`` cases per test, 400 by
default), which also writes the count of runs per format and outcome to ``fuzz-report.json``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

from tests.fuzz.harness import TALLY
from toonmotion import api
from toonmotion.animate.timeline import Keyframe, make_timeline
from toonmotion.capture.footage import suggest_joints
from toonmotion.io.char_cfg import save_char_cfg
from toonmotion.io.image import save_png
from toonmotion.io.keyshape_json import save_contours, save_model
from toonmotion.io.motion_json import save_motion
from toonmotion.io.pose_json import save_keyframes, save_pose
from toonmotion.io.skeleton_json import save_skeleton_json
from toonmotion.io.sketch_json import save_sketch
from toonmotion.io.track_json import save_joints
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.samples import sample_character, sample_character_on

_COMMON = dict(deadline=None, suppress_health_check=list(HealthCheck), print_blob=True)
settings.register_profile("quick", max_examples=12, derandomize=True, **_COMMON)
settings.register_profile(
    "long", max_examples=int(os.environ.get("TOONMOTION_FUZZ_EXAMPLES", "400")), **_COMMON
)
settings.load_profile(os.environ.get("TOONMOTION_FUZZ_PROFILE", "quick"))

@pytest.fixture(scope="session", autouse=True)
def _report():
    yield
    if os.environ.get("TOONMOTION_FUZZ_PROFILE") == "long":
        report = {f"{kind} {result}": n for (kind, result), n in sorted(TALLY.items())}
        Path(os.environ.get("TOONMOTION_FUZZ_REPORT", "fuzz-report.json")).write_text(
            json.dumps(report, indent=1) + "\n"
        )


@pytest.fixture(scope="session")
def valid(tmp_path_factory):
    """A folder of valid files of every kind, made from a half-size sample character."""
    folder = tmp_path_factory.mktemp("valid")
    rgba, skeleton = sample_character(scale=0.5)
    size = (rgba.shape[1], rgba.shape[0])
    save_png(folder / "hero.png", rgba)
    save_skeleton_json(folder / "hero.json", skeleton, size)
    save_char_cfg(folder / "hero.yaml", skeleton, size)
    hero = api.rig_image(rgba, skeleton=skeleton)
    api.save_project(folder / "P", hero)
    bent = Pose(rotate_about(skeleton, skeleton.positions, skeleton.names[-1], 0.4))
    save_pose(folder / "pose.json", skeleton, bent)
    bones = [bent.positions[[i, j]] for i, j in skeleton.bones]
    stick = [np.linspace(a, b, 5) for a, b in bones if np.ptp([a, b], axis=0).any()]
    save_sketch(folder / "sketch.json", stick[-3:])  # the last three bones of some length
    outline = hero.mesh.V[hero.mesh.boundary[0][::8]]
    base = np.array([outline[:, 0].mean(), outline[:, 1].max()])
    bulge = 1 + 0.3 * np.sin(np.pi * (base[1] - outline[:, 1]) / np.ptp(outline[:, 1]))
    keys = np.stack([outline, base + (outline - base) * np.stack([bulge, np.full(len(bulge), 0.8)], axis=1)])
    save_contours(folder / "contours.json", keys)
    save_model(folder / "model.json", api.keyshape_space(keys, inbetweens=2))
    timeline = make_timeline(skeleton, [Keyframe(0, Pose(skeleton.positions)), Keyframe(2, bent)], fps=12.0)
    save_keyframes(folder / "keys.json", skeleton, timeline)
    save_motion(folder / "motion.json", api.animate_character(hero, timeline).motion)
    picture = sample_character_on("white", scale=0.25)[0]
    frames = np.stack([np.roll(picture, 2 * t, axis=1) for t in range(3)])
    (folder / "frames").mkdir()
    for t, frame in enumerate(frames):
        save_png(folder / "frames" / f"f_{t}.png", frame)
    small, sizes = suggest_joints(frames)
    save_joints(folder / "joints.json", small, sizes)
    return folder
