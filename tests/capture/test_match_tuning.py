"""Tests for toonmotion.capture.match_tuning: the matching core's tuning as settings.

The defaults are the tracker's (the suite's other tracking tests run with them, and the turns
they derive are the constants they replace, to the bit); here each value given changes what the
matching does as its documentation says, on small scenes of ``tests/capture/test_template_match.py``
and ``tests/capture/test_tracker.py``, and bad values are refused in one line.
"""

import math
import re

import cv2
import numpy as np
import pytest

from tests.capture.test_template_match import SIDE, _patch, _scene
from tests.capture.test_tracker import _errors, _leaning_flat_body, _setup
from toonmotion.capture import template_match
from toonmotion.capture.coarse_search import locate
from toonmotion.capture.joint_plan import Templates, plan_joint
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.patches import confidence, distinct_size, is_textured, sample, ssd_at
from toonmotion.capture.template_context import Pyramid, cut_context, place_by_context
from toonmotion.capture.template_match import _Cells, match
from toonmotion.capture.track_gaps import fill_hidden_spans
from toonmotion.capture.track_settings import TrackSettings
from toonmotion.capture.tracker import _plans, track
from toonmotion.errors import TrackingError


def _plan(radius=18.0, parent=0, **given):
    """A plan for a ``SIDE`` square with the tuning ``given``; ``parent`` -1: it does not turn."""
    return plan_joint((SIDE, SIDE), radius, 1 / 255**2, 1 / radius**2, parent=parent, hangs_from=parent,
                      tuning=MatchTuning(**given))


def _turned(image, degrees, centre=(60, 50)):
    """``image`` turned ``degrees`` about ``centre``: a rectangle there is found turned by ``degrees``."""
    h, w = image.shape[:2]
    turn = cv2.getRotationMatrix2D(centre, -degrees, 1.0)
    return cv2.warpAffine(image, turn, (w, h), borderValue=(128, 128, 128))


@pytest.fixture(scope="module")
def patch_scene():
    """One textured square at (60, 50) on grey, and its templates."""
    image = np.full((100, 120, 3), 128, np.uint8)
    half = SIDE // 2
    image[50 - half:50 + half + 1, 60 - half:60 + half + 1] = _patch(np.random.default_rng(7))
    return image, Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))


def test_the_defaults_are_the_constants_they_replace_and_the_settings_carry_them():
    tuning = MatchTuning()
    assert (tuning.update_confidence, tuning.visible_confidence, tuning.others, tuning.context_side) == (
        0.8, 0.25, 4, 48)
    # The turns, derived from steps and counts in degrees, are the old tuples to the last bit.
    assert tuning.turns == tuple(math.radians(sign * step) for step in (5, 10, 15) for sign in (1, -1))
    assert tuning.spin_turns == tuple(math.radians(step) for step in range(0, 360, 20))
    assert tuning.coarse_turns == (0.0, math.radians(25), math.radians(-25))
    assert tuning.context_turns == tuple(math.radians(turn) for turn in (0, 10, -10, 20, -20))
    assert TrackSettings().match == tuning
    mine, at = MatchTuning(others=2), np.array([[30.0, 30.0]])
    frame = np.zeros((60, 60, 3), np.uint8)
    plans = _plans(_setup([("dot", None)], at), TrackSettings(match=mine), frame, at)
    assert plans.tuning is mine and plans(0).tuning is mine and plans(0, 2.0).tuning is mine


def test_confidence_is_read_on_confidence_scale():
    ssd = 20.0**2 * 3 * 4  # 20 grey levels off in every channel of a 2 x 2 patch
    assert round(confidence(ssd, (2, 2)), 2) == 0.8
    wide = MatchTuning(confidence_scale=60.0)
    assert confidence(ssd, (2, 2), wide) == pytest.approx(math.exp(-400 / 7200))
    assert ssd_at(confidence(ssd, (2, 2), wide), (2, 2), wide) == pytest.approx(ssd)
    assert _plan(confidence_scale=60.0).plain == pytest.approx(4 * _plan().plain)


