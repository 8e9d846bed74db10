"""The generated cartoon (sample_cartoons.py): its truth is exact, its pictures show it, and
contour capture gives its motion back."""

import numpy as np
import shapely

from toonmotion import api
from toonmotion.keyshape.model import warp
from toonmotion.sample_cartoons import BALL, STRIPE, ball_stripe, bouncing_ball


def test_the_bouncing_balls_truth_is_its_contours_and_its_pictures_show_it():
    ball = bouncing_ball(frames=16)
    for t in range(16):
        model = warp(ball.affine[t], ball.weights[t], ball.keys)
        np.testing.assert_allclose(model, ball.contours[t], atol=1e-9)
        stripe = shapely.Polygon(warp(ball.affine[t], [1], ball_stripe(24.0)[None]))
        ball_only = shapely.Polygon(ball.contours[t]).buffer(-2).difference(stripe.buffer(2))
        ys, xs = np.mgrid[0:200, 0:200]
        for region, colour in ((ball_only, BALL), (stripe.buffer(-1.5), STRIPE)):
            inside = shapely.contains_xy(region, xs + 0.5, ys + 0.5)
            assert inside.sum() > 20
            assert (np.abs(ball.frames[t][inside].astype(int) - colour).max(axis=1) <= 1).all()
    heights = ball.affine[:, 1, 1]
    assert heights.min() < 0.7 and heights.max() > 1.3  # squashed on the ground, stretched in flight
    np.testing.assert_allclose(ball.affine[:, 0, 0] * heights, 1)  # the area stays the same


def test_contour_capture_gives_the_balls_affine_motion_back():
    ball = bouncing_ball(frames=24)
    found = api.capture_contours(ball.contours, ball.keys)
    np.testing.assert_allclose(found.affine, ball.affine, atol=1e-6)
    rng = np.random.default_rng(0)
    noisy = ball.contours + rng.normal(0, 1 / np.sqrt(2), ball.contours.shape)
    again = api.capture_contours(noisy, ball.keys)
    rebuilt = np.stack([warp(a, w, ball.keys) for a, w in zip(again.affine, again.weights, strict=True)])
    assert np.sqrt(((rebuilt - ball.contours) ** 2).sum(axis=2).mean()) <= 1.5
