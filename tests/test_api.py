"""Tests for toonmotion.api, the public library surface the CLI and the editor call."""

import subprocess
import sys

import numpy as np
import pytest

import toonmotion
from toonmotion import api
from toonmotion.animate.pose_filter import exaggerate_pose
from toonmotion.deform.deformer import Deformer
from toonmotion.errors import SettingsError
from toonmotion.io.char_cfg import save_char_cfg
from toonmotion.io.image import save_png
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@pytest.fixture(scope="module")
def hero():
    rgba, skeleton = sample_character()
    return rig_drawing(rgba, skeleton=skeleton)


def test_the_package_re_exports_exactly_the_api_and_the_types_a_user_builds():
    assert toonmotion.__all__ == ["ToonmotionError", "__version__", *api.__all__]
    for name in api.__all__:
        assert getattr(toonmotion, name) is getattr(api, name)
    # The types the README and the docs tell users to construct are among them.
    assert {"Deformer", "DeformSettings", "RigSettings", "TrackSettings", "FilterSettings", "CameraWeights",
            "SkeletonWeights", "Balloon", "Balls", "Scarf", "Skirt", "Rain"} <= set(api.__all__)
    # Nothing else: every name is a function or class of the library, none a module.
    for name in api.__all__:
        value = getattr(api, name)
        assert not isinstance(value, type(api)) and value.__module__.startswith("toonmotion."), name
    namespace: dict[str, object] = {}
    exec("from toonmotion import *", namespace)
    assert set(api.__all__) <= set(namespace)
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        toonmotion.nope  # noqa: B018


def test_the_docs_api_reference_lists_every_name_of_the_api(tmp_path):
    """The site's API reference (docs/reference.md, rendered by mkdocstrings) has an entry for every
    name of toonmotion.api, and the site builds with --strict."""
    import os
    import zlib
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    build = [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "--site-dir", str(tmp_path)]
    subprocess.run(build, cwd=root, check=True, env=env)
    inventory = (tmp_path / "objects.inv").read_bytes()
    listed = zlib.decompress(inventory.split(b"\n", 4)[4]).decode()
    # Each entry: canonical name, role, priority, page#anchor, title; the anchor is the name documented.
    names = {line.split()[3].partition("#")[2] for line in listed.splitlines() if line.strip()}
    assert {f"toonmotion.api.{n}" for n in api.__all__} <= names


def test_importing_the_package_does_not_load_the_heavy_libraries():
    code = "import sys, toonmotion; print(sorted(m for m in ('cv2', 'scipy', 'skimage') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_rig_from_files_is_rig_drawing_on_what_they_hold(hero, tmp_path):
    rgba, skeleton = sample_character()
    save_png(tmp_path / "hero.png", rgba)
    save_char_cfg(tmp_path / "hero.yaml", skeleton, (rgba.shape[1], rgba.shape[0]))
    from_files = api.rig_image(tmp_path / "hero.png", skeleton=tmp_path / "hero.yaml")
    np.testing.assert_array_equal(from_files.mesh.V, hero.mesh.V)
    np.testing.assert_array_equal(from_files.binding.bone, hero.binding.bone)


def test_posing_the_rest_pose_gives_the_rest_mesh(hero):
    frame = api.pose_character(hero, api.rotate_joint(hero, "right_elbow", 0.0))
    np.testing.assert_allclose(frame.deformation.U, hero.mesh.V, atol=1e-9)


def test_a_deformer_can_be_passed_instead_of_the_character(hero):
    posed = api.rotate_joint(hero, "left_elbow", -0.7)
    a = api.pose_character(hero, posed).deformation.U
    b = api.pose_character(Deformer(hero), posed).deformation.U
    np.testing.assert_array_equal(a, b)


def test_the_single_frame_filter_is_applied_before_deforming(hero):
    rest = api.rotate_joint(hero, "right_elbow", 0.0)
    frame = api.pose_character(hero, rest, accel=(0.0, -40.0), fixed=("right_foot", "left_foot"))
    expected = exaggerate_pose(hero.skeleton, rest, (0.0, -40.0), ("right_foot", "left_foot"))
    np.testing.assert_array_equal(frame.pose.positions, expected.positions)
    feet = [hero.skeleton.index(n) for n in ("right_foot", "left_foot")]
    np.testing.assert_array_equal(frame.pose.positions[feet], hero.skeleton.positions[feet])


def test_render_grows_the_picture_to_hold_the_posed_figure(hero):
    frame = api.pose_character(hero, api.rotate_joint(hero, "right_shoulder", 2.5))
    x0, y0, x1, y1 = api.pose_view(hero, frame)
    picture = api.render_pose(hero, frame)
    assert picture.shape[:2] == (int(np.ceil(y1 - y0)), int(np.ceil(x1 - x0)))
    assert picture[..., 3].any()


def test_animate_takes_key_frames_or_a_motion(hero):
    timeline = sample_keyframes(hero.skeleton)
    from_keys = api.animate_character(hero, timeline)
    from_motion = api.animate_character(hero, from_keys.motion)
    assert len(from_keys.meshes) == len(from_motion.meshes) == timeline.frame_count
    np.testing.assert_array_equal(from_motion.motion.positions, from_keys.motion.positions)
    assert from_keys.keys == timeline.keys and from_motion.keys == ()


def test_filter_motion_with_zero_strength_changes_nothing(hero):
    motion = api.animate_character(hero, sample_keyframes(hero.skeleton)).motion
    np.testing.assert_allclose(api.filter_motion(motion, 0.0).positions, motion.positions, atol=1e-12)


def test_capture_needs_both_corrections_and_their_frame_to_correct(hero):
    frames = np.zeros((3, 40, 40, 3), dtype=np.uint8)
    motion = api.animate_character(hero, sample_keyframes(hero.skeleton)).motion
    with pytest.raises(SettingsError, match="needs the corrections and the frame"):
        api.track_footage(
            frames, joints=(hero.skeleton, np.full((len(hero.skeleton), 2), 9.0)), earlier=motion
        )


@pytest.mark.parametrize("name", [n for n in api.__all__ if n[0].islower()])
def test_every_api_function_documents_its_parameters_and_shows_an_example(name):
    doc = getattr(api, name).__doc__
    sections = {line.strip() for line in doc.splitlines()}
    assert {"Parameters", "Examples"} <= sections, f"{name} lacks Parameters or Examples"
    if getattr(api, name).__annotations__.get("return") not in ("None", None):
        assert "Returns" in sections, f"{name} does not say what it returns"
    assert ">>> " in doc or "See :func:" in doc
