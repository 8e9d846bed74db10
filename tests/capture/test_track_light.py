"""Tests for toonmotion.capture.track_light: frames seen in the light of the first."""

import numpy as np
import pytest

from tests.capture.test_tracker import _errors, _setup, _wander
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.track_light import Relit, light_levels, relight
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.capture.tracker import track
from toonmotion.errors import ToonmotionError


def _dim_and_flicker(canvas, t):
    """40% dimmer over 150 frames, flickering by 25 grey levels (a lamp, a camera's exposure)."""
    return canvas * (1 - 0.4 * t / 150) + 25 * np.sin(t / 3)


def _strobe(canvas, t):
    """Half as bright every other 5 frames (a camera's exposure hunting)."""
    return canvas * (0.5 if (t // 5) % 2 else 1.0)


def test_a_joint_is_seen_in_every_frame_though_the_light_jumps():
    frames, truth = _wander(light=_strobe)
    relit = track(frames, _setup([("dot", None)], truth[0]))
    raw = track(frames, _setup([("dot", None)], truth[0]), settings=TrackSettings(relight=False))
    assert relit.confidence[:, 0].min() > 0.8
    errors = _errors(relit, truth)
    assert errors.max() <= 0.2, f"worst error {errors.max():.3f} px at frame {errors.argmax()}"
    # Without, the joint is taken to be hidden in every dark frame (and coasts through them).
    assert (raw.confidence[:, 0] < MatchTuning().visible_confidence).sum() == 75


def test_frames_in_the_light_of_the_first_are_left_exactly_as_they_are():
    # A square wandering over a still background: the border's levels do not move with it.
    frames, _ = _wander()
    seen = Relit(frames, frames[0])
    assert len(seen) == len(frames)
    reference = light_levels(frames[0])
    for t in range(0, len(frames), 10):
        frame = frames[t]
        assert relight(frame, reference) is frame
        np.testing.assert_array_equal(seen[t], frame)


def test_a_relit_frame_takes_the_reference_levels():
    frames, _ = _wander(light=_dim_and_flicker)
    reference = light_levels(frames[0])
    for t in (50, 100, 149):
        assert not np.array_equal(relight(frames[t], reference), frames[t])
        np.testing.assert_allclose(light_levels(relight(frames[t], reference)), reference, atol=3.0)


def test_a_bad_frame_still_gets_the_trackers_own_error():
    frames, truth = _wander(T=6)
    bad = list(frames)
    bad[3] = frames[3].astype(np.float32)
    with pytest.raises(ToonmotionError, match="frame 3 is a float32 array"):
        track(bad, _setup([("dot", None)], truth[0]))
