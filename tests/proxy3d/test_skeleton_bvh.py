"""The skeleton proxy as a joint-per-limb tree and BVH clip (toonmotion.proxy3d.skeleton_bvh)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tests.proxy3d.synthetic_proxy import BRANCHING, FOREST, synthetic_proxy
from toonmotion.capture.bvh_kinematics import forward_kinematics
from toonmotion.io.bvh import load_bvh, save_bvh
from toonmotion.proxy3d.skeleton_bvh import LIMB_CHANNELS, ROOT_CHANNELS, limb_tree, skeleton_clip

CASES = {
    "branching": dict(hierarchy=BRANCHING),
    "forest": dict(hierarchy=FOREST),
    "gimbal lock": dict(hierarchy=FOREST, gimbal=True, seed=3),
    "one marker": dict(hierarchy={"ball": None}, frames=2),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_forward_kinematics_reproduce_the_skeleton(case):
    proxy = synthetic_proxy(**CASES[case])
    clip = skeleton_clip(proxy)
    fk = forward_kinematics(clip)
    error = np.abs(fk[:, limb_tree(proxy).markers] - proxy.skeleton).max()
    assert error < 1e-6, f"{case}: FK differs from the skeleton by {error:.3g} m"


@pytest.mark.parametrize("case", sorted(CASES))
def test_each_limb_joint_sits_at_its_parent_marker_and_carries_the_limb(case):
    proxy = synthetic_proxy(**CASES[case])
    tree, clip = limb_tree(proxy), skeleton_clip(proxy)
    fk = forward_kinematics(clip)
    for j in np.flatnonzero(tree.limbs >= 0):
        p, c = proxy.limbs[tree.limbs[j]]
        assert clip.names[j] == proxy.names[c]
        assert clip.channels[j] == LIMB_CHANNELS
        assert np.abs(fk[:, j] - proxy.skeleton[:, p]).max() < 1e-6
    for j in tree.roots:
        assert clip.channels[j] == ROOT_CHANNELS and np.all(clip.motion[:, 3:6] == 0)
    leaves = [n for n in range(len(proxy.names)) if n not in proxy.parents and proxy.parents[n] >= 0]
    ends = sorted(clip.names[tree.markers[n]] for n in leaves)
    assert ends == sorted(f"{proxy.names[n]}_end" for n in leaves)
    assert len(set(clip.names)) == len(clip.names)
    assert np.all(tree.parents < np.arange(len(tree.parents)))


def test_a_branching_marker_has_a_joint_per_child_limb():
    proxy = synthetic_proxy(BRANCHING)
    clip = skeleton_clip(proxy)
    pelvis = clip.names.index("pelvis")
    under = sorted(n for n, p in zip(clip.names, clip.parents, strict=True) if p == pelvis)
    assert under == ["left_hip", "right_hip", "spine"]  # three joints at the pelvis, one per limb
    for name in under:
        assert np.array_equal(clip.offsets[clip.names.index(name)], np.zeros(3))


def test_local_rotations_compose_to_the_limbs_global_rotations():
    proxy = synthetic_proxy(FOREST)
    tree = limb_tree(proxy)
    local = tree.local_rotations(proxy.limb_rotations)
    for j in np.flatnonzero(tree.limbs >= 0):
        world, i = Rotation.identity(proxy.frame_count), j
        while i >= 0:
            world = Rotation.from_quat(local[:, i]) * world
            i = tree.parents[i]
        expected = Rotation.from_quat(proxy.limb_rotations[:, tree.limbs[j]])
        assert np.abs((world * expected.inv()).magnitude()).max() < 1e-9


def test_clip_survives_a_bvh_file_exactly(tmp_path):
    proxy = synthetic_proxy(FOREST, gimbal=True)
    clip = skeleton_clip(proxy)
    save_bvh(tmp_path / "skeleton.bvh", clip)
    back = load_bvh(tmp_path / "skeleton.bvh")
    assert back.names == clip.names and back.channels == clip.channels
    assert np.array_equal(back.parents, clip.parents) and np.array_equal(back.offsets, clip.offsets)
    assert np.array_equal(back.motion, clip.motion) and back.frame_time == clip.frame_time
    error = np.abs(forward_kinematics(back)[:, limb_tree(proxy).markers] - proxy.skeleton).max()
    assert error < 1e-6
    assert clip.frame_time == 1 / proxy.fps


def test_end_site_names_avoid_marker_names_as_the_bvh_reader_does(tmp_path):
    # A marker already called "head_end": the End Site after "head" is "head_end2", as load_bvh names it.
    hierarchy = {"neck": None, "head": "neck", "head_end": None, "head_end_tip": "head_end"}
    proxy = synthetic_proxy(hierarchy, frames=2)
    clip = skeleton_clip(proxy)
    assert "head_end2" in clip.names and "head_end" in clip.names
    save_bvh(tmp_path / "clip.bvh", clip)
    assert load_bvh(tmp_path / "clip.bvh").names == clip.names