def test_only_places_at_least_update_confidence_are_plain_and_the_prediction_chooses_among_them():
    """Two copies of the joint's texture, one 16 grey levels off at the prediction (0.87), one 6
    off 27 px away (0.98): both plain, the prediction takes the near one; at a bar of 0.9 only the
    far one is plain, and is taken."""
    image = _scene()
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    later = image.astype(int)
    later[:, :75] += 16
    later[:, 75:] += 6
    later = np.clip(later, 0, 255).astype(np.uint8)
    predicted = np.array([63.0, 50.0])
    near = match(later, templates, predicted, 0.0, _plan(32.0, parent=-1))
    far = match(later, templates, predicted, 0.0, _plan(32.0, parent=-1, update_confidence=0.9))
    assert np.hypot(*(near.xy - (60, 50))) < 0.1 and np.hypot(*(far.xy - (90, 50))) < 0.1


def test_the_other_places_kept_are_others_at_most_other_spacing_apart_and_visibly_confident():
    """A colour-cost map with the match and two other minima 3 cells apart: both are kept, the
    best first; counted over 3 cells round, the weaker is not the least there; at most ``others``;
    none less confident than ``visible_confidence``."""
    ssd = np.full((17, 17), 1e6, np.float32)
    ssd[8, 8], ssd[2, 2], ssd[2, 5] = 0.0, 1000.0, 2000.0

    def kept(**given):
        joint = plan_joint((4, 4), 8, 1 / 255**2, 1 / 64, -1, -1, tuning=MatchTuning(**given))
        return _Cells(ssd, np.ones_like(ssd, bool), (8, 8), joint).others()[:, :2].tolist()

    assert kept() == [[-6.0, -6.0], [-3.0, -6.0]]
    assert kept(other_spacing=3) == [[-6.0, -6.0]]
    assert kept(others=1) == [[-6.0, -6.0]] and kept(others=0) == []
    assert kept(visible_confidence=0.999) == []


def test_a_joint_less_confident_than_visible_confidence_is_hidden_and_its_span_re_placed():
    P = np.array([[[0.0, 0.0]], [[9.0, 9.0]], [[9.0, 9.0]], [[3.0, 0.0]]])
    C = np.array([[1.0], [0.3], [0.3], [1.0]])
    args = (np.array([-1]), np.ones(4, bool), np.zeros(4, bool))
    assert fill_hidden_spans(P, C, *args)[1:3, 0].tolist() == [[9.0, 9.0], [9.0, 9.0]]  # 0.3: found
    hidden = fill_hidden_spans(P, C, *args, match=MatchTuning(visible_confidence=0.5))
    assert hidden[1:3, 0].tolist() == [[7.0, 6.0], [5.0, 3.0]]


def test_the_anchors_and_the_latests_matches_agree_within_drift_tolerance(patch_scene):
    """The latest template cut 3 px right of the anchor; in a noisy frame (both below the plain
    bar) their matches lie 3 px apart."""
    image, templates = patch_scene
    drifted = Templates(templates.anchor, sample(image, np.array([63.0, 50.0]), 0.0, (SIDE, SIDE)),
                        templates.coarse)
    noisy = np.clip(image + np.random.default_rng(1).normal(0, 25, image.shape), 0, 255).astype(np.uint8)
    apart = match(noisy, drifted, np.array([61.0, 50.0]), 0.0, _plan(parent=-1))
    together = match(noisy, drifted, np.array([61.0, 50.0]), 0.0, _plan(parent=-1, drift_tolerance=4.0))
    assert apart.confidence < MatchTuning().update_confidence
    assert not apart.agree and together.agree and np.hypot(*(together.xy - (60, 50))) < 0.5


