"""Tests for toonmotion.capture.mocap: standard joints from mocap, projected to 2D."""

import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require
from toonmotion.capture.bvh_kinematics import forward_kinematics
from toonmotion.capture.mocap import (
    STANDARD_JOINTS,
    fit_to_frame,
    pick_joints,
    project_orthographic,
    standard_skeleton_parents,
)
from toonmotion.errors import MotionError, SettingsError
from toonmotion.io.bvh import load_bvh
from toonmotion.rig.skeleton import Skeleton

MOCAP_DIR = SHARED_DATA / "mocap"
CLIPS = sorted(p.name for p in MOCAP_DIR.glob("*.bvh")) or ["<missing>"]
S = {name: i for i, name in enumerate(STANDARD_JOINTS)}
# The chains a left/right pick must follow: each joint below the one before it.
LIMBS = [("shoulder", "elbow", "hand"), ("hip", "knee", "foot")]


def _tree(pairs, prefix=""):
    """Names and parent indices from ``(name, parent)`` pairs listed parents first."""
    names = [prefix + n for n, _ in pairs]
    parents = [-1 if p is None else names.index(prefix + p) for _, p in pairs]
    return names, np.array(parents)


def _sided(template):
    return [(n.format(s=s), p.format(s=s)) for s in ("Left", "Right") for n, p in template]


MIXAMO = [("Hips", None), ("Spine", "Hips"), ("Spine1", "Spine"), ("Spine2", "Spine1"), ("Neck", "Spine2"),
          ("Head", "Neck"), ("HeadTop_End", "Head")] + _sided([
    ("{s}Shoulder", "Spine2"), ("{s}Arm", "{s}Shoulder"), ("{s}ForeArm", "{s}Arm"), ("{s}Hand", "{s}ForeArm"),
    ("{s}HandIndex1", "{s}Hand"), ("{s}UpLeg", "Hips"), ("{s}Leg", "{s}UpLeg"), ("{s}Foot", "{s}Leg"),
    ("{s}ToeBase", "{s}Foot"), ("{s}Toe_End", "{s}ToeBase"),
])
ROKOKO = [("Hips", None), ("Spine", "Hips"), ("Spine1", "Spine"), ("Spine2", "Spine1"), ("Spine3", "Spine2"),
          ("Spine4", "Spine3"), ("Neck", "Spine4"), ("Head", "Neck")] + _sided([
    ("{s}Shoulder", "Spine4"), ("{s}Arm", "{s}Shoulder"), ("{s}ForeArm", "{s}Arm"), ("{s}Hand", "{s}ForeArm"),
    ("{s}UpLeg", "Hips"), ("{s}Leg", "{s}UpLeg"), ("{s}Foot", "{s}Leg"), ("{s}Toe", "{s}Foot"),
])
UNREAL = [("root", None), ("pelvis", "root"), ("spine_01", "pelvis"), ("spine_02", "spine_01"),
          ("spine_03", "spine_02"), ("neck_01", "spine_03"), ("head", "neck_01")] + [
    (n.format(s=s), p.format(s=s)) for s in ("l", "r") for n, p in [
        ("clavicle_{s}", "spine_03"), ("upperarm_{s}", "clavicle_{s}"), ("lowerarm_{s}", "upperarm_{s}"),
        ("hand_{s}", "lowerarm_{s}"), ("thigh_{s}", "pelvis"), ("calf_{s}", "thigh_{s}"),
        ("foot_{s}", "calf_{s}"), ("ball_{s}", "foot_{s}")]
]
SNAKE = [("hips", None), ("spine", "hips"), ("neck", "spine"), ("head", "neck")] + [
    (n.format(s=s), p.format(s=s)) for s in ("l", "r") for n, p in [
        ("{s}_shoulder", "neck"), ("{s}_elbow", "{s}_shoulder"), ("{s}_wrist", "{s}_elbow"),
        ("{s}_hip", "hips"), ("{s}_knee", "{s}_hip"), ("{s}_ankle", "{s}_knee")]
]
SYNTHETIC = {
    "mixamo": (MIXAMO, "mixamorig:"),
    "mixamo_bip": (MIXAMO, "Bip01 "),
    "rokoko": (ROKOKO, ""),
    "unreal": (UNREAL, ""),
    "snake": (SNAKE, ""),
}


@pytest.fixture(scope="module", params=CLIPS)
def clip(request):
    return load_bvh(_require(MOCAP_DIR) / request.param)


