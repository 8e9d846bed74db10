"""Contour capture (keyshape/contour.py): the properties the issue names, on key-shapes from
the bundled character's posed outline."""

import numpy as np
import pytest

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.contour import capture_contours
from toonmotion.keyshape.model import warp


def _affines(rng, count):
    """Random affines: turned up to 0.5 rad, scaled 0.7 to 1.3 with some shear, moved 100 px."""
    out = []
    for _ in range(count):
        angle, sx, sy, shear = rng.uniform(-0.5, 0.5), *rng.uniform(0.7, 1.3, 2), rng.uniform(-0.2, 0.2)
        R = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        out.append(np.column_stack([R @ np.array([[sx, shear], [0, sy]]), rng.uniform(-100, 100, 2)]))
    return np.array(out)


def _weights(rng, count, K, J=None):
    """Random weights summing to 1 within [-0.5, 1.5], at most J non-zero."""
    out = np.zeros((count, K))
    for t in range(count):
        keys = rng.choice(K, size=J or K, replace=False)
        while True:
            w = rng.uniform(-0.3, 1.2, len(keys))
            w[-1] = 1 - w[:-1].sum()
            if -0.5 <= w[-1] <= 1.5:
                break
        out[t, keys] = w
    return out


def test_noise_free_contours_give_back_the_affine_and_weights(outlines):
    rng = np.random.default_rng(1)
    A, W = _affines(rng, 12), _weights(rng, 12, len(outlines))
    contours = np.stack([warp(a, w, outlines) for a, w in zip(A, W, strict=True)])
    found = capture_contours(contours, outlines)
    np.testing.assert_allclose(found.affine, A, atol=1e-6)
    np.testing.assert_allclose(found.weights, W, atol=1e-6)
    assert found.error.max() <= 1e-6 and found.rounds.max() <= 50


def test_the_support_and_bounds_always_hold(outlines):
    rng = np.random.default_rng(2)
    shapes = np.concatenate([outlines, outlines[:2] * [1.1, 0.9]])  # five keys
    contours = [warp(a, w, shapes) + rng.normal(0, 3, shapes.shape[1:])
                for a, w in zip(_affines(rng, 10), _weights(rng, 10, 5), strict=True)]
    found = capture_contours(contours, shapes, lower=-0.2, upper=1.2, support=2)
    assert (np.count_nonzero(np.abs(found.weights) > 1e-9, axis=1) <= 2).all()
    np.testing.assert_allclose(found.weights.sum(axis=1), 1, atol=1e-9)
    assert found.weights.min() >= -0.2 - 1e-9 and found.weights.max() <= 1.2 + 1e-9


def test_with_one_pixel_of_noise_the_error_stays_within_one_and_a_half_pixels(outlines):
    rng = np.random.default_rng(3)
    A, W = _affines(rng, 20), _weights(rng, 20, len(outlines))
    clean = np.stack([warp(a, w, outlines) for a, w in zip(A, W, strict=True)])
    noisy = clean + rng.normal(0, 1.0 / np.sqrt(2), clean.shape)  # 1 px rms per point
    found = capture_contours(noisy, outlines)
    rebuilt = np.stack([warp(a, w, outlines) for a, w in zip(found.affine, found.weights, strict=True)])
    assert np.sqrt(((rebuilt - clean) ** 2).sum(axis=2).mean()) <= 1.5 * 1.0
    assert found.error.mean() <= 1.5 * 1.0


@pytest.mark.parametrize(("contours", "options", "message"), [
    (np.zeros((1, 5, 2)), {}, "one line"),
    (np.ones((1, 68, 2)) * np.nan, {}, "finite"),
    (np.random.default_rng(0).random((1, 10, 2)), {}, "correspondence"),
    (None, {"support": 0}, "support"),
    (None, {"lower": 0.6}, "bounds"),
])
def test_bad_input_is_refused_in_one_line(outlines, contours, options, message):
    with pytest.raises(KeyShapeError, match=message) as caught:
        capture_contours(outlines[:1] if contours is None else contours, outlines, **options)
    assert "\n" not in str(caught.value)


def test_in_betweens_are_captured_in_the_extended_space_within_its_tolerance(smooth_keys):
    from toonmotion import api
    from toonmotion.keyshape.arap import ArapPair

    space = api.keyshape_space(smooth_keys, inbetweens=5, tolerance=0.5)
    rng = np.random.default_rng(4)
    frames = [ArapPair(smooth_keys[i], smooth_keys[j], closed=True).at(t)
              for i, j, t in [(0, 1, 0.3), (1, 2, 0.55), (0, 2, 0.8), (2, 0, 0.1)]]  # new in-betweens
    affines = _affines(rng, len(frames))
    contours = [f @ a[:, :2].T + a[:, 2] for f, a in zip(frames, affines, strict=True)]
    found = api.capture_contours(contours, space)
    np.testing.assert_allclose(found.weights.sum(axis=1), 1, atol=1e-9)
    assert np.abs(found.weights[:, :-1]).max() <= 1.5 + 1e-9
    # In-betweens the space was not built from (other t) still come within its tolerance, rms.
    assert found.error.max() <= space.tolerance


def test_progress_counts_every_frame_captured_and_changes_nothing(outlines):
    from toonmotion import api

    rng = np.random.default_rng(3)
    A, W = _affines(rng, 5), _weights(rng, 5, len(outlines))
    contours = np.stack([warp(a, w, outlines) for a, w in zip(A, W, strict=True)])
    seen = []
    found = api.capture_contours(contours, outlines, progress=lambda *step: seen.append(step))
    assert seen == [("capturing", t, 5) for t in range(1, 6)]
    assert np.array_equal(found.weights, api.capture_contours(contours, outlines).weights)
