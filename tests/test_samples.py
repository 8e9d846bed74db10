import numpy as np
import pytest
from scipy import ndimage as ndi
from skimage.measure import euler_number

from toonmotion.samples import sample_character, sample_character_on
from toonmotion.shape.segment import clean_mask, segment_foreground

JOINT_NAMES = {
    "root",
    "hip",
    "torso",
    "neck",
    "head",
    *(f"{side}_{part}" for side in ("right", "left") for part in ("shoulder", "elbow", "hand")),
    *(f"{side}_{part}" for side in ("right", "left") for part in ("hip", "knee", "foot")),
}


@pytest.fixture(scope="module")
def character():
    return sample_character()


def _point(skeleton, name):
    return skeleton.positions[skeleton.index(name)]


def _iou(a, b):
    return np.count_nonzero(a & b) / np.count_nonzero(a | b)


def test_image_is_rgba_with_a_transparent_background(character):
    rgba, _ = character
    assert rgba.shape == (600, 420, 4)
    assert rgba.dtype == np.uint8
    alpha = rgba[..., 3]
    border = np.concatenate([alpha[0], alpha[-1], alpha[:, 0], alpha[:, -1]])
    assert np.all(border == 0)
    # Opaque figure, transparent background, partial alpha only on the anti-aliased edge.
    opaque = alpha == 255
    assert 0.3 < opaque.mean() < 0.7
    edge = (alpha > 0) & (alpha < 255)
    assert np.all(ndi.binary_dilation(opaque, iterations=2)[edge])
    assert np.all(~ndi.binary_dilation(alpha > 0, iterations=1) | (alpha < 255) | opaque)


def test_output_is_deterministic(character):
    rgba, skeleton = character
    again, skeleton_again = sample_character()
    assert rgba.tobytes() == again.tobytes()
    np.testing.assert_array_equal(skeleton.positions, skeleton_again.positions)
    paper, _ = sample_character_on("paper", seed=3)
    assert paper.tobytes() == sample_character_on("paper", seed=3)[0].tobytes()
    assert paper.tobytes() != sample_character_on("paper", seed=4)[0].tobytes()


def test_skeleton_has_the_animated_drawings_joints_and_a_head(character):
    _, skeleton = character
    assert set(skeleton.names) == JOINT_NAMES
    assert len(skeleton) == 17
    np.testing.assert_array_equal(_point(skeleton, "root"), _point(skeleton, "hip"))
    # right_* is the character's right: on the image's left.
    for part in ("shoulder", "elbow", "hand", "hip", "knee", "foot"):
        assert _point(skeleton, f"right_{part}")[0] < 210 < _point(skeleton, f"left_{part}")[0]
    # Head above shoulders above hips above knees above feet (y down).
    ys = [_point(skeleton, n)[1] for n in ("neck", "right_shoulder", "right_hip", "right_knee")]
    assert ys == sorted(ys) and ys[-1] < _point(skeleton, "right_foot")[1]


@pytest.mark.parametrize("threshold", [1, 128])
def test_figure_is_one_piece_without_holes(character, threshold):
    rgba, _ = character
    mask = rgba[..., 3] >= threshold
    _, count = ndi.label(mask, structure=np.ones((3, 3)))
    assert count == 1
    assert euler_number(mask, connectivity=2) == 1  # one part, no holes


def test_every_joint_is_on_the_figure(character):
    rgba, skeleton = character
    distance_to_figure = ndi.distance_transform_edt(rgba[..., 3] < 128)
    for name, (x, y) in zip(skeleton.names, skeleton.positions, strict=True):
        assert distance_to_figure[round(y), round(x)] <= 3, name


def test_arms_are_held_away_from_the_body(character):
    _, skeleton = character
    neck, hip = _point(skeleton, "neck"), _point(skeleton, "hip")
    axis = (hip - neck) / np.linalg.norm(hip - neck)
    for side in ("right", "left"):
        offset = _point(skeleton, f"{side}_hand") - neck
        distance = abs(offset[0] * axis[1] - offset[1] * axis[0])
        assert distance > 0.35 * 420, side  # well beyond the body's half width (~90 px)


def test_limbs_do_not_touch_each_other(character):
    rgba, skeleton = character
    mask = rgba[..., 3] >= 128
    # Between the hands and the body, and between the feet, is background.
    for side in ("right", "left"):
        hand = _point(skeleton, f"{side}_hand")
        hip = _point(skeleton, f"{side}_hip")
        x0, x1 = sorted((hand[0], hip[0]))
        y = round(hand[1]) + 45  # below the hand, beside the waist
        assert not mask[y, round(x0) : round(x1)].all()
    x0, x1 = _point(skeleton, "right_knee")[0], _point(skeleton, "left_knee")[0]
    assert not mask[round(_point(skeleton, "right_knee")[1]), round(x0) : round(x1)].all()


@pytest.mark.parametrize(("background", "min_iou"), [("white", 0.97), ("paper", 0.95)])
def test_segmentation_finds_the_figure(character, background, min_iou):
    rgba, _ = character
    rgb, _ = sample_character_on(background)
    assert rgb.shape == (600, 420, 3) and rgb.dtype == np.uint8
    found = clean_mask(segment_foreground(rgb))
    # Measured: white 0.991, paper 0.953 (the paper method grows its mask by about 2 px).
    assert _iou(found, rgba[..., 3] >= 128) >= min_iou


def test_backgrounds_look_as_described():
    white, _ = sample_character_on("white")
    assert np.all(white[0] == 255) and np.all(white[:, 0] == 255)
    paper, _ = sample_character_on("paper")
    border = np.concatenate([paper[0], paper[-1], paper[:, 0], paper[:, -1]]).astype(float)
    assert 200 < border.mean() < 250  # off-white
    assert border.std() > 2  # lit unevenly, with grain and noise
    assert border[:, 2].mean() < border[:, 0].mean()  # warm: less blue than red


def test_unknown_background_is_rejected():
    with pytest.raises(ValueError, match=r"background must be one of .*, got 'grey'"):
        sample_character_on("grey")


@pytest.mark.parametrize("scale", [0, -1, 100, "big"])
def test_bad_scale_is_rejected(scale):
    with pytest.raises(ValueError, match="scale must be"):
        sample_character(scale=scale)


def test_half_scale_halves_the_image_and_the_joints(character):
    rgba, skeleton = character
    half, half_skeleton = sample_character(scale=0.5)
    assert half.shape == (300, 210, 4)
    assert half_skeleton.names == skeleton.names
    np.testing.assert_allclose(half_skeleton.positions, skeleton.positions / 2)
    # The same drawing: its mask matches the full-size mask shrunk by 2 (up to the edge).
    shrunk = rgba[..., 3].reshape(300, 2, 210, 2).mean(axis=(1, 3)) >= 128
    assert _iou(half[..., 3] >= 128, shrunk) > 0.97
    rgb, _ = sample_character_on("paper", scale=0.5)
    assert rgb.shape == (300, 210, 3)
