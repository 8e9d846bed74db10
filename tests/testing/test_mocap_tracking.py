"""Tests for toonmotion.testing.mocap_tracking: rendering mocap with its true joints, tracking
from them, and the scores. A small clip is built in memory, so no shared data is needed."""

from dataclasses import replace

import numpy as np
import pytest

from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics
from toonmotion.capture.mocap import STANDARD_JOINTS, fit_to_frame, pick_joints, project_orthographic
from toonmotion.testing.mocap_tracking import (
    LOST_PX,
    PCK_PX,
    RenderedClip,
    render_mocap,
    track_from_truth,
    tracking_errors,
    tracking_scores,
)

# A standing figure, Y up, facing +Z, in centimetres; its left is +X. Joint names in the
# snake_case convention pick_joints reads.
_JOINTS = [
    ("hips", None, (0, 100, 0)), ("spine", "hips", (0, 20, 0)), ("neck", "spine", (0, 30, 0)),
    ("head", "neck", (0, 15, 0)),
    ("l_shoulder", "neck", (15, -5, 0)), ("l_elbow", "l_shoulder", (0, -25, 0)),
    ("l_wrist", "l_elbow", (0, -25, 0)),
    ("r_shoulder", "neck", (-15, -5, 0)), ("r_elbow", "r_shoulder", (0, -25, 0)),
    ("r_wrist", "r_elbow", (0, -25, 0)),
    ("l_hip", "hips", (10, 0, 0)), ("l_knee", "l_hip", (0, -45, 0)), ("l_ankle", "l_knee", (0, -45, 0)),
    ("r_hip", "hips", (-10, 0, 0)), ("r_knee", "r_hip", (0, -45, 0)), ("r_ankle", "r_knee", (0, -45, 0)),
]
_ROOT = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
_ARM = ("Zrotation", "Xrotation", "Yrotation")


def _clip(frames=41, fps=120.0, tpose=False):
    """The figure raising both arms sideways by up to 40 degrees while drifting right, at ``fps``;
    with ``tpose``, a first frame with the arms straight out, away from everything after it."""
    names = [n for n, _, _ in _JOINTS]
    parents = np.array([-1 if p is None else names.index(p) for _, p, _ in _JOINTS])
    channels = [_ROOT if n == "hips" else _ARM if n.endswith("shoulder") else () for n in names]
    t = np.arange(frames) / fps
    raised = 40 * np.sin(np.pi * t / t[-1])
    motion = np.zeros((frames, 12))
    motion[:, 0] = 30 * t  # cm/s
    motion[:, 1] = 100
    motion[:, 6] = raised  # the left arm turns about Z towards +X, outwards
    motion[:, 9] = -raised
    if tpose:
        motion[0, 6], motion[0, 9], motion[0, 0] = 90, -90, -20
    offsets = np.array([o for _, _, o in _JOINTS], dtype=float)
    offsets[0] = 0
    return BvhClip(names=tuple(names), parents=parents, offsets=offsets, channels=tuple(channels),
                   motion=motion, frame_time=1 / fps)


@pytest.fixture(scope="module")
def rendered():
    return render_mocap(_clip(), size=(320, 240))


def test_rendered_clip_is_resampled_fitted_and_ordered_like_its_skeleton(rendered):
    clip = _clip()
    assert isinstance(rendered, RenderedClip)
    # 120 fps to 30: every 4th of 41 frames.
    assert rendered.fps == 30.0 and rendered.images.shape == (11, 240, 320, 3)
    assert rendered.images.dtype == np.uint8
    X = forward_kinematics(clip)[::4]
    picks = pick_joints(clip.names, clip.parents)
    expected = fit_to_frame(project_orthographic(X[:, [picks[n] for n in STANDARD_JOINTS]]), (320, 240))
    order = [STANDARD_JOINTS.index(n) for n in rendered.skeleton.names]
    np.testing.assert_allclose(rendered.truth, expected[:, order], rtol=0, atol=1e-9)
    np.testing.assert_allclose(rendered.skeleton.positions, rendered.truth[0], rtol=0, atol=1e-12)
    assert sorted(rendered.skeleton.names) == sorted(STANDARD_JOINTS)
    assert rendered.skeleton.parents[rendered.skeleton.index("hips")] == -1
    # Inside the frame less its 10% margin; the left hand on the image's right.
    assert (rendered.truth >= np.array([32, 24]) - 1e-9).all()
    assert (rendered.truth <= np.array([288, 216]) + 1e-9).all()
    hand = {side: rendered.skeleton.index(f"{side}_hand") for side in ("left", "right")}
    assert rendered.truth[0, hand["left"], 0] > rendered.truth[0, hand["right"], 0]
    assert rendered.side > 0


def test_the_figure_is_drawn_where_the_true_joints_are(rendered):
    """Every joint's disc covers its true centre: the pixels there move with the figure, not
    with the background, which stays still."""
    still = (np.abs(np.diff(rendered.images.astype(int), axis=0)).max(axis=(0, 3)) == 0)
    for t in range(len(rendered.images)):
        x, y = np.rint(rendered.truth[t]).astype(int).T
        assert not still[y, x].any(), f"frame {t}: a joint lies on unchanging background"


def test_a_leading_t_pose_frame_is_dropped():
    plain, tposed = render_mocap(_clip(), size=(320, 240)), render_mocap(_clip(tpose=True), size=(320, 240))
    assert len(plain.images) == 11 and len(tposed.images) == 10  # frames 1, 5, ..., 37


def test_frames_keeps_the_first_frames_and_fits_them_alone():
    clip = _clip()
    short = render_mocap(clip, size=(320, 240), frames=4)
    cut = render_mocap(replace(clip, motion=clip.motion[:13]), size=(320, 240))  # frames 0, 4, 8, 12
    assert len(short.images) == 4
    np.testing.assert_array_equal(short.images, cut.images)
    np.testing.assert_array_equal(short.truth, cut.truth)


def test_tracking_from_the_true_rectangles_follows_the_figure(rendered):
    found, seconds = track_from_truth(rendered)
    assert found.shape == rendered.truth.shape and seconds > 0
    np.testing.assert_allclose(found[0], rendered.truth[0], rtol=0, atol=1e-9)
    figures = tracking_scores(found, rendered.truth)
    print(figures)
    assert figures["mean_px"] <= 0.5 and figures["lost"] == 0


def test_scores_leave_out_the_first_frame_and_count_at_their_thresholds():
    truth = np.zeros((3, 2, 2))
    found = truth + [[[100.0, 0.0], [0.0, 100.0]],  # frame 0: where tracking starts, not scored
                     [[PCK_PX, 0.0], [0.0, PCK_PX + 1e-9]],
                     [[0.0, LOST_PX], [LOST_PX + 1e-9, 0.0]]]
    np.testing.assert_allclose(tracking_errors(found, truth), [PCK_PX, PCK_PX, LOST_PX, LOST_PX], atol=1e-8)
    scores = tracking_scores(found, truth)
    assert scores == {"mean_px": 12.5, "median_px": 12.5, "pck5": 0.25, "lost": 0.25}


def test_scores_need_matching_point_arrays():
    with pytest.raises(ValueError, match=r"found and truth must both be \(frames, joints, 2\)"):
        tracking_scores(np.zeros((3, 2, 2)), np.zeros((3, 3, 2)))
    with pytest.raises(ValueError, match="frames, joints, 2"):
        tracking_errors(np.zeros((3, 2)), np.zeros((3, 2)))
