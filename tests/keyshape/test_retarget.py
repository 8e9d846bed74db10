"""Retargeting key-shape motion (keyshape/retarget.py): the issue's properties, on the bundled
character's posed outlines and its skeleton."""

import numpy as np
import pytest

from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.contour import capture_contours
from toonmotion.keyshape.model import warp
from toonmotion.keyshape.retarget import pin, retarget_poses, retarget_shapes
from toonmotion.rig.kinematics import bone_angles


def _clip(keys, frames=10, seed=0):
    rng = np.random.default_rng(seed)
    out, weights = [], []
    for _ in range(frames):
        w = rng.dirichlet(np.ones(len(keys)))
        angle = rng.uniform(-0.3, 0.3)
        A = np.column_stack([rng.uniform(0.8, 1.2) * np.array([[np.cos(angle), -np.sin(angle)],
                                                                [np.sin(angle), np.cos(angle)]]),
                             rng.uniform(-60, 60, 2)])
        out.append(warp(A, w, keys))
        weights.append(w)
    return np.stack(out), np.array(weights)


def test_output_keys_equal_to_the_input_keys_give_the_input_back(outlines):
    clip, _ = _clip(outlines)
    found = capture_contours(clip, outlines)
    np.testing.assert_allclose(retarget_shapes(found, outlines, outlines), clip, atol=1e-6)


def test_a_smaller_character_elsewhere_moves_as_the_input_scaled_and_moved(outlines):
    clip, _ = _clip(outlines, seed=1)
    found = capture_contours(clip, outlines)
    other = outlines * 0.5 + [300, 40]  # the same keys drawn half size, elsewhere
    np.testing.assert_allclose(retarget_shapes(found, outlines, other), clip * 0.5 + [300, 40], atol=1e-6)


def test_key_poses_blend_bone_by_bone(outlines):
    from toonmotion import api
    from toonmotion.samples import sample_rig

    hero = sample_rig()
    poses = np.stack([hero.skeleton.positions, api.rotate_joint(hero, "right_elbow", -1.2).positions,
                      api.rotate_joint(hero, "left_shoulder", 0.9).positions])
    clip = np.stack([warp(np.eye(2, 3), w, outlines) for w in np.eye(3)])  # each key, unmoved
    found = capture_contours(clip, outlines)
    posed = retarget_poses(found, outlines, hero.skeleton, poses)
    np.testing.assert_allclose(posed, poses, atol=1e-6)  # each key's pose, exactly
    halfway = capture_contours([warp(np.eye(2, 3), [0.5, 0.5, 0], outlines)], outlines)
    between = retarget_poses(halfway, outlines, hero.skeleton, poses)[0]
    angles, lengths = bone_angles(hero.skeleton, between)
    key_angles, key_lengths = bone_angles(hero.skeleton, poses[:2])
    np.testing.assert_allclose(lengths, key_lengths.mean(axis=0), atol=1e-6)
    np.testing.assert_allclose(np.angle(np.exp(1j * (angles - (key_angles[0] + key_angles[1]) / 2))), 0,
                               atol=1e-6)


def test_pinned_points_hit_their_targets_exactly(outlines):
    clip, _ = _clip(outlines, frames=12, seed=2)
    found = capture_contours(clip, outlines)
    shapes = retarget_shapes(found, outlines, outlines)
    foot = int(np.argmax(outlines[0][:, 1]))  # the lowest point: a foot
    targets = {0: (100.0, 400.0), 5: (130.0, 400.0), 11: (180.0, 400.0)}
    pinned = pin(shapes, foot, targets)
    for frame, target in targets.items():
        np.testing.assert_allclose(pinned[frame, foot], target, atol=1e-9)
    moved = pinned - shapes  # one translation per frame: the shape itself is untouched
    np.testing.assert_allclose(moved, moved[:, :1].repeat(moved.shape[1], axis=1), atol=1e-9)


def test_mismatched_keys_are_refused(outlines):
    clip, _ = _clip(outlines)
    found = capture_contours(clip, outlines)
    with pytest.raises(KeyShapeError, match="pair every input key"):
        retarget_shapes(found, outlines, outlines[:2])
    with pytest.raises(KeyShapeError, match="weights for 3 keys"):
        retarget_shapes(found, outlines[:2], outlines[:2])
    with pytest.raises(KeyShapeError, match="within the motion's"):
        pin(clip, 0, {99: (0, 0)})


def _sample_drawing():
    """The bundled character's picture (RGBA, as rigged) and its outline (every 4th point)."""
    from toonmotion.samples import sample_rig

    hero = sample_rig()
    return hero.texture, hero.mesh.V[hero.mesh.boundary[0][::4]]


def test_a_drawing_moved_by_its_own_outline_is_itself():
    from toonmotion import api

    picture, outline = _sample_drawing()
    still, shifted = api.animate_drawing(picture, outline, [outline, outline + [7, 3]])
    assert still.shape == shifted.shape
    low = np.floor(np.vstack([outline, outline + [7, 3]]).min(axis=0) - 8).astype(int)  # the canvas origin
    inside = np.argwhere(still[..., 3] == 255)
    assert len(inside) > 0.5 * (picture[..., 3] == 255).sum()  # most of the figure is drawn
    ys, xs = inside[:, 0], inside[:, 1]
    np.testing.assert_array_equal(still[ys, xs], picture[ys + low[1], xs + low[0]])  # pixel for pixel
    np.testing.assert_array_equal(shifted[ys + 3, xs + 7], still[ys, xs])  # and moved whole


def test_a_drawing_follows_a_stretched_outline():
    from toonmotion import api

    picture, outline = _sample_drawing()
    centre = outline.mean(axis=0)
    tall = centre + (outline - centre) * [1.0, 1.5]
    still, stretched = api.animate_drawing(picture, outline, [outline, tall])
    height = [np.ptp(np.argwhere(frame[..., 3] > 127)[:, 0]) for frame in (still, stretched)]
    assert abs(height[1] - 1.5 * height[0]) <= 3  # half as tall again, within a pixel or two
    with pytest.raises(KeyShapeError, match="correspondence"):
        api.animate_drawing(picture, outline, [tall[:-1]])
