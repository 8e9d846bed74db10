"""Lifting end to end (toonmotion.proxy3d.lift, skeleton; sections 3.3-3.4, the paper's section 5 in short).

The CMU walk is the truth, seen by a still perspective camera; other CMU clips are the priors.
"""

import numpy as np
import pytest

from tests.proxy3d.conftest import clip_path
from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.errors import AmbiguousViewError, ProxyError
from toonmotion.io.bvh import load_bvh
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.descriptor import upper_body
from toonmotion.proxy3d.lift import lift
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import view_direction
from toonmotion.proxy3d.prior import Prior, prior_from_bvh, prior_in_metres, resample_prior
from toonmotion.proxy3d.skeleton import limb_lengths

FOCAL, IMAGE = 1000.0, (960, 720)


@pytest.fixture(scope="module")
def truth():
    clip = load_bvh(clip_path("cmu_07_01_walk.bvh"))
    return resample_prior(prior_in_metres(prior_from_bvh(clip, STANDARD_JOINTS, start=1))[0], 24)


def _camera(truth, view=(30.0, 10.0)):
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([*view, 0.0]), middle + 7 * view_direction(*view)])
    return PerspectiveCamera(FOCAL, *IMAGE, np.tile(ext, (truth.frame_count, 1)))


def _prior(name):
    return prior_from_bvh(load_bvh(clip_path(name)), STANDARD_JOINTS, start=1)


def _drawn(truth, cam, noise=0.0, squash=0.0, seed=0):
    rng = np.random.default_rng(seed)
    P = truth.positions.copy()
    for p, c in truth.limbs:  # squash and stretch, rebuilt from the root
        scale = 1 + squash * np.sin(rng.uniform(0, 6.3) + rng.uniform(0.1, 0.4) * np.arange(len(P)))
        P[:, c] = P[:, p] + scale[:, None] * (truth.positions[:, c] - truth.positions[:, p])
    return Markers(truth.names, cam.project(P) + rng.normal(0, noise, P.shape[:2] + (2,)), fps=truth.fps), P


def test_the_truth_as_prior_gives_the_truth_back(truth):
    """View searched, camera estimated: depths within 1e-6 m, the skeleton within the subspace's reach."""
    cam = _camera(truth)
    drawn, _ = _drawn(truth, cam)
    proxy, report = lift(drawn, truth, focal=FOCAL, size=IMAGE, units=1.0)
    assert np.abs(proxy.camera.depth(proxy.points) - cam.depth(truth.positions)).max() <= 1e-6
    assert report.camera_px < 1e-6 and report.reproj_px < 1e-6
    assert np.abs(proxy.skeleton - truth.positions).max() < 0.1  # P = 20 of 48 dimensions


@pytest.mark.parametrize("case", [
    ("cmu_07_01_walk.bvh", 0.0, 0.0), ("cmu_02_03_run.bvh", 0.0, 0.0), ("cmu_16_07_jump.bvh", 2.0, 0.1),
    ("cmu_jumping_jacks.bvh", 1.0, 0.1),
])
def test_points_reproject_and_skeleton_limbs_keep_their_lengths(truth, case):
    name, noise, squash = case
    cam = _camera(truth)
    drawn, _ = _drawn(truth, cam, noise, squash)
    prior = _prior(name)
    longest = int(2 * truth.frame_count * prior.fps / truth.fps)
    prior = Prior(prior.names, prior.parents, prior.positions[:longest], prior.fps, prior.joints,
                  prior.turns[:longest])
    proxy, report = lift(drawn, prior, focal=FOCAL, size=IMAGE)
    seen = proxy.camera.project(proxy.points)
    assert np.linalg.norm(seen - drawn.positions, axis=-1).max() <= 0.5  # every frame, every marker
    lengths = limb_lengths(proxy.skeleton, proxy.limbs)
    assert np.ptp(lengths, axis=0).max() <= 1e-6
    L = proxy.limbs
    assert np.allclose(proxy.limb_vectors(), proxy.skeleton[:, L[:, 1]] - proxy.skeleton[:, L[:, 0]],
                       atol=1e-9)


