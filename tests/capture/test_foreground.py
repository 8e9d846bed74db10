"""Tests for toonmotion.capture.foreground."""

import cv2
import numpy as np
import pytest

from toonmotion.capture.foreground import estimate_background, foreground_masks, guide_skeleton
from toonmotion.errors import TrackingError

H, W, T = 96, 128, 20


def _texture(rng, low, high, shape=(H, W)):
    """Smooth colour noise with each channel between ``low`` and ``high``, (h, w, 3) uint8."""
    noise = cv2.GaussianBlur(rng.uniform(0, 1, (*shape, 3)).astype(np.float32), (9, 9), 3)
    noise = (noise - noise.min()) / (noise.max() - noise.min())
    return np.rint(np.array(low) + noise * (np.array(high) - np.array(low))).astype(np.uint8)


def _sequence(*, background=None, specks=True, seed=0):
    """A textured disc and a rectangle moving over a static background.

    Returns frames (T, H, W, 3), the true masks (T, H, W) and the background (H, W, 3).
    """
    rng = np.random.default_rng(seed)
    if background is None:
        background = _texture(rng, (20, 100, 60), (80, 180, 140))  # blue-green
    figure = _texture(rng, (200, 20, 0), (255, 80, 60))  # red-orange, far from the background
    y, x = np.mgrid[0:H, 0:W]
    frames, masks = [], []
    for t in range(T):
        disc = (x - (15 + 5 * t)) ** 2 + (y - 40) ** 2 <= 12**2
        rect = (np.abs(x - (110 - 4 * t)) <= 6) & (np.abs(y - (60 + t)) <= 14)
        mask = disc | rect
        frame = np.where(mask[..., None], figure, background)
        if specks:  # a few isolated wrong pixels, as from noise or compression
            r, c = rng.integers(0, H, 6), rng.integers(0, W, 6)
            frame[r, c] = rng.integers(0, 256, (6, 3))
        frames.append(frame)
        masks.append(mask)
    return np.stack(frames), np.stack(masks), background


def _iou(a, b):
    return np.count_nonzero(a & b) / np.count_nonzero(a | b)


def _stick_figure():
    mask = np.zeros((160, 120), np.uint8)
    cv2.circle(mask, (60, 25), 12, 1, -1)
    for a, b in [((60, 30), (60, 95)), ((60, 50), (25, 75)), ((60, 50), (95, 75)),
                 ((60, 95), (35, 145)), ((60, 95), (85, 145))]:
        cv2.line(mask, a, b, 1, 7)
    return mask.astype(bool)


def test_estimated_background_is_exact_where_the_figure_covers_under_half_the_frames():
    frames, masks, truth = _sequence()
    background = estimate_background(frames)
    covered = masks.mean(axis=0)
    assert covered.max() < 0.5  # the figure keeps moving
    never = covered == 0
    np.testing.assert_array_equal(background[never], truth[never])
    diff = np.abs(background.astype(int) - truth)
    assert diff[~never].max() <= 2


def test_estimate_background_uses_evenly_spaced_samples():
    frames = np.zeros((9, 2, 2, 3), np.uint8)
    frames[[1, 3, 5, 7]] = 200  # odd frames are never sampled with samples=5
    assert estimate_background(frames, samples=5).max() == 0
    assert estimate_background(frames).max() == 0  # 5 of 9 are 0


def test_foreground_masks_match_the_truth():
    frames, masks, _ = _sequence()
    found = foreground_masks(frames)
    assert found.shape == masks.shape and found.dtype == bool
    ious = [_iou(f, m) for f, m in zip(found, masks, strict=True)]
    assert min(ious) >= 0.95


def test_foreground_masks_with_a_given_background_and_threshold():
    frames, masks, background = _sequence()
    found = foreground_masks(frames, background=background, threshold=60)
    assert min(_iou(f, m) for f, m in zip(found, masks, strict=True)) >= 0.95


def test_flat_colour_background():
    flat = np.full((H, W, 3), (245, 245, 240), np.uint8)
    frames, masks, _ = _sequence(background=flat)
    found = foreground_masks(frames, colour=(245, 245, 240))
    assert min(_iou(f, m) for f, m in zip(found, masks, strict=True)) >= 0.95


def test_small_holes_are_filled_and_big_ones_kept():
    frames, masks, background = _sequence(specks=False)
    frames = frames.copy()
    frames[:, 40, 15:17] = background[40, 15:17]  # a 2-pixel hole in the disc of frame 0
    found = foreground_masks(frames, background=background)
    assert found[0, 40, 15] and found[0, 40, 16]
    ring = np.zeros((T, H, W, 3), np.uint8)
    y, x = np.mgrid[0:H, 0:W]
    r = np.hypot(x - 64, y - 48)
    ring[:, (r >= 15) & (r <= 30)] = 255
    found = foreground_masks(ring, colour=(0, 0, 0))
    assert not found[0, 48, 64]  # the ring's hole is a third of its area: kept


def test_guide_skeleton_of_a_stick_figure_has_branches():
    skeleton = guide_skeleton(_stick_figure())
    assert len(skeleton.branches) >= 5
    assert skeleton.kinds.count("junction") >= 2
    assert skeleton.kinds.count("end") >= 4


def test_guide_skeleton_of_an_empty_mask_raises():
    with pytest.raises(TrackingError, match="foreground is empty"):
        guide_skeleton(np.zeros((10, 10), bool))


def test_bad_inputs_raise_tracking_errors():
    frames, _, background = _sequence()
    with pytest.raises(TrackingError, match="not both"):
        foreground_masks(frames, background=background, colour=(0, 0, 0))
    with pytest.raises(TrackingError, match=r"\(T, h, w, 3\) uint8"):
        foreground_masks(frames[0])
    with pytest.raises(TrackingError, match="sequence is empty"):
        estimate_background(frames[:0])
    with pytest.raises(TrackingError, match="background image is 64x96"):
        foreground_masks(frames, background=background[:, :64])
    with pytest.raises(TrackingError, match="three numbers"):
        foreground_masks(frames, colour=(0, 0))
    with pytest.raises(TrackingError, match="threshold"):
        foreground_masks(frames, threshold=-1)


def test_border_colour_reads_a_flat_background_and_refuses_a_textured_one():
    from toonmotion.capture.foreground import border_colour

    frame = np.full((40, 50, 3), (250, 248, 240), dtype=np.uint8)
    frame[10:30, 15:35] = (20, 90, 200)  # the figure, off the border
    assert border_colour(frame) == (250, 248, 240)
    noisy = np.random.default_rng(0).integers(0, 256, size=(40, 50, 3), dtype=np.uint8)
    assert border_colour(noisy) is None
