"""Tests for toonmotion.rig.pipeline, including the project's acceptance criteria.

On every shared drawing:
(a) rigging from texture.png alone gives a silhouette with IoU >= 0.95 against mask.png;
(b) rigging with mask.png and char_cfg.yaml keeps every triangle inside the mask's outline
    (grown by the simplification tolerance) and gives a sound mesh;
(c) its char_cfg.yaml loads: 16 joints, named as in the file;
(d) every vertex is attached to a bone.
"""

import functools

import numpy as np
import pytest
import shapely
import yaml
from skimage.draw import polygon as fill_polygon

from toonmotion.errors import MaskError, SettingsError, SkeletonError
from toonmotion.io.image import load_image, load_mask
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.rig import pipeline
from toonmotion.rig.character import Character, RigSettings
from toonmotion.rig.pipeline import STAGES, rig_drawing
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.mesh import check_mesh
from toonmotion.shape.silhouette import trace_silhouette

MIN_IOU = 0.95
SMALL = RigSettings(vertices=300)


@functools.cache
def _rig_texture_only(folder):
    return rig_drawing(load_image(f"{folder}/texture.png"))


@functools.cache
def _rig_with_mask_and_skeleton(folder):
    texture = load_image(f"{folder}/texture.png")
    size = (texture.shape[1], texture.shape[0])
    mask = load_mask(f"{folder}/mask.png", size=size)
    skeleton = load_skeleton_file(f"{folder}/char_cfg.yaml", image_size=size)
    return rig_drawing(texture, mask=mask, skeleton=skeleton), mask


def rasterise(silhouette, shape):
    """Pixels whose centres lie inside the silhouette (outer loops minus holes)."""
    out = np.zeros(shape, dtype=bool)
    for part in silhouette.parts:
        filled = np.zeros(shape, dtype=bool)
        rows, cols = fill_polygon(part.outer[:, 1], part.outer[:, 0], shape)
        filled[rows, cols] = True
        for hole in part.holes:
            rows, cols = fill_polygon(hole[:, 1], hole[:, 0], shape)
            filled[rows, cols] = False
        out |= filled
    return out


def iou(a, b):
    return np.count_nonzero(a & b) / np.count_nonzero(a | b)


# --- acceptance criteria on the shared drawings -----------------------------------------------


def test_a_silhouette_from_texture_alone_matches_the_mask(drawing_dir, record_property):
    character = _rig_texture_only(str(drawing_dir))
    truth = load_mask(drawing_dir / "mask.png")
    score = iou(rasterise(character.silhouette, truth.shape), truth)
    record_property("iou", score)
    print(f"\n{drawing_dir.name}: silhouette IoU {score:.4f}")
    assert score >= MIN_IOU


def test_b_every_triangle_lies_inside_the_mask(drawing_dir):
    character, mask = _rig_with_mask_and_skeleton(str(drawing_dir))
    mesh = character.mesh
    assert check_mesh(mesh) == []
    np.testing.assert_array_equal(character.mask, mask)  # the mask is clean: nothing dropped
    outline = trace_silhouette(mask, tolerance=0).to_shapely()
    allowed = outline.buffer(character.silhouette.tolerance + 1e-6)
    triangles = shapely.polygons(mesh.V[mesh.F])
    outside = ~shapely.covers(allowed, triangles)
    assert not outside.any(), f"{outside.sum()} triangles leave the mask, e.g. {mesh.F[outside][0]}"
    # The mesh fills the figure: its area is the silhouette's.
    assert shapely.area(triangles).sum() == pytest.approx(character.silhouette.area, rel=1e-9)


def test_c_char_cfg_loads_with_the_files_joints(drawing_dir):
    data = yaml.safe_load((drawing_dir / "char_cfg.yaml").read_text())
    texture = load_image(drawing_dir / "texture.png")
    skeleton = load_skeleton_file(
        drawing_dir / "char_cfg.yaml", image_size=(texture.shape[1], texture.shape[0])
    )
    assert len(skeleton) == 16
    assert sorted(skeleton.names) == sorted(j["name"] for j in data["skeleton"])
    for joint in data["skeleton"]:
        i = skeleton.index(joint["name"])
        parent = skeleton.parents[i]
        assert (skeleton.names[parent] if parent >= 0 else None) == joint["parent"]
        np.testing.assert_array_equal(skeleton.positions[i], joint["loc"])


