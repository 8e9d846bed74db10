"""Tests for toonmotion.capture.clip_tuning: how the tracker reads the clip round its search, as
settings. The defaults are the tracker's; each value given changes what it governs as its
documentation says, and bad values are refused in one line."""

import numpy as np
import pytest

from tests.capture.test_track_gaps import _turning_bone
from tests.capture.test_tracker import _setup, _translation
from toonmotion.capture.clip_tuning import ClipTuning
from toonmotion.capture.track_figure import FigureMasks, onto_figure
from toonmotion.capture.track_gaps import fill_hidden_spans
from toonmotion.capture.track_light import light_levels, relight
from toonmotion.capture.track_prediction import is_held
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.capture.tracker import track
from toonmotion.errors import TrackingError


def test_the_defaults_are_the_measured_values_and_track_settings_carry_them():
    clip = ClipTuning()
    assert (clip.coast_steps, clip.held_level, clip.held_fraction, clip.pull_reach) == (4, 16.0, 1e-4, 4.0)
    assert TrackSettings().clip == clip
    assert TrackSettings(clip=ClipTuning(coast_steps=2)).clip.coast_steps == 2


def test_a_frame_is_held_below_held_level_and_held_fraction():
    rng = np.random.default_rng(0)
    still = rng.integers(0, 256, (60, 80, 3), dtype=np.uint8)
    moved = still.copy()
    moved[10:20, 10:20] = np.clip(still[10:20, 10:20].astype(int) + 20, 0, 255)  # 2 % of values, 20 levels
    assert not is_held(moved, still)
    assert is_held(moved, still, tuning=ClipTuning(held_level=30))  # 20 levels is noise now
    assert is_held(moved, still, tuning=ClipTuning(held_fraction=0.05))  # 2 % is few enough now


def test_a_clip_read_as_all_held_drawings_stands_still():
    frames, truth = _translation()
    moving = track(frames, _setup([("dot", None)], truth[0]))
    assert not moving.held[1:].any()
    still = track(frames, _setup([("dot", None)], truth[0]),
                  settings=TrackSettings(clip=ClipTuning(held_level=255)))
    assert still.held[1:].all() and (still.positions == still.positions[0]).all()


def test_guesses_that_miss_their_span_by_more_than_trusted_are_dropped():
    truth = _turning_bone()
    P, C = truth.copy(), np.ones((12, 2))
    # Guesses far off, zigzagging about the parent.
    P[3:8, 1], C[3:8, 1] = 100 + np.array([[60.0, 0], [0, 60], [-60, 0], [0, -60], [60, 0]]), 0.2
    args = (np.array([-1, 0]), np.ones(12, bool), np.zeros(12, bool))
    np.testing.assert_allclose(fill_hidden_spans(P, C, *args), truth, atol=1e-9)
    trusting = fill_hidden_spans(P, C, *args, tuning=ClipTuning(trusted=1e9))  # the guesses kept, bent
    assert np.abs(trusting[3:8, 1] - truth[3:8, 1]).max() > 10


def test_figure_slack_and_pull_reach():
    mask = np.zeros((1, 10, 10), bool)
    mask[0, :, 6:] = True
    near = {s: FigureMasks(mask, 1, (10, 10), tuning=ClipTuning(figure_slack=s)).near(0) for s in (0.0, 2.0)}
    assert near[0.0][:, 5].max() == 0 and near[2.0][:, 4].min() > 0  # two columns more are on it
    point = np.array([2.0, 4.0])  # 4 px off the figure
    assert onto_figure(near[0.0], point, 3.0).tolist() == [5.0, 4.0]  # a limit's step towards it
    assert onto_figure(near[0.0], point, 3.0, pull=1.0).tolist() == [2.0, 4.0]  # beyond one limit: left


def test_a_change_of_light_within_light_tolerance_is_left_alone():
    dark = np.tile(np.arange(20, 120, dtype=np.uint8), (8, 1)).repeat(3).reshape(8, 100, 3)
    brighter = light_levels(dark + 10)
    assert relight(dark, brighter) is not dark  # 10 levels: relit
    assert relight(dark, brighter, ClipTuning(light_tolerance=12.0)) is dark


@pytest.mark.parametrize("given, message", [
    ({"coast_steps": 0}, "coast_steps must be a whole number >= 1, got 0"),
    ({"light_samples": 1.5}, "light_samples must be a whole number >= 1"),
    ({"held_fraction": 2}, "held_fraction must be a finite number from 0 to 1, got 2.0"),
    ({"pull_reach": 0.5}, "pull_reach must be a finite number >= 1, got 0.5"),
    ({"held_level": -1}, "held_level must be a finite number >= 0"),
    ({"trusted": float("inf")}, "trusted must be a finite number >= 0"),
])
def test_bad_values_are_refused_in_one_line(given, message):
    with pytest.raises(TrackingError) as caught:
        ClipTuning(**given)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_track_settings_refuse_a_clip_tuning_of_another_kind():
    with pytest.raises(TrackingError, match="clip must be a ClipTuning, got SearchTuning"):
        from toonmotion.capture.search_tuning import SearchTuning
        TrackSettings(clip=SearchTuning())
