"""The pose descriptor and the prior's modification (toonmotion.proxy3d.descriptor, paper 3.2)."""

import numpy as np
import pytest

from tests.proxy3d.conftest import clip_path
from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.errors import ProxyError
from toonmotion.geometry.angles import wrap_angle
from toonmotion.io.bvh import load_bvh
from toonmotion.proxy3d.descriptor import limb_vectors, modify_prior, pose_descriptor, upper_body
from toonmotion.proxy3d.orthographic import camera
from toonmotion.proxy3d.prior import Prior, prior_from_bvh, resample_prior
from toonmotion.rig.kinematics import rotate

UPPER = {"spine", "neck", "head", "left_shoulder", "left_elbow", "left_hand", "right_shoulder", "right_elbow",
         "right_hand"}


@pytest.mark.parametrize("name", ["cmu_07_01_walk.bvh", "cmu_jumping_jacks.bvh", "fair_zombie.bvh"])
def test_upper_body_comes_from_the_tree(name):
    prior = prior_from_bvh(load_bvh(clip_path(name)), STANDARD_JOINTS, start=1)
    assert {n for n, up in zip(prior.names, upper_body(prior), strict=True) if up} == UPPER


def test_upper_body_does_not_read_names(walk_prior):
    renamed = Prior(tuple(f"m{i}" for i in range(len(walk_prior.names))), walk_prior.parents,
                    walk_prior.positions, walk_prior.fps)
    assert np.array_equal(upper_body(renamed), upper_body(walk_prior))
    chosen = upper_body(walk_prior, upper=["left_hand"])
    assert chosen.sum() == 1 and chosen[walk_prior.names.index("left_hand")]
    with pytest.raises(ProxyError, match="upper body names 'tail'"):
        upper_body(walk_prior, upper=["tail"])


def test_descriptor_ignores_translation_scale_and_limb_lengths(walk_prior):
    P = walk_prior.positions @ camera(40, 10).T
    limbs = walk_prior.limbs
    theta = pose_descriptor(P, limbs)
    assert theta.shape == (len(P), len(walk_prior.names) - 1)
    assert np.all((theta >= -np.pi) & (theta < np.pi))
    assert np.allclose(pose_descriptor(2.5 * P + [300, -40], limbs), theta, atol=1e-12)
    # Stretch every limb by its own factor, rebuilding from the root: angles unchanged.
    v = limb_vectors(P, limbs) * np.linspace(0.5, 2, len(limbs))[:, None]
    stretched = P.copy()
    for k, (p, c) in enumerate(limbs):
        stretched[:, c] = stretched[:, p] + v[:, k]
    assert np.allclose(wrap_angle(pose_descriptor(stretched, limbs) - theta), 0, atol=1e-12)


def test_relative_descriptor_ignores_a_turn_of_the_whole_figure(walk_prior):
    P = walk_prior.positions @ camera(-70, 20).T
    limbs = walk_prior.limbs
    rel = pose_descriptor(P, limbs, relative=True)
    turned = pose_descriptor(rotate(P, 0.7), limbs, relative=True)
    roots = np.array([walk_prior.parents[p] < 0 for p, _ in limbs])  # limbs from the root turn with it
    assert np.allclose(wrap_angle(turned[:, ~roots] - rel[:, ~roots]), 0, atol=1e-12)
    assert np.allclose(wrap_angle(turned[:, roots] - rel[:, roots]), 0.7, atol=1e-12)
    # relative = own absolute angle minus the parent limb's
    absolute = pose_descriptor(P, limbs)
    k = [tuple(limb) for limb in limbs.tolist()].index((walk_prior.names.index("left_elbow"),
                                                        walk_prior.names.index("left_hand")))
    parent = [tuple(limb) for limb in limbs.tolist()].index((walk_prior.names.index("left_shoulder"),
                                                             walk_prior.names.index("left_elbow")))
    assert np.allclose(rel[:, k], wrap_angle(absolute[:, k] - absolute[:, parent]))


@pytest.fixture(scope="module")
def modified(walk_prior):
    """The walk seen from the front-left, modified to match jumping jacks drawn from the front."""
    jacks = prior_from_bvh(load_bvh(clip_path("cmu_jumping_jacks.bvh")), STANDARD_JOINTS, start=1)
    jacks = resample_prior(jacks, walk_prior.fps)
    T = min(jacks.frame_count, walk_prior.frame_count)
    drawn = 40 * jacks.positions[:T] @ camera(0, 5).T + [320, 240]
    projected = 20 * walk_prior.positions[:T] @ camera(30, 10).T + [100, 50]
    up = upper_body(walk_prior)
    return projected, drawn, up, walk_prior.limbs, modify_prior(projected, drawn, walk_prior.limbs, up)


def test_modified_upper_body_takes_the_drawn_angles(modified):
    projected, drawn, up, limbs, out = modified
    upper_limbs = up[limbs[:, 1]]
    assert upper_limbs.sum() == len(UPPER) and (~upper_limbs).sum() == 6
    for relative in (False, True):
        got = pose_descriptor(out, limbs, relative=relative)[:, upper_limbs]
        want = pose_descriptor(drawn, limbs, relative=relative)[:, upper_limbs]
        assert np.abs(wrap_angle(got - want)).max() < 1e-9
    # ... and the drawing's angles are not the prior's to begin with.
    before = pose_descriptor(projected, limbs)[:, upper_limbs]
    assert np.abs(wrap_angle(before - pose_descriptor(drawn, limbs)[:, upper_limbs])).max() > 1


def test_modified_lower_body_and_limb_lengths_are_the_prior_s(modified):
    projected, drawn, up, limbs, out = modified
    lower = ~up
    assert np.array_equal(out[:, lower], projected[:, lower])  # pelvis and legs untouched, exactly
    length = np.linalg.norm(limb_vectors(out, limbs), axis=-1)
    assert np.allclose(length, np.linalg.norm(limb_vectors(projected, limbs), axis=-1), rtol=0, atol=1e-9)


def test_a_drawn_limb_of_no_length_keeps_the_prior_s_direction():
    projected = np.array([[[0.0, 0], [0, -10], [5, -10]]])
    drawn = np.array([[[0.0, 0], [0, -20], [0, -20]]])  # the hand on the elbow
    out = modify_prior(projected, drawn, [[0, 1], [1, 2]], [False, True, True])
    assert out[0].tolist() == [[0, 0], [0, -10], [5, -10]]


def test_modify_prior_checks_shapes():
    with pytest.raises(ProxyError, match="same shape"):
        modify_prior(np.zeros((2, 3, 2)), np.zeros((3, 3, 2)), [[0, 1]], [False, True, True])
    with pytest.raises(ProxyError, match="each of the 3 markers"):
        modify_prior(np.zeros((2, 3, 2)), np.zeros((2, 3, 2)), [[0, 1]], [False, True])