def test_an_anchor_within_alike_level_is_found_as_cut_however_far_from_the_prediction():
    """The texture as cut 16 px from the prediction and 8 grey levels off 14 px from it: found as
    cut, the first is taken; with alike_level above 8 both are, and the prediction chooses."""
    image = _scene()
    image[:, 75:] = np.clip(image[:, 75:].astype(int) + 8, 0, 255).astype(np.uint8)
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    predicted = np.array([76.0, 50.0])
    assert np.allclose(match(image, templates, predicted, 0.0, _plan()).xy, (60, 50), atol=0.05)
    assert np.hypot(*(match(image, templates, predicted, 0.0, _plan(alike_level=10.0)).xy - (90, 50))) < 0.1


def test_a_flat_anchor_found_as_cut_at_more_than_exact_cells_leaves_the_choice_to_the_prediction():
    image = np.full((100, 200, 3), (200, 120, 60), np.uint8)
    image[:, 75:] += 8  # as cut only left of x 75, 35 px and more from the prediction
    templates = Templates.cut(image, np.array([30.0, 50.0]), 0.0, (SIDE, SIDE))
    predicted = np.array([100.0, 50.0])
    assert np.allclose(match(image, templates, predicted, 0.0, _plan(40.0)).xy, (100, 50), atol=0.05)
    anywhere = match(image, templates, predicted, 0.0, _plan(40.0, exact_cells=100_000))
    assert anywhere.xy[0] < 75 and anywhere.confidence == 1.0


def test_a_rectangle_matching_below_turn_confidence_tries_the_turns_of_turn_step_and_turn_count(patch_scene):
    image, templates = patch_scene
    turned = _turned(image, 15)

    def found(**given):
        f = match(turned, templates, np.array([60.0, 50.0]), 0.0, _plan(**given))
        return round(math.degrees(f.angle), 6), f.confidence

    assert found()[0] == 15.0 and found()[1] > 0.95
    assert found(turn_count=2)[0] == 10.0 and found(turn_count=2)[1] < 0.8  # +-5, +-10 only
    assert found(turn_step=7.5, turn_count=2)[0] == 15.0
    assert found(turn_confidence=0.0) == (0.0, pytest.approx(0.27, abs=0.01))  # never tries them


def test_fine_turns_of_the_ranked_turns_are_matched_finely(patch_scene, monkeypatch):
    image, templates = patch_scene
    fine = template_match._match_turned
    calls = []
    monkeypatch.setattr(template_match, "_match_turned", lambda *a, **k: calls.append(1) or fine(*a, **k))
    for count in (1, 2, 6):
        calls.clear()
        # A bar no match reaches: every one of the fine_turns best turns is tried.
        match(_turned(image, 15), templates, np.array([60.0, 50.0]), 0.0,
              _plan(fine_turns=count, turn_confidence=1.0))
        assert len(calls) == 1 + count


def test_a_hidden_joint_is_looked_for_coarsely_at_the_coarse_turns(patch_scene):
    image, templates = patch_scene
    small = cv2.pyrDown(_turned(image, 50))
    start = np.array([62.0, 49.0])
    _, few, angle = locate(small, templates, start, 0.0, _plan(), 18.0)  # 0 and +-25
    _, more, wider = locate(small, templates, start, 0.0, _plan(coarse_turn_count=2), 18.0)
    _, none, alone = locate(small, templates, start, 0.0, _plan(coarse_turn_count=0), 18.0)
    assert round(math.degrees(angle)) == 25 and round(math.degrees(wider)) == 50 and alone == 0.0
    assert none < few < 0.5 < more


def test_a_rectangle_seen_end_on_is_looked_for_all_round_spin_step_apart(patch_scene):
    image, templates = patch_scene
    small = cv2.pyrDown(_turned(image, 150))
    start = np.array([62.0, 49.0])
    assert len(MatchTuning().spin_turns) == 18 and len(MatchTuning(spin_step=30.0).spin_turns) == 12
    _, near, angle = locate(small, templates, start, 0.0, _plan(), 18.0, turns=MatchTuning().spin_turns)
    _, exact, on = locate(small, templates, start, 0.0, _plan(), 18.0,
                          turns=MatchTuning(spin_step=30.0).spin_turns)
    assert round(math.degrees(angle)) in (140, 160) and round(math.degrees(on)) == 150 and near < exact


