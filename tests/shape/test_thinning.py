"""Tests for toonmotion.shape.thinning."""

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage as ndi
from skimage.measure import euler_number, label

from toonmotion.shape.thinning import hilditch_thin

# Yokoi's neighbour order x1..x8: E, NE, N, NW, W, SW, S, SE (x1, x3, x5, x7 are 4-neighbours).
_YOKOI_OFFSETS = [(0, 1), (-1, 1), (-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0), (1, 1)]


def _neighbours(image):
    """(8, h, w) stack of each pixel's neighbours in Yokoi's order, zero outside."""
    padded = np.pad(image.astype(np.int64), 1)
    h, w = image.shape
    return np.stack([padded[1 + dr : 1 + dr + h, 1 + dc : 1 + dc + w] for dr, dc in _YOKOI_OFFSETS])


def _yokoi_n8(image):
    """Yokoi's 8-connectivity number of every pixel.

    N8 = sum over k in {1, 3, 5, 7} of (x_k - x_k x_{k+1} x_{k+2}) on the complemented
    neighbours; a foreground pixel is 8-simple (deletable without changing topology) iff N8 = 1.
    """
    x = 1 - _neighbours(image)
    return sum(x[k] - x[k] * x[(k + 1) % 8] * x[(k + 2) % 8] for k in (0, 2, 4, 6))


def _topology(mask):
    """(8-connected components, Euler number with 8-connected foreground)."""
    return int(label(mask, connectivity=2).max()), int(euler_number(mask, connectivity=2))


def _assert_thin(skeleton, mask, what=""):
    assert not np.any(skeleton & ~mask), f"{what}: skeleton leaves the shape"
    assert _topology(skeleton) == _topology(mask), f"{what}: topology changed"
    blocks = skeleton[:-1, :-1] & skeleton[1:, :-1] & skeleton[:-1, 1:] & skeleton[1:, 1:]
    assert not blocks.any(), f"{what}: a 2x2 block of skeleton pixels"
    degree = _neighbours(skeleton).sum(axis=0)
    reducible = skeleton & (degree >= 2) & (_yokoi_n8(skeleton) == 1)
    assert not reducible.any(), f"{what}: simple pixels left at {np.argwhere(reducible)[:5]}"


def _disk(shape, center, radius):
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    return np.hypot(xx - center[0], yy - center[1]) <= radius


def _random_blob(seed):
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(24, 72, size=2))
    field = ndi.gaussian_filter(rng.standard_normal(shape), rng.uniform(1.5, 4.0))
    return field > np.quantile(field, rng.uniform(0.3, 0.7))


# The test's own Yokoi number -----------------------------------------------------------------


def _brute_force_simple(code):
    """Simple by definition: one 8-component of foreground neighbours, one 4-component of
    background neighbours 4-adjacent to the centre."""
    window = np.zeros((3, 3), int)
    for k, (dr, dc) in enumerate(_YOKOI_OFFSETS):
        window[1 + dr, 1 + dc] = (code >> k) & 1
    fg = window.copy()
    fg[1, 1] = 0
    n_fg = ndi.label(fg, structure=np.ones((3, 3)))[1]
    bg = 1 - window
    bg[1, 1] = 0
    bg_labels = ndi.label(bg)[0]
    touching = {bg_labels[1 + dr, 1 + dc] for dr, dc in [(0, 1), (-1, 0), (0, -1), (1, 0)]}
    return n_fg == 1 and len(touching - {0}) == 1


def test_yokoi_number_characterises_simple_pixels():
    for code in range(256):
        window = np.zeros((3, 3), bool)
        window[1, 1] = True
        for k, (dr, dc) in enumerate(_YOKOI_OFFSETS):
            window[1 + dr, 1 + dc] = (code >> k) & 1
        assert (_yokoi_n8(window)[1, 1] == 1) == _brute_force_simple(code), code


# Thinning --------------------------------------------------------------------------------------


def test_drawing_mask_thins_to_a_thin_irreducible_skeleton(drawing_dir):
    mask = np.asarray(Image.open(drawing_dir / "mask.png").convert("L")) >= 128
    skeleton = hilditch_thin(mask)
    _assert_thin(skeleton, mask, drawing_dir.name)
    assert np.count_nonzero(skeleton) < 0.05 * np.count_nonzero(mask)


def test_random_smooth_blobs_keep_topology():
    cases = 0
    for seed in range(100):
        mask = _random_blob(seed)
        _assert_thin(hilditch_thin(mask), mask, f"seed {seed}")
        cases += _topology(mask)[0] > 1 or _topology(mask)[1] < 1
    assert cases > 10, "the blobs should include several parts and holes"


def test_disk_with_holes_keeps_its_holes():
    mask = _disk((80, 80), (40, 40), 32)
    for center in [(30, 30), (52, 34), (40, 55)]:
        mask &= ~_disk((80, 80), center, 4)
    assert _topology(mask) == (1, -2)
    _assert_thin(hilditch_thin(mask), mask, "disk with holes")


def test_regression_2x2_block_does_not_vanish():
    # Plain parallel Hilditch deletes all four pixels of a 2x2 block at once.
    mask = np.zeros((6, 6), bool)
    mask[2:4, 2:4] = True
    skeleton = hilditch_thin(mask)
    assert skeleton.any()
    _assert_thin(skeleton, mask, "2x2 block")


def test_two_pixel_wide_line_stays_connected():
    mask = np.zeros((12, 40), bool)
    mask[5:7, 3:37] = True
    skeleton = hilditch_thin(mask)
    _assert_thin(skeleton, mask, "2 px line")
    assert np.ptp(np.nonzero(skeleton)[1]) >= 28  # still spans most of the line


def test_horizontal_bar_skeleton_is_centred():
    mask = np.zeros((41, 120), bool)
    mask[10:31, 5:115] = True  # 21 rows tall: the middle row is 20
    skeleton = hilditch_thin(mask)
    rows, cols = np.nonzero(skeleton[:, 30:90])
    assert len(np.unique(cols)) == 60, "the skeleton runs through the whole middle part"
    assert np.all(np.abs(rows - 20) <= 1)


def test_vertical_bar_skeleton_is_centred():
    mask = np.zeros((120, 41), bool)
    mask[5:115, 10:31] = True
    rows, cols = np.nonzero(hilditch_thin(mask)[30:90])
    assert len(np.unique(rows)) == 60
    assert np.all(np.abs(cols - 20) <= 1)


def test_skeleton_of_a_skeleton_is_itself(drawing_dir):
    mask = np.asarray(Image.open(drawing_dir / "mask.png").convert("L")) >= 128
    skeleton = hilditch_thin(mask)
    np.testing.assert_array_equal(hilditch_thin(skeleton), skeleton)


@pytest.mark.parametrize(
    "mask",
    [np.zeros((5, 5), bool), np.eye(5, dtype=bool), np.ones((7, 9), bool)],
    ids=["empty", "diagonal", "full-frame"],
)
def test_small_cases(mask):
    skeleton = hilditch_thin(mask)
    assert skeleton.shape == mask.shape and skeleton.dtype == bool
    _assert_thin(skeleton, mask, "small case")


def test_single_pixel_survives():
    mask = np.zeros((3, 3), bool)
    mask[1, 1] = True
    np.testing.assert_array_equal(hilditch_thin(mask), mask)


def test_input_is_not_modified():
    mask = _disk((30, 30), (15, 15), 10)
    before = mask.copy()
    hilditch_thin(mask)
    np.testing.assert_array_equal(mask, before)