def test_d_every_vertex_is_attached_to_a_bone(drawing_dir):
    character, _ = _rig_with_mask_and_skeleton(str(drawing_dir))
    n = len(character.mesh.V)
    bone = character.binding.bone
    assert bone.shape == (n,)
    assert bone.min() >= 0 and bone.max() < len(character.skeleton.bones)
    # Zero-length bones (the char_cfg's root -> hip) get no vertices.
    lengths = character.skeleton.bone_lengths
    assert np.all(lengths[np.unique(bone)] > 0)


def test_auto_skeleton_on_drawings_lies_within_the_figure(drawing_dir):
    character = _rig_texture_only(str(drawing_dir))
    _check_auto_skeleton(character)


def _check_auto_skeleton(character):
    skeleton = character.skeleton
    assert len(skeleton.bones) >= 1
    assert np.all(skeleton.bone_lengths > 0)
    rows, cols = np.nonzero(character.mask)
    x, y = skeleton.positions.T
    assert np.all((x >= cols.min()) & (x <= cols.max()))
    assert np.all((y >= rows.min()) & (y <= rows.max()))


# --- synthetic drawings ------------------------------------------------------------------------


def _disk(shape, centre, radius):
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    return np.hypot(xx - centre[0], yy - centre[1]) <= radius


def _figure(shape=(64, 72)):
    """A blob with two arms: a disk and a horizontal bar through it."""
    mask = _disk(shape, (36, 32), 14)
    mask[28:37, 8:64] = True
    return mask


def _rgba(mask, seed=0):
    rng = np.random.default_rng(seed)
    rgba = rng.integers(0, 256, size=(*mask.shape, 4), dtype=np.uint8)
    rgba[..., 3] = np.where(mask, 255, 0)
    return rgba


def test_rgba_drawing_rigs_with_alpha_as_the_mask():
    mask = _figure()
    rgba = _rgba(mask)
    rgba[mask, 3] = 200  # partly transparent figure still counts (alpha >= 128)
    character = rig_drawing(rgba, settings=SMALL)
    assert isinstance(character, Character)
    np.testing.assert_array_equal(character.mask, mask)
    np.testing.assert_array_equal(character.texture, rgba)
    assert character.size == (72, 64)
    assert character.settings == SMALL
    assert abs(len(character.mesh.V) - 300) <= 0.1 * 300
    assert check_mesh(character.mesh) == []
    _check_auto_skeleton(character)


def test_rgb_on_flat_white_is_segmented():
    mask = _figure()
    rgb = np.full((*mask.shape, 3), 255, dtype=np.uint8)
    rgb[mask] = (200, 40, 30)
    rgb[30:34, 30:40] = (20, 20, 20)  # some dark detail inside
    character = rig_drawing(rgb, settings=SMALL)
    np.testing.assert_array_equal(character.mask, mask)
    assert character.texture.shape == (*mask.shape, 4)
    np.testing.assert_array_equal(character.texture[..., :3], rgb)
    assert np.all(character.texture[..., 3] == 255)


def test_opaque_rgba_is_segmented_like_rgb():
    mask = _figure()
    rgba = np.full((*mask.shape, 4), 255, dtype=np.uint8)
    rgba[mask, :3] = (30, 60, 200)
    character = rig_drawing(rgba, settings=SMALL)
    np.testing.assert_array_equal(character.mask, mask)


@pytest.mark.parametrize(
    ("mask", "message"),
    [
        (np.zeros((64, 72), dtype=bool), r"the mask is empty"),
        (np.ones((64, 72), dtype=bool), r"the mask covers the whole image"),
        (np.ones((72, 64), dtype=bool), r"the mask is 64x72 but the drawing is 72x64"),
    ],
    ids=["empty", "everything", "wrong-size"],
)
def test_bad_masks_raise_mask_error(mask, message):
    with pytest.raises(MaskError, match=message) as info:
        rig_drawing(_rgba(_figure()), mask=mask, settings=SMALL)
    assert "\n" not in str(info.value)