def test_templates_grow_while_not_distinct_up_to_max_growth():
    """distinct_size's doctest scene: on a straight edge a template is never distinct and grows as
    far as it may; at a corner it is distinct at once, unless every way must change alike."""
    image = np.full((80, 80, 3), 200, np.uint8)
    image[:, 40:] = 40
    image[60:, :] = 120
    on_edge, at_corner = np.array([40.0, 40.0]), np.array([40.0, 60.0])

    def sizes(**given):
        tuning = MatchTuning(**given)
        return tuple(distinct_size(image, at, (12, 12), tuning)[0] for at in (on_edge, at_corner))

    assert sizes() == (36, 12)
    assert sizes(max_growth=2.0) == (24, 12) and sizes(max_growth=1.0) == (12, 12)
    assert sizes(distinct_ratio=1.0) == (36, 36)  # a corner changes more one way than another
    assert sizes(distinct_ratio=0.0, distinct_level=0.0) == (12, 12)  # nothing is too alike


def test_a_faint_texture_is_distinct_only_above_distinct_level():
    faint = (128 + np.random.default_rng(1).integers(0, 2, (80, 80, 1))).repeat(3, axis=2).astype(np.uint8)
    centre = np.array([40.0, 40.0])  # moved, it changes by 0.7 grey levels RMS
    assert distinct_size(faint, centre, (12, 12)) == (36, 36)
    assert distinct_size(faint, centre, (12, 12), MatchTuning(distinct_level=0.5)) == (12, 12)


def test_a_checkerboard_looks_like_itself_moved_by_a_distinct_shift_of_two():
    checker = (np.indices((80, 80)).sum(axis=0) % 2 * 255).astype(np.uint8)[..., None].repeat(3, axis=2)
    one = MatchTuning(distinct_shift=1)
    assert not is_textured(checker[30:50, 30:50].astype(np.float32))
    assert is_textured(checker[30:50, 30:50].astype(np.float32), one)
    centre = np.array([40.0, 40.0])
    assert distinct_size(checker, centre, (12, 12), one) < distinct_size(checker, centre, (12, 12))


def test_a_template_is_textured_by_texture_level_and_textured_fraction():
    flat = np.full((20, 20, 3), 200, np.float32)
    flat[:, 9:12] = 20  # a fill and an outline: a few pixels change when moved
    noise = np.random.default_rng(0).uniform(0, 255, (20, 20, 3)).astype(np.float32)
    assert (is_textured(flat), is_textured(noise)) == (False, True)
    assert is_textured(flat, MatchTuning(textured_fraction=0.1))
    assert not is_textured(noise, MatchTuning(texture_level=255.0))


def test_the_context_is_context_growth_rectangles_wide_at_most_context_side_pixels_at_its_level():
    rng = np.random.default_rng(0)
    noise = cv2.GaussianBlur(rng.uniform(0, 255, (200, 200, 3)).astype(np.float32), (0, 0), 2)
    pyramid, centre = Pyramid(noise.astype(np.uint8)), np.array([100.0, 100.0])

    def cut(**given):
        context = cut_context(pyramid, centre, 0.0, (16, 16), MatchTuning(**given))
        return context.level, context.patch.shape[0]

    assert cut() == (0, 40)  # 2.5 x 16
    assert cut(context_growth=4.0) == (1, 32)  # 64 px, halved to be at most 48
    assert cut(context_side=32) == (1, 20)  # 40 px, halved to be at most 32


