"""Tests for toonmotion.io.drawing_folder: Animated Drawings character folders."""

import numpy as np
import pytest

from toonmotion.errors import ImageReadError, MaskError, SkeletonError
from toonmotion.io.char_cfg import load_char_cfg, save_char_cfg
from toonmotion.io.drawing_folder import DrawingFolder, load_drawing_folder, rig_drawing_folder
from toonmotion.io.image import load_image, load_mask, save_png
from toonmotion.rig.character import RigSettings
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character

SMALL = RigSettings(vertices=300)


@pytest.fixture(scope="module")
def sample():
    return sample_character(scale=0.5)


def _folder(path, rgba, skeleton=None, mask=None, size=None):
    path.mkdir(exist_ok=True)
    save_png(path / "texture.png", rgba)
    if skeleton is not None:
        save_char_cfg(path / "char_cfg.yaml", skeleton, size or (rgba.shape[1], rgba.shape[0]))
    if mask is not None:
        save_png(path / "mask.png", mask)
    return path


def test_every_shared_drawing_folder_reads_its_three_files(drawing_dir):
    drawing = load_drawing_folder(drawing_dir)
    assert isinstance(drawing, DrawingFolder)
    np.testing.assert_array_equal(drawing.texture, load_image(drawing_dir / "texture.png"))
    size = (drawing.texture.shape[1], drawing.texture.shape[0])
    np.testing.assert_array_equal(drawing.mask, load_mask(drawing_dir / "mask.png", size=size))
    skeleton, cfg_size = load_char_cfg(drawing_dir / "char_cfg.yaml")
    assert cfg_size == size and drawing.skeleton.names == skeleton.names
    np.testing.assert_array_equal(drawing.skeleton.positions, skeleton.positions)
    np.testing.assert_array_equal(drawing.skeleton.parents, skeleton.parents)


def test_rigging_a_folder_is_rigging_its_contents(tmp_path, sample):
    rgba, skeleton = sample
    mask = rgba[..., 3] >= 128
    folder = _folder(tmp_path / "hero", rgba, skeleton, mask)
    drawing = load_drawing_folder(folder)
    np.testing.assert_array_equal(drawing.mask, mask)
    character = rig_drawing_folder(folder, settings=SMALL)
    expected = rig_drawing(rgba, mask=mask, skeleton=drawing.skeleton, settings=SMALL)
    np.testing.assert_array_equal(character.mesh.V, expected.mesh.V)
    np.testing.assert_array_equal(character.mesh.F, expected.mesh.F)
    assert character.skeleton.names == skeleton.names


def test_mask_and_skeleton_are_optional(tmp_path, sample):
    rgba, _ = sample
    drawing = load_drawing_folder(_folder(tmp_path / "bare", rgba))
    assert drawing.mask is None and drawing.skeleton is None
    np.testing.assert_array_equal(drawing.texture, rgba)
    stages = []
    character = rig_drawing_folder(tmp_path / "bare", settings=SMALL,
                                   progress=lambda stage, index, count: stages.append(stage))
    assert len(character.skeleton) > 1 and stages[0] == "mask"  # skeleton built along the curve skeleton


def test_a_folder_without_a_texture_is_refused(tmp_path):
    with pytest.raises(ImageReadError, match=r"nowhere is not a folder; give a character folder holding"):
        load_drawing_folder(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ImageReadError, match=r"empty has no texture.png; give a character folder"):
        rig_drawing_folder(tmp_path / "empty")


def test_a_skeleton_or_mask_for_another_drawing_is_refused(tmp_path, sample):
    rgba, skeleton = sample
    _folder(tmp_path / "cfg", rgba, skeleton, size=(rgba.shape[1] + 10, rgba.shape[0]))
    with pytest.raises(SkeletonError, match=r"char_cfg.yaml was made for a \d+x\d+ drawing but this one is"):
        load_drawing_folder(tmp_path / "cfg")
    _folder(tmp_path / "mask", rgba, mask=np.ones((5, 5), bool))
    with pytest.raises(MaskError, match=r"mask mask.png is 5x5 but the drawing is"):
        load_drawing_folder(tmp_path / "mask")