def test_the_skeleton_takes_the_drawing_s_upper_body_and_keeps_the_prior_s_legs(truth):
    """Fig. 22: with the run as the prior, the skeleton's upper body is nearer the walk than the prior's,
    its lower body about as near (poses compared root-relative, in camera axes)."""
    cam = _camera(truth)
    drawn, _ = _drawn(truth, cam)
    proxy, report = lift(drawn, _prior("cmu_02_03_run.bvh"), focal=FOCAL, size=IMAGE)
    root = int(np.flatnonzero(truth.parents < 0)[0])

    def pose(camera, P):
        seen = camera.to_camera(P)
        return seen - seen[:, root:root + 1]

    target = pose(cam, truth.positions)
    upper = upper_body(truth)

    def rms(P, which):
        return float(np.sqrt(((pose(proxy.camera, P)[:, which] - target[:, which]) ** 2).sum(-1).mean()))

    assert rms(proxy.skeleton, upper) < 0.9 * rms(report.warped.positions, upper)
    assert rms(proxy.skeleton, ~upper) < 1.05 * rms(report.warped.positions, ~upper)


def test_the_view_is_found_within_a_few_degrees(truth):
    cam = _camera(truth, (-50.0, 15.0))
    drawn, _ = _drawn(truth, cam)
    _, report = lift(drawn, truth, focal=FOCAL, size=IMAGE)
    found = view_direction(report.azimuth, report.elevation)
    assert np.degrees(np.arccos(found @ view_direction(-50,
                                                       15))) < 3.0  # orthographic stand-in for perspective


def test_bad_input_is_refused_in_one_line(truth):
    cam = _camera(truth)
    drawn, _ = _drawn(truth, cam)
    cases = [
        (lambda: lift(Markers(drawn.names, drawn.positions[:5], fps=24), truth, view=(30, 10)), "too long"),
        (lambda: lift(drawn, Prior(truth.names, truth.parents, truth.positions[:10], fps=24), view=(30, 10)),
         "too short"),
        (lambda: lift(drawn, truth, view=(30, 10), frames=np.zeros((3, 10, 10, 3), np.uint8)),
         "one image per"),
        (lambda: lift(drawn, truth, view=(30, 10), focal=-1.0, size=IMAGE), "focal"),
        (lambda: lift(drawn, truth, view=(30, 10), size=(0, 10)), "image size"),
        (lambda: lift(drawn, truth, view=(30, 10), units="furlong"), "units"),
    ]
    for call, match in cases:
        with pytest.raises(ProxyError, match=match) as caught:
            call()
        assert "\n" not in str(caught.value)


def test_a_view_the_drawing_cannot_tell_from_its_twin_is_asked_for(truth):
    """A figure moving in one plane looks the same from a view and its mirror twin: lifting
    names both in one line and asks for --view instead of picking one; given, it lifts."""
    P = truth.positions.copy()
    P[..., 0] = 0.0  # the walk flattened onto its swing plane
    flat = Prior(truth.names, truth.parents, P, truth.fps)
    cam = _camera(flat, (40.0, 15.0))
    drawn = Markers(flat.names, cam.project(P), fps=flat.fps)
    with pytest.raises(AmbiguousViewError) as asked:
        lift(drawn, flat, focal=FOCAL, size=IMAGE)
    message = str(asked.value)
    assert "\n" not in message and "--view" in message and message.startswith("two views explain")
    first, second = asked.value.views
    views = [(first[0], first[1]), (second[0], second[1])]
    assert min(np.degrees(np.arccos(np.clip(view_direction(*v) @ view_direction(40, 15), -1, 1)))
               for v in views) < 3.0  # the view drawn from is one of the two
    _, report = lift(drawn, flat, view=(40.0, 15.0), focal=FOCAL, size=IMAGE)
    assert (report.azimuth, report.elevation) == (40.0, 15.0) and not report.view_found


def test_the_world_stays_upright_unless_the_picture_is_turned(truth):
    """The walk drawn with the picture turned 60° clockwise (as a figure whose posture is unlike
    the prior's leaves it): by default the camera stays level, the world's up the picture's, and a
    warning says the fit is poor; up=60 says how the picture is turned, and the fit is exact; the
    paper's fitted roll (up=None) tilts the world, and a warning says so."""
    from toonmotion.api import lift_warnings

    view = (30.0, 10.0)
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([*view, -60.0]), middle + 7 * view_direction(*view)])
    turned = PerspectiveCamera(FOCAL, *IMAGE, np.tile(ext, (truth.frame_count, 1)))
    drawn = Markers(truth.names, turned.project(truth.positions), fps=truth.fps)
    level, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE)
    assert np.all(level.camera.extrinsics[:, 2] == 0)
    assert any(w.startswith("no camera sees the prior as drawn") for w in lift_warnings(level, report))
    told, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, up=60.0)
    assert np.allclose(told.camera.extrinsics[:, 2], np.radians(-60.0)) and report.camera_px < 0.01
    assert lift_warnings(told, report) == []
    free, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, up=None)
    assert np.degrees(np.abs(free.camera.extrinsics[:, 2])).min() > 50
    assert any("--up 0" in w for w in lift_warnings(free, report))


