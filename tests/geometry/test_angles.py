"""Tests for toonmotion.geometry.angles: wrapping and short-way interpolation of angles."""

import numpy as np
import pytest

from toonmotion.geometry.angles import lerp_angle, wrap_angle


def _degrees(a):
    return float(np.degrees(a))


def test_wrap_lands_in_half_open_range_and_keeps_the_direction():
    a = np.linspace(-20, 20, 2001)
    w = wrap_angle(a)
    assert np.all(w >= -np.pi) and np.all(w < np.pi)
    np.testing.assert_allclose(np.exp(1j * w), np.exp(1j * a), atol=1e-12)
    np.testing.assert_allclose(wrap_angle(w), w, atol=0)  # already wrapped: unchanged


@pytest.mark.parametrize(
    ("angle", "expected"),
    [(0.0, 0.0), (np.pi, -np.pi), (-np.pi, -np.pi), (3 * np.pi / 2, -np.pi / 2), (-3 * np.pi / 2, np.pi / 2),
     (7 * np.pi, -np.pi), (np.radians(190), np.radians(-170))],
)
def test_wrap_known_values(angle, expected):
    assert float(wrap_angle(angle)) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("a", "b", "midpoint"),
    [
        (0, 170, 85),  # the short way is the positive way
        (0, -170, -85),
        (170, -170, 180),  # across +-180, not back through 0
        (-170, 170, -180),
        (0, 190, -85),  # 190 is -170: the short way is negative
        (350, 10, 360),  # the same across 0
        (90, 90 + 720, 90),  # whole turns are no turn
    ],
)
def test_lerp_turns_the_short_way(a, b, midpoint):
    mid = lerp_angle(np.radians(a), np.radians(b), 0.5)
    assert _degrees(mid) == pytest.approx(midpoint, abs=1e-9)


def test_lerp_endpoints_and_linearity():
    rng = np.random.default_rng(1)
    a, b = rng.uniform(-10, 10, 200), rng.uniform(-10, 10, 200)
    assert np.array_equal(lerp_angle(a, b, 0.0), a)
    np.testing.assert_allclose(np.exp(1j * lerp_angle(a, b, 1.0)), np.exp(1j * b), atol=1e-12)
    turn = lerp_angle(a, b, 1.0) - a
    assert np.all(np.abs(turn) <= np.pi)  # never the long way round
    for t in (0.25, 0.5, 0.9):
        np.testing.assert_allclose(lerp_angle(a, b, t) - a, t * turn, atol=1e-12)


def test_lerp_is_batched():
    a = np.radians([0.0, 170.0, -90.0])
    b = np.radians([170.0, -170.0, 90.0])
    mid = np.degrees(lerp_angle(a, b, 0.5))
    # A half turn wraps to -pi, so it goes the negative way.
    np.testing.assert_allclose(mid, [85.0, 180.0, -180.0], atol=1e-9)