def test_fully_transparent_drawing_raises_mask_error():
    with pytest.raises(MaskError, match="the alpha channel is empty"):
        rig_drawing(_rgba(np.zeros((20, 20), dtype=bool)), settings=SMALL)


def test_blank_rgb_drawing_raises_mask_error():
    with pytest.raises(MaskError, match="is empty"):
        rig_drawing(np.full((20, 20, 3), 255, dtype=np.uint8), settings=SMALL)


def test_joint_far_outside_the_drawing_is_named():
    skeleton = Skeleton.from_joints(
        [
            ("body", None, (36.0, 32.0)),
            ("arm", "body", (60.0, 32.0)),
            ("balloon", "body", (1036.0, 32.0)),
        ]
    )
    message = r"joint 'balloon' at \(1036, 32\) is 973 px from the figure"
    with pytest.raises(SkeletonError, match=message) as info:
        rig_drawing(_rgba(_figure()), skeleton=skeleton, settings=SMALL)
    assert "is the skeleton for this drawing" in str(info.value)


def test_joint_just_off_the_figure_is_accepted():
    skeleton = Skeleton.from_joints(
        [("body", None, (36.0, 32.0)), ("arm", "body", (66.0, 32.0))]  # bar ends at x = 63
    )
    character = rig_drawing(_rgba(_figure()), skeleton=skeleton, settings=SMALL)
    assert character.skeleton is skeleton


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"spacing": 4.0, "vertices": 300}, "give either a spacing or a vertex count"),
        ({"segmentation": "magic"}, r"segmentation must be one of auto, flat, paper, got 'magic'"),
        ({"tolerance": -1.0}, "tolerance must be between 0 and 100"),
        ({"min_part": 1.0}, r"min_part must be in \[0, 1\)"),
    ],
    ids=["spacing-and-vertices", "segmentation", "tolerance", "min-part"],
)
def test_bad_settings_raise_settings_error(settings, message):
    # RigSettings checks itself, so the error may come from building the settings.
    with pytest.raises(SettingsError, match=message):
        rig_drawing(_rgba(_figure()), settings=RigSettings(**settings))


def _bar_drawing():
    mask = np.zeros((40, 120), dtype=bool)
    mask[8:32, 5:115] = True
    skeleton = Skeleton.from_joints(
        [("a", None, (10.0, 20.0)), ("b", "a", (60.0, 20.0)), ("c", "b", (110.0, 20.0))]
    )
    return _rgba(mask), skeleton


def test_refine_joints_samples_denser_near_meeting_joints():
    rgba, skeleton = _bar_drawing()
    counts = {}
    for refine in (False, True):
        character = rig_drawing(
            rgba, skeleton=skeleton, settings=RigSettings(spacing=4.0, refine_joints=refine)
        )
        assert character.mesh.spacing == 4.0
        assert check_mesh(character.mesh) == []
        d = np.linalg.norm(character.mesh.V - [60.0, 20.0], axis=1)
        far = np.abs(character.mesh.V[:, 0] - 60.0) > 35
        counts[refine] = (np.count_nonzero(d < 10), np.count_nonzero(far))
    (near_plain, far_plain), (near_refined, far_refined) = counts[False], counts[True]
    # Half the spacing is four times the density; ask for at least twice.
    assert near_refined >= 2 * near_plain
    # Only the meeting joint b is refined, not the chain's ends a and c.
    assert abs(far_refined - far_plain) <= 0.1 * far_plain


def test_progress_is_reported_once_per_stage_in_order():
    calls = []
    rig_drawing(
        _rgba(_figure()), settings=SMALL, progress=lambda *args: calls.append(args)
    )
    assert calls == [(stage, i, len(STAGES)) for i, stage in enumerate(STAGES)]
    assert STAGES == pipeline.STAGES and len(STAGES) == 6


def test_auto_skeleton_has_bones_within_the_figure():
    character = rig_drawing(_rgba(_figure()), settings=SMALL)
    _check_auto_skeleton(character)
    assert character.skeleton.names[0] == "root"


def test_texture_must_be_uint8_image():
    with pytest.raises(ValueError, match="uint8"):
        rig_drawing(np.zeros((10, 10, 4), dtype=float))