def _check_consistent(picks, names, parents):
    assert list(picks) == list(STANDARD_JOINTS)
    assert len(set(picks.values())) == len(STANDARD_JOINTS), "two standard joints share a joint"

    def below(j, ancestor):
        while j >= 0:
            j = parents[j]
            if j == ancestor:
                return True
        return False

    for side in ("left", "right"):
        for chain in LIMBS:
            for upper, lower in zip(chain, chain[1:], strict=False):
                assert below(picks[f"{side}_{lower}"], picks[f"{side}_{upper}"]), (side, upper, lower)
        for part in ("shoulder", "hip"):
            name = names[picks[f"{side}_{part}"]].lower()
            assert side in name or name.startswith(side[0]) or name.endswith(side[0]), (side, part, name)
            assert below(picks[f"{side}_{part}"], picks["hips"])
    for center in ("spine", "neck", "head"):
        assert below(picks[center], picks["hips"])
    assert below(picks["neck"], picks["spine"]) and below(picks["head"], picks["neck"])


def test_standard_skeleton_is_a_tree_rooted_at_the_hips():
    parents = standard_skeleton_parents()
    assert tuple(parents) == STANDARD_JOINTS
    skeleton = Skeleton.from_joints([(n, p, (0, i)) for i, (n, p) in enumerate(parents.items())])
    assert skeleton.names[0] == "hips" and (skeleton.parents == -1).sum() == 1
    assert parents["left_shoulder"] == parents["right_shoulder"] == "neck"
    assert parents["left_hip"] == parents["right_hip"] == "hips"


def test_pick_joints_finds_all_sixteen_in_every_shared_clip(clip):
    picks = pick_joints(clip.names, clip.parents)
    _check_consistent(picks, clip.names, clip.parents)
    named = {k: clip.names[v] for k, v in picks.items()}
    assert (named["hips"], named["neck"], named["head"]) == ("Hips", "Neck", "Head")
    # The shoulder is where the upper arm starts: LeftArm beside a clavicle LeftShoulder.
    assert named["left_shoulder"] == ("LeftShoulder" if "LeftCollar" in clip.names else "LeftArm")


@pytest.mark.parametrize("style", sorted(SYNTHETIC))
def test_pick_joints_reads_other_naming_conventions(style):
    pairs, prefix = SYNTHETIC[style]
    names, parents = _tree(pairs, prefix)
    picks = pick_joints(names, parents)
    _check_consistent(picks, names, parents)
    named = {k: names[v][len(prefix):] for k, v in picks.items()}
    expected = {
        "mixamo": ("Spine1", "LeftArm", "LeftForeArm", "LeftHand", "RightUpLeg", "RightLeg", "RightFoot"),
        "rokoko": ("Spine2", "LeftArm", "LeftForeArm", "LeftHand", "RightUpLeg", "RightLeg", "RightFoot"),
        "unreal": ("spine_02", "upperarm_l", "lowerarm_l", "hand_l", "thigh_r", "calf_r", "foot_r"),
        "snake": ("spine", "l_shoulder", "l_elbow", "l_wrist", "r_hip", "r_knee", "r_ankle"),
    }[style.removesuffix("_bip")]
    keys = ("spine", "left_shoulder", "left_elbow", "left_hand", "right_hip", "right_knee", "right_foot")
    assert tuple(named[k] for k in keys) == expected


def test_pick_joints_names_what_is_missing():
    renamed = {"RightShoulder": "RightCollarBone", "RightArm": "RightBone1", "RightForeArm": "RightBone2"}
    names, parents = _tree([(renamed.get(n, n), renamed.get(p, p)) for n, p in MIXAMO])
    message = r"standard joints right_shoulder, right_elbow among the mocap joints: Hips, Spine,"
    with pytest.raises(MotionError, match=message):
        pick_joints(names, parents)


@pytest.fixture(scope="module")
def jumping_jacks():
    clip = load_bvh(_require(MOCAP_DIR) / "cmu_jumping_jacks.bvh")
    picks = pick_joints(clip.names, clip.parents)
    return forward_kinematics(clip)[:, list(picks.values())]


def test_projected_jumping_jacks_stand_upright_facing_the_viewer(jumping_jacks):
    xy = project_orthographic(jumping_jacks)
    assert xy.shape == (len(jumping_jacks), 16, 2)
    assert np.all(xy[:, S["head"], 1] < xy[:, S["hips"], 1]), "head above hips (y down)"
    assert np.all(xy[:, S["neck"], 1] < xy[:, S["left_knee"], 1])
    # Facing the viewer: the character's left hand is on the image's right.
    assert xy[0, S["left_hand"], 0] > xy[0, S["right_hand"], 0]
    # The same picture as the explicit choice: +Y up, the character facing +Z (CMU's convention).
    explicit = project_orthographic(jumping_jacks, up="y", facing="z")
    size = np.ptp(explicit[0], axis=0).max()
    assert np.abs(xy[0] - explicit[0]).max() < 0.05 * size


