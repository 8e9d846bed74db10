"""The perspective camera and its estimation (toonmotion.proxy3d.camera, camera_fit; section 3.3)."""

import numpy as np
import pytest

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.camera import PerspectiveCamera, angles, rotations
from toonmotion.proxy3d.camera_fit import CameraWeights, estimate_camera
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import camera, view_direction
from toonmotion.proxy3d.prior import prior_in_metres


def test_rotations_are_proper_and_extend_the_orthographic_camera():
    rng = np.random.default_rng(0)
    a = rng.uniform([-np.pi, -1.4, -1], [np.pi, 1.4, 1], (200, 3))
    R = rotations(a)
    assert np.allclose(R @ R.transpose(0, 2, 1), np.eye(3), atol=1e-12)
    assert np.allclose(np.linalg.det(R), 1.0)
    assert np.allclose(angles(R), a, atol=1e-9)
    flat = a.copy()
    flat[:, 2] = 0
    for (az, el, _), M in zip(np.degrees(flat), rotations(flat), strict=True):
        assert np.allclose(M[:2], camera(az, el), atol=1e-12)
        assert np.allclose(M[2], -view_direction(az, el), atol=1e-12)  # looks at the character


def test_projection_and_back_projection_are_inverse():
    rng = np.random.default_rng(1)
    T, N = 5, 7
    cam = PerspectiveCamera(900.0, 800, 600, np.hstack([rng.uniform(-0.3, 0.3, (T, 3)), rng.uniform(-1, 1,
                                                                                                    (T, 3))
                                                          + [0, 1.5, 6]]))
    X = rng.uniform(-1, 1, (T, N, 3)) + [0, 1, 0]
    x, d = cam.project(X), cam.depth(X)
    assert np.all(d > 0)
    assert np.allclose(cam.at(x, d), X, atol=1e-12)
    # The projection matrices agree with the direct projection.
    h = np.einsum("tij,tnj->tni", cam.matrices(), np.concatenate([X, np.ones((T, N, 1))], axis=2))
    assert np.allclose(h[..., :2] / h[..., 2:], x, atol=1e-9)
    assert np.allclose(h[..., 2], d, atol=1e-12)  # m3^T X is the depth


def test_a_point_behind_the_camera_is_refused():
    cam = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5]])
    with pytest.raises(ProxyError, match="behind the camera"):
        cam.project([[[0.0, 1.0, 6.0]]])


def _moving_camera(T):
    """A camera that dollies sideways, cranes up, pans and tilts a little: (T, 6)."""
    s = np.linspace(0, 1, T)
    return np.stack([np.radians(25 + 15 * s), np.radians(4 + 6 * np.sin(3 * s)),
                     np.radians(2 * np.sin(5 * s)),
                     1.5 + 1.2 * s, 1.3 + 0.6 * s ** 2, 5.5 - 0.8 * s], axis=1)


def test_estimation_recovers_a_moving_camera_s_path(walk_prior):
    """The truth as the prior, the paper's weights and its fitted roll (roll=None; the camera rolls
    here): the path comes back to 1e-5 degree and 1e-6 m (the roll and smoothness terms' pull;
    without them, to rounding error)."""
    prior = prior_in_metres(walk_prior)[0]
    truth = PerspectiveCamera(1000.0, 960, 720, _moving_camera(prior.frame_count))
    drawn = Markers(prior.names, truth.project(prior.positions), fps=prior.fps)
    found = estimate_camera(drawn, prior, azimuth=20, elevation=0, focal=1000.0, width=960, height=720,
                            roll=None)
    error = found.extrinsics - truth.extrinsics
    assert np.degrees(np.abs(error[:, :3])).max() < 1e-5
    assert np.abs(error[:, 3:]).max() < 1e-6
    exact = estimate_camera(drawn, prior, azimuth=20, elevation=0, focal=1000.0, width=960, height=720,
                            weights=CameraWeights(ground=0, roll=0, smooth=0), roll=None)
    assert np.abs(exact.extrinsics - truth.extrinsics).max() < 1e-10


