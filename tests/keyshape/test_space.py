"""The extended linear space (keyshape/space.py): PCA over keys and ARAP in-betweens."""

import numpy as np
import pytest

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.space import build_space


def test_every_example_is_reconstructed_within_the_tolerance(smooth_keys):
    space = build_space(smooth_keys, inbetweens=5, tolerance=0.5)
    triangles = triangulate_shape(smooth_keys[0], closed=True)
    examples = [*smooth_keys]
    for i, j in [(0, 1), (0, 2), (1, 2)]:
        pair = ArapPair(smooth_keys[i], smooth_keys[j], closed=True, triangles=triangles)
        examples.extend(pair.inbetweens(5))
    assert len(examples) == 3 + 3 * 5
    for example in examples:
        weights = space.coefficients(example)
        rebuilt = np.tensordot(weights, space.extended, axes=1)
        assert np.hypot(*(rebuilt - example).T).max() <= 0.5 + 1e-9
        assert weights.sum() == pytest.approx(1.0, abs=1e-12)
    assert 1 <= len(space.eigen) < len(examples)
    assert space.error <= 0.5


def test_weights_summing_to_one_give_the_mean_plus_the_eigen_shapes(smooth_keys):
    space = build_space(smooth_keys, inbetweens=3)
    L = len(space.eigen)
    np.testing.assert_array_equal(np.tensordot(np.eye(L + 1)[L], space.extended, axes=1), space.mean)
    alpha = np.linspace(-0.7, 0.9, L)
    weights = np.append(alpha, 1 - alpha.sum())
    np.testing.assert_allclose(np.tensordot(weights, space.extended, axes=1),
                               space.mean + np.tensordot(alpha, space.eigen, axes=1), atol=1e-9)


def test_the_examples_coefficients_span_minus_one_to_one(smooth_keys):
    space = build_space(smooth_keys, inbetweens=5)
    alphas = np.array([space.coefficients(k)[:-1] for k in smooth_keys])
    assert np.abs(alphas).max() <= 1 + 1e-9


def test_a_tighter_tolerance_takes_more_eigen_shapes(smooth_keys):
    tight, loose = build_space(smooth_keys, tolerance=0.05), build_space(smooth_keys, tolerance=2)
    assert len(tight.eigen) >= len(loose.eigen)


@pytest.mark.parametrize(("options", "message"), [
    ({"inbetweens": -1}, "in-betweens"),
    ({"tolerance": 0}, "tolerance"),
])
def test_bad_settings_are_refused(smooth_keys, options, message):
    with pytest.raises(KeyShapeError, match=message):
        build_space(smooth_keys, **options)
