"""Sub-parts (keyshape/parts.py, 3.1.4) on the bundled character's posed outlines, split into
an upper and a lower half that share the points where they meet."""

import numpy as np
import pytest

from toonmotion import api
from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.model import warp


def _halves(outline):
    """Point numbers above and below the outline's middle height, sharing a band 6 px deep."""
    middle = np.median(outline[:, 1])
    upper = np.flatnonzero(outline[:, 1] <= middle + 3)
    lower = np.flatnonzero(outline[:, 1] >= middle - 3)
    return {"upper": upper.tolist(), "lower": lower.tolist()}


def _turn(angle, shift):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, shift[0]], [s, c, shift[1]]])


def test_each_part_gets_its_own_affine_and_weights_back(outlines):
    parts = _halves(outlines[0])
    rng = np.random.default_rng(3)
    truths, clip = [], []
    for _ in range(6):
        frame = np.empty_like(outlines[0])
        truth = {}
        for name, points in parts.items():  # the shared points follow the upper half's model
            A, w = _turn(rng.uniform(-0.2, 0.2), rng.uniform(-20, 20, 2)), rng.dirichlet(np.ones(3))
            truth[name] = (A, w)
            frame[points] = warp(A, w, outlines)[points]
        clip.append(frame)
        truths.append(truth)
    # The shared points were written last by the lower half: they are its, not the upper's.
    shared = np.intersect1d(parts["upper"], parts["lower"])
    own = {"upper": np.setdiff1d(parts["upper"], shared).tolist(), "lower": parts["lower"]}
    found = api.capture_parts(clip, outlines, own)
    for t, truth in enumerate(truths):
        for name in own:
            A, w = truth[name]
            np.testing.assert_allclose(found[name].affine[t], A, atol=1e-6)
            np.testing.assert_allclose(found[name].weights[t], w, atol=1e-6)
    # The whole outline as one part cannot follow two motions: parts fit far better.
    whole = api.capture_contours(clip, outlines)
    assert whole.error.mean() > 100 * max(f.error.mean() for f in found.values())


def test_the_same_keys_give_the_input_back_and_the_parts_stay_together(outlines):
    parts = _halves(outlines[0])
    clip = [warp(_turn(0.1 * t, (5 * t, 0)), [1 - t / 4, t / 4, 0], outlines) for t in range(5)]
    found = api.capture_parts(clip, outlines, parts)
    np.testing.assert_allclose(api.retarget_parts(found, outlines, outlines, parts, parts), clip, atol=1e-6)
    # Output keys at half size, split the same way: one map places every part, so the result is
    # the input at half size, shared points and all.
    half = api.retarget_parts(found, outlines, outlines * 0.5, parts, parts)
    whole = api.retarget_keyshapes(api.capture_contours(clip, outlines), outlines, outlines * 0.5)
    np.testing.assert_allclose(half, whole, atol=1e-6)


def test_one_part_is_the_whole(outlines):
    clip = [warp(_turn(0.05 * t, (2 * t, t)), [1 - t / 4, 0, t / 4], outlines) for t in range(5)]
    everything = {"all": list(range(outlines.shape[1]))}
    found = api.capture_parts(clip, outlines, everything)["all"]
    np.testing.assert_allclose(found.affine, api.capture_contours(clip, outlines).affine, atol=1e-9)


@pytest.mark.parametrize(("parts", "message"), [
    ({"a": [0, 1]}, "at least 3 distinct points"),
    ({"a": [0, 1, 9999]}, "outside"),
    ({"a": [0, 1, 2]}, "is in no part"),
    ({}, "at least one part"),
])
def test_bad_parts_are_refused_in_one_line(outlines, parts, message):
    with pytest.raises(KeyShapeError, match=message) as info:
        api.capture_parts(outlines, outlines, parts)
    assert "\n" not in str(info.value)


def test_parts_that_do_not_pair_up_are_refused(outlines):
    parts = _halves(outlines[0])
    found = api.capture_parts(outlines, outlines, parts)
    with pytest.raises(KeyShapeError, match="pair every part"):
        api.retarget_parts(found, outlines, outlines, parts, {"upper": list(range(outlines.shape[1]))})