def test_a_figure_lower_than_its_prior_tilts_the_camera_unless_the_elevation_is_held(truth):
    """The walk drawn crouched (every marker at half its height, as a four-legged character's front
    feet reach the ground where a human's hands hang) from a level side view: the fitted camera
    tilts to make the prior look like it, and a warning names --hold-elevation; held, the camera
    stays level on every frame, the points still lie on the drawing, and the world's vertical is
    the picture's (a vertical segment at the figure projects vertical)."""
    from toonmotion.api import lift_warnings

    view = (90.0, 0.0)
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([*view, 0.0]), middle + 7 * view_direction(*view)])
    level = PerspectiveCamera(FOCAL, *IMAGE, np.tile(ext, (truth.frame_count, 1)))
    drawn = Markers(truth.names, level.project(truth.positions * [1.0, 0.5, 1.0]), fps=truth.fps)
    tilted, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, still_camera=True)
    assert np.degrees(np.abs(tilted.camera.extrinsics[:, 1])).max() > 20
    assert any("--hold-elevation" in w for w in lift_warnings(tilted, report))
    # The editor asks in its own words: the same warning, its remedy replaced.
    asked = lift_warnings(tilted, report, remedies={"hold": "tick 'Keep the view's elevation'"})
    assert [w.replace("tick 'Keep the view's elevation'", "give --hold-elevation (with --view AZ,EL)")
            for w in asked] == lift_warnings(tilted, report)
    held, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, still_camera=True,
                        hold_elevation=True)
    assert np.all(held.camera.extrinsics[:, 1:3] == 0) and report.reproj_px < 1e-6
    assert not any("--hold-elevation" in w for w in lift_warnings(held, report))
    centre = held.points.mean(axis=1, keepdims=True)
    seen = held.camera.project(np.concatenate([centre, centre + [0.0, 0.1, 0.0]], axis=1))
    assert np.abs(seen[:, 1, 0] - seen[:, 0, 0]).max() < 1e-9


def test_the_ground_can_be_the_drawn_figure_s_lowest_path(truth):
    """The walk drawn crouched (half its height) from the side, lifted with the walk standing as the
    prior and the camera level: on the prior's floor its feet float; with ground="feet" the whole
    proxy and its camera move down together, so every picture is the same, and the figure's lowest
    path is the ground."""
    from toonmotion.proxy3d.lift import lowest_path

    view = (90.0, 0.0)
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    ext = np.concatenate([np.radians([*view, 0.0]), middle + 7 * view_direction(*view)])
    level = PerspectiveCamera(FOCAL, *IMAGE, np.tile(ext, (truth.frame_count, 1)))
    drawn = Markers(truth.names, level.project(truth.positions * [1.0, 0.5, 1.0]), fps=truth.fps)
    floor, _ = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, still_camera=True, hold_elevation=True)
    feet, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, still_camera=True,
                        hold_elevation=True, ground="feet")
    lowest = lowest_path(floor)
    assert lowest > 0.2  # in the air on the prior's floor
    assert report.ground_shift == pytest.approx(-lowest)
    assert abs(lowest_path(feet)) < 1e-12
    np.testing.assert_allclose(feet.points, floor.points - [0, lowest, 0], atol=1e-12)
    seen = feet.camera.project(feet.points)
    np.testing.assert_allclose(seen, floor.camera.project(floor.points), atol=1e-9)
    with pytest.raises(ProxyError, match="'prior'.*'feet'"):
        lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, ground="floor")


@pytest.mark.xfail(strict=True, reason="issue 45: with a prior of another motion the view search is biased "
                   "(the walk lifted with the CMU run: about 20 degrees off, and it does not know)")
def test_the_view_is_found_with_a_prior_of_another_motion(truth):
    cam = _camera(truth, (30.0, 10.0))
    drawn, _ = _drawn(truth, cam)
    run = resample_prior(prior_in_metres(_prior("cmu_02_03_run.bvh"))[0], 24)
    _, report = lift(drawn, run, focal=FOCAL, size=IMAGE)
    found = view_direction(report.azimuth, report.elevation)
    assert np.degrees(np.arccos(np.clip(found @ view_direction(30, 10), -1, 1))) < 10.0
