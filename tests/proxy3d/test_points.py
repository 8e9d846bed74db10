"""Single-point proxies (toonmotion.proxy3d.points, section 3.4.1) and collision volumes (volumes, 3.4.2)."""

import cv2
import numpy as np
import pytest

from tests.proxy3d.test_camera import _moving_camera
from toonmotion.errors import ProxyError
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.points import point_proxies
from toonmotion.proxy3d.prior import Prior, prior_in_metres
from toonmotion.proxy3d.volumes import collision_radii, drawn_widths


@pytest.fixture(scope="module")
def scene(walk_prior):
    prior = prior_in_metres(walk_prior)[0]
    cam = PerspectiveCamera(1000.0, 960, 720, _moving_camera(prior.frame_count))
    return prior, cam


def test_the_truth_as_prior_with_the_true_camera_gives_the_truth(scene):
    prior, cam = scene
    drawn = Markers(prior.names, cam.project(prior.positions), fps=prior.fps)
    for smooth in (0.0, 1.0, 100.0):
        found = point_proxies(cam, drawn, prior, smooth_weight=smooth)
        assert np.abs(cam.depth(found) - cam.depth(prior.positions)).max() <= 1e-6
        assert np.abs(found - prior.positions).max() <= 1e-6


def test_points_stay_on_the_drawn_markers_whatever_the_prior(scene):
    """Another pose as the prior, noisy markers: every point reprojects to rounding error, and takes the
    other prior's depth where smoothness has nothing to say."""
    prior, cam = scene
    rng = np.random.default_rng(3)
    drawn = Markers(prior.names, cam.project(prior.positions) + rng.normal(0, 2, (prior.frame_count, 16, 2)),
                    fps=prior.fps)
    other = Prior(prior.names, prior.parents, prior.positions[::-1] + [0.3, 0, -0.2], fps=prior.fps)
    for smooth in (0.0, 1.0):
        found = point_proxies(cam, drawn, other, smooth_weight=smooth)
        assert np.linalg.norm(cam.project(found) - drawn.positions, axis=-1).max() < 1e-6
    no_smoothing = point_proxies(cam, drawn, other, smooth_weight=0.0)
    assert np.allclose(cam.depth(no_smoothing), cam.depth(other.positions), atol=1e-9)


def test_mismatched_inputs_are_refused(scene):
    prior, cam = scene
    drawn = Markers(prior.names, cam.project(prior.positions), fps=prior.fps)
    with pytest.raises(ProxyError, match="aligned"):
        point_proxies(cam, Markers(prior.names, drawn.positions[:-1], fps=prior.fps), prior)
    with pytest.raises(ProxyError, match="weight"):
        point_proxies(cam, drawn, prior, prior_weight=0.0)
    behind = Prior(prior.names, prior.parents, prior.positions + cam.rotations[:, 2][:, None] * -20,
                   fps=prior.fps)
    with pytest.raises(ProxyError, match="behind the camera"):
        point_proxies(cam, drawn, behind)


def _drawn_arm(cam, X, width_px, outline=2):
    """Frames of an arm (two limbs) drawn as grey quads ``width_px`` wide with black outlines, on white."""
    pictures = []
    x = cam.project(X)
    for t in range(len(X)):
        frame = np.full((cam.height, cam.width, 3), 255, np.uint8)
        for p, c in ((0, 1), (1, 2)):
            a, b = x[t, p], x[t, c]
            n = np.array([-(b - a)[1], (b - a)[0]]) / np.linalg.norm(b - a)
            half = width_px / 2 + outline
            quad = np.array([a + half * n, b + half * n, b - half * n, a - half * n])
            cv2.fillConvexPoly(frame, np.rint(quad * 16).astype(np.int32), (0, 0, 0), shift=4)
            inner = np.array([a + width_px / 2 * n, b + width_px / 2 * n, b - width_px / 2 * n,
                              a - width_px / 2 * n])
            cv2.fillConvexPoly(frame, np.rint(inner * 16).astype(np.int32), (150, 170, 200), shift=4)
        pictures.append(frame)
    return np.array(pictures)


def test_radii_come_from_the_drawn_width_at_the_markers_depth():
    """An arm reaching towards the camera, drawn 24 px wide: each end's radius is 12 px seen at that end's
    depth, within a pixel."""
    T = 6
    s = np.linspace(0, 1, T)[:, None]
    X = np.stack([np.hstack([0 * s, 1.4 + 0 * s, 0 * s]), np.hstack([0.3 + 0 * s, 1.4 + 0 * s, 0.2 * s]),
                  np.hstack([0.55 + 0 * s, 1.4 + 0 * s, 0.5 * s + 0.1])], axis=1)
    cam = PerspectiveCamera(800.0, 640, 480, [[0.4, 0.1, 0, 2.0, 1.8, 4.0]] * T)
    frames = _drawn_arm(cam, X, 24.0)
    markers = Markers(("shoulder", "elbow", "hand"), cam.project(X), fps=12)
    limbs = [[0, 1], [1, 2]]
    widths, capped = drawn_widths(frames, markers, limbs)
    assert not capped.any()
    assert np.abs(widths - 24.0).max() <= 1.5  # rasterised edges
    radii = collision_radii(cam, markers, X, limbs, widths)
    depth = cam.depth(X)
    expected = 12.0 * np.stack([depth[:, [0, 1]], depth[:, [1, 2]]], axis=1) / cam.focal
    assert np.abs(radii - expected).max() <= 1.0 * depth.max() / cam.focal  # a pixel, in metres
    # An override replaces the measurement; a stroke (ink on the limb's line) is as wide as the stroke.
    widths, _ = drawn_widths(frames, markers, limbs, widths={(2, 1): (40.0, 30.0)})
    assert widths[2, 1].tolist() == [40.0, 30.0]
    stroke = np.full_like(frames[:1], 255)
    a, b = np.rint(markers.positions[0, :2]).astype(int)
    cv2.line(stroke[0], tuple(map(int, a)), tuple(map(int, b)), (0, 0, 0), 5)
    w, _ = drawn_widths(stroke, Markers(markers.names[:2], markers.positions[:1, :2], fps=12), [[0, 1]])
    assert np.abs(w - 5).max() <= 2.0  # a rasterised diagonal stroke


def test_a_limb_with_no_outline_is_capped_and_reported():
    frames = np.full((1, 100, 100, 3), 255, np.uint8)
    frames[0, 20:80, 20:80] = (200, 100, 50)  # a flat block, no outline, the limb's width unbounded in it
    m = Markers(("a", "b"), [[[50.0, 30], [50, 70]]], fps=12)
    w, capped = drawn_widths(frames, m, [[0, 1]])
    assert w.tolist() == [[[60.0, 60.0]]]  # the block is 60 px wide: stopped at the background both sides
    wide = np.full((1, 100, 100, 3), 120, np.uint8)  # no background in reach at all
    wide[0, 0, :] = 255
    _, capped = drawn_widths(wide, m, [[0, 1]])
    assert capped.all()
