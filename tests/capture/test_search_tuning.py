"""Tests for toonmotion.capture.search_tuning: the tracker's search tuning as settings.

The defaults are the tracker's (the suite's other tracking tests run with them); here each value
given changes what the tracker does as its documentation says, on the scenes of
``tests/capture/test_tracker.py``, and bad values are refused in one line.
"""

import math

import numpy as np
import pytest

from tests.capture.test_tracker import _arm_under_covers, _errors, _setup
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.search_tuning import SearchTuning
from toonmotion.capture.track_path import best_paths
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.capture.tracker import track
from toonmotion.errors import TrackingError

ARM = [("shoulder", None), ("elbow", "shoulder"), ("hand", "elbow")]


def test_the_defaults_are_the_measured_values_and_track_settings_carry_them():
    tuning = SearchTuning()
    assert (tuning.places, tuning.reacquire_confidence, tuning.weak_confidence) == (64, 0.35, 0.5)
    assert tuning.span_step == pytest.approx(math.radians(45))
    assert TrackSettings().tuning == tuning
    assert TrackSettings(tuning=SearchTuning(places=8)).tuning.places == 8


@pytest.fixture(scope="module")
def arm():
    """The arm whose hand hides under a cover for frames 10-24 and re-emerges 15 px on, its
    elbow covered from frame 10 on; with the default tuning the hand is found again."""
    frames, truth = _arm_under_covers()
    return frames, truth, track(frames, _setup(ARM, truth[0]))


def test_a_hand_is_found_again_only_by_a_match_as_confident_as_reacquire_confidence(arm):
    frames, truth, default = arm
    again = default.confidence[27:, 2]
    assert (again >= SearchTuning().reacquire_confidence).all()
    # Asking for more than its matches give (they are below 1), it is never found again.
    strict = track(frames, _setup(ARM, truth[0]),
                   settings=TrackSettings(tuning=SearchTuning(reacquire_confidence=1.0)))
    assert (strict.confidence[12:, 2] < MatchTuning().visible_confidence).all()
    assert _errors(strict, truth)[27:, 2].max() > 5 * _errors(default, truth)[27:, 2].max()


def test_without_widening_a_hidden_hand_is_not_looked_for_where_it_re_emerged(arm):
    """The hand re-emerges 15 px from where it hid, beyond one search radius (10 px) of where it
    is carried: found in the window widened while it hid, not without widening."""
    frames, truth, default = arm
    assert _errors(default, truth)[27:, 2].max() < 1.0
    narrow = track(frames, _setup(ARM, truth[0]), settings=TrackSettings(tuning=SearchTuning(widen_step=0.0)))
    assert (narrow.confidence[25:, 2] < MatchTuning().visible_confidence).mean() > 0.5


@pytest.mark.parametrize("given, message", [
    ({"places": 0}, "places must be a whole number >= 1, got 0"),
    ({"places": 2.5}, "places must be a whole number >= 1"),
    ({"places": True}, "places must be a whole number >= 1"),
    ({"reacquire_confidence": 1.5}, "reacquire_confidence must be a finite number from 0 to 1, got 1.5"),
    ({"weak_confidence": -0.1}, "weak_confidence must be a finite number from 0 to 1"),
    ({"span_step": 0}, "span_step must be a finite number > 0"),
    ({"textured_colour_weight": float("nan")}, "textured_colour_weight must be a finite number > 0"),
    ({"widen_step": -1}, "widen_step must be a finite number >= 0"),
    ({"bone_weight": "1"}, "bone_weight must be a number >= 0, got '1'"),
    ({"max_hold": 0}, "max_hold must be a whole number >= 1, got 0"),
    ({"max_widen": 0.5}, "max_widen must be a finite number >= 1, got 0.5"),
    ({"min_search": 0}, "min_search must be a finite number >= 1"),
    ({"search_fraction": -1}, "search_fraction must be a finite number > 0"),
])
def test_bad_values_are_refused_in_one_line(given, message):
    with pytest.raises(TrackingError) as caught:
        SearchTuning(**given)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_track_settings_refuse_a_tuning_of_another_kind():
    with pytest.raises(TrackingError, match="tuning must be a SearchTuning, got dict"):
        TrackSettings(tuning={"places": 8})


def test_every_value_is_documented_with_its_unit_or_range():
    doc = SearchTuning.__doc__
    for name in SearchTuning.__dataclass_fields__:
        entry = doc.split(f"    {name} : ", 1)[1].split("\n    ", 2)[1]
        assert any(word in entry for word in ("0 to 1", "Radians", "radii", "times", "How many", "Of ",
                                              "Pixels", "weight")), (name, entry)



def test_the_whole_clip_pass_steps_no_farther_than_max_widen_radii():
    """A joint matched poorly all along, with a perfect look-alike 30 px away on every frame after
    the first: beyond the widest window at 3 radii (24 px), it is left alone; at 4 (32 px) the pass
    takes it."""
    T = 8
    P, C = np.zeros((T, 1, 2)), np.full((T, 1), 0.3)
    options = np.full((T, 1, 1, 3), np.nan)
    options[1:, 0, 0] = (30.0, 0.0, 1.0)

    def taken(widest):
        found, _ = best_paths(P, C, options, np.array([-1]), np.arange(T), np.array([8.0]),
                              tuning=SearchTuning(max_widen=widest))
        return {tuple(x) for x in found[1:, 0]}

    assert taken(3.0) == {(0.0, 0.0)}
    assert taken(4.0) == {(30.0, 0.0)}


def test_the_default_search_radius_follows_search_fraction_and_min_search():
    """Through the tracker's plans: the radius is max(min_search, search_fraction x the larger
    side) unless TrackSettings.search is given."""
    from toonmotion.capture.tracker import _plans

    frames, truth = _arm_under_covers(T=3)
    setup = _setup(ARM, truth[0])  # rectangles 20 px a side
    radius = {}
    for key, tuning in {"default": SearchTuning(), "wide": SearchTuning(search_fraction=1.5),
                        "floor": SearchTuning(search_fraction=0.1, min_search=6.0)}.items():
        plans = _plans(setup, TrackSettings(tuning=tuning), frames[0], truth[0])
        radius[key] = plans(0).radius
    assert radius == {"default": 10.0, "wide": 30.0, "floor": 6.0}
    settings = TrackSettings(search=12.0, tuning=SearchTuning(search_fraction=1.5))
    given = _plans(setup, settings, frames[0], truth[0])
    assert given(0).radius == 12.0