def test_one_pixel_noise_and_the_window(walk_prior):
    """With 1 px of noise the moving camera's path is found to within a degree and 10 cm on average; a window
    of three frames (the paper's robustness to noise) does worse on it, since it takes the camera as still
    across the window -- why the default window is one frame (docs/proxy3d.md)."""
    prior = prior_in_metres(walk_prior)[0]
    truth = PerspectiveCamera(1000.0, 960, 720, _moving_camera(prior.frame_count))
    rng = np.random.default_rng(2)
    drawn = Markers(prior.names, truth.project(prior.positions) + rng.normal(0, 1, (prior.frame_count, 16,
                                                                                    2)),
                    fps=prior.fps)
    errors = {}
    for window in (1, 3):
        found = estimate_camera(drawn, prior, azimuth=20, elevation=0, focal=1000.0, width=960, height=720,
                                weights=CameraWeights(window=window), roll=None)
        e = found.extrinsics - truth.extrinsics
        errors[window] = (np.degrees(np.abs(e[:, :3])).mean(), np.abs(e[:, 3:]).mean())
    assert errors[1][0] < 1.0 and errors[1][1] < 0.1
    assert errors[3][0] > errors[1][0] and errors[3][1] > errors[1][1]


def test_a_still_camera_is_one_pose_and_steadier_where_the_prior_fits_badly(walk_prior):
    """A still camera, a prior whose limbs are 25% off the drawn figure's (cartoon proportions):
    the still fit is one pose for the shot, near the truth; a camera per frame wanders."""
    prior = prior_in_metres(walk_prior)[0]
    T = prior.frame_count
    truth = PerspectiveCamera(1000.0, 960, 720, np.tile(_moving_camera(2)[0], (T, 1)))
    rng = np.random.default_rng(3)
    P = prior.positions.copy()
    for p, c in prior.limbs:  # parents first: each limb rescaled, its children carried along
        scale = rng.uniform(0.75, 1.25)
        below = [c] + [j for j in range(len(prior.names)) if _is_below(prior.parents, j, c) and j != c]
        P[:, below] += (scale - 1) * (prior.positions[:, c] - prior.positions[:, p])[:, None]
    drawn = Markers(prior.names, truth.project(P), fps=prior.fps)
    still = estimate_camera(drawn, prior, azimuth=20, elevation=0, focal=1000.0, width=960, height=720,
                            still=True)
    assert np.ptp(still.extrinsics, axis=0).max() == 0
    moving = estimate_camera(drawn, prior, azimuth=20, elevation=0, focal=1000.0, width=960, height=720)
    centre_error = {name: np.linalg.norm(cam.centres - truth.centres, axis=1).max()
                    for name, cam in (("still", still), ("moving", moving))}
    print(centre_error)
    assert centre_error["still"] < 0.5 * centre_error["moving"]
    assert np.ptp(moving.centres, axis=0).max() > 2 * np.ptp(still.centres, axis=0).max() + 0.05


def _is_below(parents, j, ancestor):
    while j >= 0:
        if j == ancestor:
            return True
        j = parents[j]
    return False


def test_the_ground_and_roll_terms_pull_as_stated():
    """Without drawing evidence against it, a camera below the ground rises and a rolled one unrolls
    (the roll fitted, as the paper does: roll=None)."""
    P = np.array([[[0.0, 0.0, 0.0], [0.0, 0.3, 0.0]]])
    from toonmotion.proxy3d.prior import Prior

    prior = Prior(("a", "b"), [-1, 0], P, fps=12)
    low = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0.2, 0, 0.1, 4]])
    drawn = Markers(("a", "b"), low.project(P), fps=12)
    free = estimate_camera(drawn, prior, azimuth=0, elevation=0, focal=500.0, width=640, height=480,
                           weights=CameraWeights(ground=0, roll=0, smooth=0), roll=None)
    pulled = estimate_camera(drawn, prior, azimuth=0, elevation=0, focal=500.0, width=640, height=480,
                             weights=CameraWeights(ground=10, roll=10, smooth=0), roll=None)
    assert pulled.extrinsics[0, 4] > free.extrinsics[0, 4]
    assert abs(pulled.extrinsics[0, 2]) < abs(free.extrinsics[0, 2])