def test_projection_finds_z_up_and_takes_full_joint_lists(tmp_path):
    # A FAIR clip is Z-up; project every joint, reading up and facing from the picks.
    clip = load_bvh(_require(MOCAP_DIR) / "fair_jumping.bvh")
    picks = pick_joints(clip.names, clip.parents)
    P = forward_kinematics(clip)
    xy = project_orthographic(P, joints=picks)
    assert xy.shape == (clip.frame_count, len(clip.names), 2)
    np.testing.assert_allclose(xy[:, :, 1], -P[:, :, 2], atol=1e-12)
    assert np.all(xy[:, picks["head"], 1] < xy[:, picks["hips"], 1])
    assert xy[0, picks["left_hand"], 0] > xy[0, picks["right_hand"], 0]
    with pytest.raises(MotionError, match="pass joints="):
        project_orthographic(P)
    with pytest.raises(SettingsError, match="up must be one of"):
        project_orthographic(P, up="w", facing="x")


def test_fit_to_frame_fits_every_frame_inside_the_margin_with_one_scale(jumping_jacks):
    xy = project_orthographic(jumping_jacks)
    W, H, margin = 640, 480, 0.1
    fitted = fit_to_frame(xy, (W, H), margin=margin)
    lo, hi = fitted.min(axis=(0, 1)), fitted.max(axis=(0, 1))
    eps = 1e-9
    assert np.all(lo >= [margin * W - eps, margin * H - eps])
    assert np.all(hi <= [(1 - margin) * W + eps, (1 - margin) * H + eps])
    # It touches the margin on one axis at least, and is centred.
    assert np.isclose(hi - lo, [(1 - 2 * margin) * W, (1 - 2 * margin) * H]).any()
    np.testing.assert_allclose((lo + hi) / 2, [W / 2, H / 2])
    # One uniform scale and a translation: every distance scales by the same factor, y stays down.
    scale = (fitted[5, 3] - fitted[0, 0]) / (xy[5, 3] - xy[0, 0])
    np.testing.assert_allclose(scale, scale[0])
    assert scale[0] > 0
    np.testing.assert_allclose(fitted - fitted[0, 0], (xy - xy[0, 0]) * scale[0], atol=1e-9)


def test_fit_to_frame_rejects_bad_settings():
    points = np.zeros((1, 2, 2))
    np.testing.assert_allclose(fit_to_frame(points, (100, 50)), [[[50, 25], [50, 25]]])
    with pytest.raises(SettingsError, match="margin"):
        fit_to_frame(points, margin=0.5)
    with pytest.raises(SettingsError, match="size"):
        fit_to_frame(points, (0, 10))


def test_depth_puts_the_chest_nearer_than_the_back():
    """A Y-up figure facing +Z: a point at +Z is nearer the camera (smaller depth)."""
    P = np.array([[[0.0, 1.0, 0.5], [0.0, 1.0, -0.5]]])
    points, depth = project_orthographic(P, up="y", facing="z", with_depth=True)
    np.testing.assert_array_equal(points, project_orthographic(P, up="y", facing="z"))
    assert depth[0, 0] < depth[0, 1]


def test_find_joints_finds_what_it_can_and_pick_joints_wants_all():
    """A drawn figure without a head joint (a shared drawing's skeleton): its roles are found, the
    head's is None; pick_joints, which wants all sixteen, says which is missing."""
    from toonmotion.capture.mocap import find_joints, pick_joints
    from toonmotion.errors import MotionError

    names = ["root", "hip", "torso", "neck", "right_shoulder", "right_elbow", "right_hand", "left_shoulder",
             "left_elbow", "left_hand", "right_hip", "right_knee", "right_foot", "left_hip", "left_knee",
             "left_foot"]
    parents = [-1, 0, 1, 2, 3, 4, 5, 3, 7, 8, 1, 10, 11, 1, 13, 14]
    found = find_joints(names, parents)
    assert found["head"] is None
    assert (found["hips"], found["spine"], found["left_hand"], found["right_foot"]) == (1, 2, 9, 12)
    with pytest.raises(MotionError, match="standard joint head among"):
        pick_joints(names, parents)
