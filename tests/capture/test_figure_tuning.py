"""Tests for toonmotion.capture.figure_tuning: how the figure is found and the joints' rectangles
suggested, as settings. The defaults are the library's (the suite's foreground and set-up tests
run with them); each value given changes what it governs as its documentation says, and bad
values are refused in one line."""

import numpy as np
import pytest

from tests.capture.test_match_tuning import documented
from toonmotion.capture.figure_tuning import FigureTuning
from toonmotion.capture.footage import _masks, suggested_sizes
from toonmotion.capture.foreground import cleaned_mask, flat_threshold, without_frame
from toonmotion.capture.setup import rectangle_sizes, size_scale
from toonmotion.capture.track_scale import WORKING_SIDE
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.errors import TrackingError


def test_the_defaults_are_the_constants_they_replace_and_the_settings_carry_them():
    tuning = FigureTuning()
    assert (tuning.threshold_low, tuning.threshold_high) == (20.0, 100.0)
    assert (tuning.size_low, tuning.size_high) == (8.0, 48.0)
    assert tuning.frame_side == WORKING_SIDE and tuning.thickness_reach == 3
    assert TrackSettings().cutout == tuning
    assert TrackSettings(cutout=FigureTuning(size_high=64)).cutout.size_high == 64


def test_the_flat_threshold_lies_within_its_range_and_paper_is_no_farther_than_its_top():
    """Paper whose light falls off 15 grey levels a channel (45 summed) on half the frame."""
    frame = np.full((10, 10, 3), 250, np.uint8)
    frame[:, :5] = 235
    white = (250, 250, 250)
    assert flat_threshold(frame, white) == 45.0
    assert flat_threshold(frame, white, FigureTuning(threshold_low=60)) == 60.0
    # Beyond the top, the darker half is not paper: the rest differs by nothing, the low end is taken.
    assert flat_threshold(frame, white, FigureTuning(threshold_high=40)) == 20.0


def test_the_figure_the_tracker_holds_joints_to_is_found_with_the_settings_cutout():
    frames = np.full((2, 20, 20, 3), 240, np.uint8)
    frames[:, 5:15, 5:15] = 200  # a fill 120 off the paper, summed
    frames[:, 8:12, 8:12] = 0
    assert _masks(frames, None, None)[0].sum() == 100
    strict = TrackSettings(cutout=FigureTuning(threshold_low=130, threshold_high=150))
    assert _masks(frames, strict, None)[0].sum() == 16  # the fill is paper now


def test_specks_and_holes_under_clean_fraction_are_cleaned():
    mask = np.zeros((100, 100), bool)
    mask[10:90, 10:90] = True
    mask[50, 50] = False  # a hole of one pixel
    mask[2:4, 2:4] = True  # a speck of four
    default = cleaned_mask(mask)
    assert default[50, 50] and not default[2, 2]
    kept = cleaned_mask(mask, FigureTuning(clean_fraction=1e-4))
    assert not kept[50, 50] and kept[2, 2]


def test_a_frame_round_the_picture_goes_by_frame_line_frame_depth_and_frame_fill():
    mask = np.zeros((100, 100), bool)
    mask[:2] = mask[-2:] = mask[:, :2] = mask[:, -2:] = True  # a frame two pixels wide
    mask[0, 45:50] = mask[-1, 45:50] = mask[45:50, 0] = mask[45:50, -1] = False  # gaps in its outer lines
    mask[40:60, 40:60] = True  # the figure, 400 px
    assert without_frame(mask).sum() == 400  # lines 95% figure are a frame's
    # Lines must be 99% figure: none is cleared, and the frame goes as a part covering little.
    assert without_frame(mask, FigureTuning(frame_line=0.99)).sum() == 400
    assert without_frame(mask, FigureTuning(frame_line=0.99, frame_fill=0.0)).sum() == mask.sum()
    mask[2:40, 50] = True  # the figure touches the frame: its lines must go for the figure to stay
    assert without_frame(mask).sum() == 438
    assert without_frame(mask, FigureTuning(frame_depth=0.01)).sum() > 438  # one line deep: half a frame kept


def test_suggested_rectangles_lie_within_the_size_range_and_twice_the_thickness_within_reach():
    bar = np.zeros((40, 120), bool)
    bar[14:26, 0:110] = True  # 12 px thick
    at = np.array([[54.0, 19.5], [54.0, 15.0]])  # its middle, and a pixel and a half in from its edge

    def sides(**given):
        return rectangle_sizes(bar, at, FigureTuning(**given))[:, 0].tolist()

    assert sides() == [12.0, 10.0]  # within 3 px of the edge point, the figure is 5 px from its outline
    assert sides(size_low=16) == [16.0, 16.0] and sides(size_high=10) == [10.0, 10.0]
    assert sides(thickness_reach=0) == [12.0, 8.0] and sides(thickness_reach=10) == [12.0, 12.0]


def test_the_size_range_doubles_beyond_frame_side():
    assert size_scale((1280, 960)) == 2.0 and size_scale((1280, 960), FigureTuning(frame_side=2000)) == 1.0
    frames = np.full((1, 40, 120, 3), 255, np.uint8)
    frames[0, 14:26, 10:110] = 0  # a bar 12 px thick on white paper
    at = np.array([[54.0, 19.5]])
    assert suggested_sizes(frames, at).tolist() == [[12.0, 12.0]]
    # On a frame twice as large as frame_side the range is 16-96 px.
    assert suggested_sizes(frames, at, tuning=FigureTuning(frame_side=60)).tolist() == [[16.0, 16.0]]


@pytest.mark.parametrize("given, message", [
    ({"threshold_low": 120}, "threshold_low must be at most threshold_high, got 120.0 > 100.0"),
    ({"size_low": 50}, "size_low must be at most size_high, got 50.0 > 48.0"),
    ({"size_low": 0}, "size_low must be a finite number > 0"),
    ({"threshold_low": -1}, "threshold_low must be a finite number >= 0"),
    ({"clean_fraction": 2}, "clean_fraction must be a finite number from 0 to 1, got 2.0"),
    ({"frame_side": 0.5}, "frame_side must be a finite number >= 1, got 0.5"),
    ({"thickness_reach": -1}, "thickness_reach must be a whole number >= 0, got -1"),
    ({"thickness_reach": 1.5}, "thickness_reach must be a whole number >= 0"),
])
def test_bad_values_are_refused_in_one_line(given, message):
    with pytest.raises(TrackingError) as caught:
        FigureTuning(**given)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_track_settings_refuse_a_figure_tuning_of_another_kind():
    with pytest.raises(TrackingError, match="cutout must be a FigureTuning, got MatchTuning"):
        from toonmotion.capture.match_tuning import MatchTuning
        TrackSettings(cutout=MatchTuning())


def test_every_value_is_documented_with_its_unit_or_range_and_its_measurement():
    entries = documented(FigureTuning)
    assert set(entries) == set(FigureTuning.__dataclass_fields__)
    for name, entry in entries.items():
        assert any(word in entry for word in ("0 to 1", "Pixels", "Colour distance", "Of the")), (name, entry)
        measured = ("->", " px", "No measurement on record", "No measurement of", "see ``")
        assert any(word in entry for word in measured), name
