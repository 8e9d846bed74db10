"""Tests for toonmotion.render.composite: premultiplied colour over a background."""

import numpy as np
import pytest

from toonmotion.render.composite import over, premultiply


def _all_colours_and_alphas():
    """Every (colour, alpha) pair as (65536, 4) RGBA: the colour in r, reversed in g, 7 in b."""
    c, a = np.meshgrid(np.arange(256), np.arange(256), indexing="ij")
    return np.stack([c, 255 - c, np.full_like(c, 7), a], axis=-1).reshape(-1, 4).astype(np.uint8)


def test_premultiply_gives_exact_integer_products():
    rgba = _all_colours_and_alphas()
    p = premultiply(rgba)
    assert p.dtype == np.float32 and p.shape == rgba.shape
    factors = np.append(rgba[:, 3:].repeat(3, axis=1), np.full((len(rgba), 1), 255), axis=1)
    expected = rgba.astype(np.int64) * factors
    np.testing.assert_array_equal(p, expected)
    assert premultiply(rgba.reshape(256, 256, 4)).shape == (256, 256, 4)


def test_without_a_background_straight_alpha_comes_back_exactly():
    rgba = _all_colours_and_alphas()
    out = over(premultiply(rgba))
    visible = rgba[:, 3] > 0
    np.testing.assert_array_equal(out[visible], rgba[visible])
    assert not out[~visible].any()  # alpha 0: (0, 0, 0, 0)


@pytest.mark.parametrize("background", [(255, 255, 255), (0, 0, 0), (30, 140, 250)])
def test_over_an_opaque_colour_is_the_exactly_rounded_blend(background):
    rgba = _all_colours_and_alphas()
    out = over(premultiply(rgba), background)
    a = rgba[:, 3:].astype(np.int64)
    # (c a + b (255 - a)) / 255 is never halfway between two levels, so rounding is unambiguous.
    expected = (rgba[:, :3] * a + np.array(background) * (255 - a) + 127) // 255
    np.testing.assert_array_equal(out[:, :3], expected)
    assert (out[:, 3] == 255).all()


def test_over_a_translucent_colour_adds_up_the_alphas():
    rgba = _all_colours_and_alphas()
    background = (40, 80, 120, 100)
    out = over(premultiply(rgba), background).astype(float)
    a, b = rgba[:, 3:] / 255, background[3] / 255
    alpha = a + b * (1 - a)
    colour = (rgba[:, :3] * a + np.array(background[:3]) * b * (1 - a)) / alpha
    np.testing.assert_allclose(out[:, 3:], np.rint(alpha * 255), atol=1)
    np.testing.assert_allclose(out[:, :3], colour, atol=0.51)


@pytest.mark.parametrize("background", [(255, 255, 255, 255), (40, 80, 120, 100), (0, 0, 0, 0)])
def test_a_background_per_pixel_matches_one_colour_under_all(background):
    rgba = _all_colours_and_alphas()
    under = np.tile(np.array(background, np.uint8), (len(rgba), 1))
    np.testing.assert_array_equal(over(premultiply(rgba), under), over(premultiply(rgba), background))


def test_a_background_per_pixel_mixes_opaque_and_translucent_rows():
    rgba = _all_colours_and_alphas()[::97]
    rng = np.random.default_rng(0)
    under = rng.integers(0, 256, (len(rgba), 4)).astype(np.uint8)
    under[::2, 3] = 255
    out = over(premultiply(rgba), under)
    for i in (0, 1, 2, 3, len(rgba) - 1):
        np.testing.assert_array_equal(out[i], over(premultiply(rgba[i:i + 1]), tuple(under[i]))[0])


def test_no_pixels():
    assert over(np.zeros((0, 4), np.float32), (255, 255, 255)).shape == (0, 4)