def test_a_held_roll_keeps_the_world_upright_where_a_fitted_one_tilts_it(walk_prior):
    """A figure lying on its side as drawn (a pig's body, with a human prior standing up): the
    paper's fitted roll turns the camera to stand the prior up in the picture; the held roll (the
    default) keeps the world's up the picture's up, and the camera fits what it can."""
    prior = prior_in_metres(walk_prior)[0]
    centre = prior.positions.reshape(-1, 3).mean(axis=0) + [7.0, 0, 0]  # 7 m away on +X
    level = PerspectiveCamera(1000.0, 960, 720, np.tile([np.radians(90), 0, np.radians(60), *centre],
                                                          (prior.frame_count, 1)))
    drawn = Markers(prior.names, level.project(prior.positions), fps=prior.fps)  # seen rolled by 60°
    fitted = estimate_camera(drawn, prior, azimuth=90, elevation=0, focal=1000.0, width=960, height=720,
                             roll=None)
    held = estimate_camera(drawn, prior, azimuth=90, elevation=0, focal=1000.0, width=960, height=720)
    assert np.degrees(np.abs(fitted.extrinsics[:, 2])).min() > 50  # the world tilted to match
    assert np.all(held.extrinsics[:, 2] == 0)  # upright
    turned = estimate_camera(drawn, prior, azimuth=90, elevation=0, focal=1000.0, width=960, height=720,
                             roll=60.0)
    assert np.abs(turned.project(prior.positions) - drawn.positions).max() < 1e-3  # a roll given is kept


def test_a_held_elevation_keeps_a_panning_camera_level_where_a_fitted_one_tilts(walk_prior):
    """The camera pans (azimuth 70-110 degrees) but does not tilt, and the drawn figure crouches
    lower than its prior (every marker's height halved, as a four-legged character's front feet
    reach the ground where a human's hands hang): the fitted camera tilts to make the prior look
    like it; the held elevation stays level, so the world's vertical is the picture's, and a true
    pan is still found when the prior is the truth."""
    prior = prior_in_metres(walk_prior)[0]
    T = prior.frame_count
    pan = np.radians(np.linspace(70, 110, T))
    centre = prior.positions.mean(axis=(0, 1))
    eye = centre + 6 * np.stack([np.sin(pan), np.zeros(T), np.cos(pan)], axis=1) + [0, 0.2, 0]
    truth = PerspectiveCamera(1000.0, 960, 720, np.column_stack([pan, np.zeros((T, 2)), eye]))
    crouched = prior.positions * [1.0, 0.5, 1.0]
    drawn = Markers(prior.names, truth.project(crouched), fps=prior.fps)
    fitted = estimate_camera(drawn, prior, azimuth=70, elevation=0, focal=1000.0, width=960, height=720)
    held = estimate_camera(drawn, prior, azimuth=70, elevation=0, focal=1000.0, width=960, height=720,
                           hold_elevation=True)
    assert np.degrees(np.abs(fitted.extrinsics[:, 1])).max() > 10  # tilted to match the prior
    assert np.all(held.extrinsics[:, 1:3] == 0)  # level and unrolled on every frame
    exact = estimate_camera(Markers(prior.names, truth.project(prior.positions), fps=prior.fps), prior,
                            azimuth=70, elevation=0, focal=1000.0, width=960, height=720,
                            weights=CameraWeights(ground=0, smooth=0), hold_elevation=True)
    assert np.degrees(np.abs(exact.extrinsics[:, 0] - pan)).max() < 1e-6
    assert np.abs(exact.centres - eye).max() < 1e-6


def test_bad_settings_are_refused():
    with pytest.raises(ProxyError, match="odd"):
        CameraWeights(window=2)
    with pytest.raises(ProxyError, match="focal"):
        PerspectiveCamera(0.0, 640, 480, [[0, 0, 0, 0, 1, 5]])
    with pytest.raises(ProxyError, match="extrinsics"):
        PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, np.nan]])