def test_the_context_is_matched_at_the_context_turns():
    """A disc leaning 20 degrees is placed by its context at turns of 10 and 20 either way, not at
    its angle alone or one turn of 10."""
    ground = np.full((200, 240, 3), 230, np.uint8)
    first, later = ground.copy(), ground.copy()
    cv2.ellipse(first, (100, 100), (60, 40), 0, 0, 360, (40, 90, 200), -1)
    cv2.ellipse(later, (104, 100), (60, 40), 20, 0, 360, (40, 90, 200), -1)

    def placed(**given):
        tuning = MatchTuning(**given)
        context = cut_context(Pyramid(first), np.array([100.0, 100.0]), 0.0, (16, 16), tuning)
        xy, sure = place_by_context(Pyramid(later), context, np.array([102.0, 100.0]), 0.0, 24.0, tuning)
        return np.hypot(*(xy - (104, 100))), sure

    assert placed()[0] < 0.5 and placed()[1] > 0.95
    assert placed(context_turn_count=0)[1] < 0.5 and placed(context_turn_count=1)[1] < 0.8
    assert placed(context_turn_step=20.0, context_turn_count=1) == placed()


def test_no_context_below_context_confidence_places_a_joint():
    """The two joints inside one flat body (tests/capture/test_tracker.py, placed by their wider
    view within 1 px on average): where no context is ever sure enough, they wander."""
    frames, truth = _leaning_flat_body()
    setup = _setup([("hip", None), ("chest", "hip")], truth[0], size=16)
    never = TrackSettings(match=MatchTuning(context_confidence=1.0))  # noisy frames never match at 1
    assert _errors(track(frames, setup, settings=never), truth).mean() > 10.0


@pytest.mark.parametrize("given, message", [
    ({"others": -1}, "others must be a whole number >= 0, got -1"),
    ({"turn_count": 0}, "turn_count must be a whole number >= 1, got 0"),
    ({"context_side": 2.5}, "context_side must be a whole number >= 1"),
    ({"distinct_shift": True}, "distinct_shift must be a whole number >= 1"),
    ({"update_confidence": 1.5}, "update_confidence must be a finite number from 0 to 1, got 1.5"),
    ({"visible_confidence": -0.1}, "visible_confidence must be a finite number from 0 to 1"),
    ({"confidence_scale": 0}, "confidence_scale must be a finite number > 0"),
    ({"turn_step": float("nan")}, "turn_step must be a finite number > 0"),
    ({"alike_level": -1}, "alike_level must be a finite number >= 0"),
    ({"max_growth": 0.5}, "max_growth must be a finite number >= 1, got 0.5"),
    ({"context_growth": "2"}, "context_growth must be a number >= 1, got '2'"),
])
def test_bad_values_are_refused_in_one_line(given, message):
    with pytest.raises(TrackingError) as caught:
        MatchTuning(**given)
    assert message in str(caught.value) and "\n" not in str(caught.value)


def test_track_settings_refuse_a_match_tuning_of_another_kind():
    with pytest.raises(TrackingError, match="match must be a MatchTuning, got dict"):
        TrackSettings(match={"others": 2})


def documented(kind):
    """``{field: its entry}`` of a tuning type's Attributes section."""
    attributes = kind.__doc__.split("Attributes\n    ----------\n", 1)[1].split("\n\n    Examples", 1)[0]
    found = re.findall(r"^    (\w+) : \w+\n((?:        .*\n?)+)", attributes, re.MULTILINE)
    return {name: " ".join(entry.split()) for name, entry in found}


def test_every_value_is_documented_with_its_unit_or_range_and_its_measurement():
    entries = documented(MatchTuning)
    assert set(entries) == set(MatchTuning.__dataclass_fields__)
    for name, entry in entries.items():
        assert any(word in entry for word in ("0 to 1", "Degrees", "Pixels", "Grey levels", "Cells", "Times",
                                              "How many")), (name, entry)
        # a measurement, or that none is on record (or where the one it shares is)
        assert any(word in entry for word in ("->", " px", "%", "No measurement on record", "see ``")), name
