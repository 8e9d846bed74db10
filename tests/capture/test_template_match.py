"""Tests for toonmotion.capture.template_match: the kinematic term and the searches for a hidden
joint (coarse, round its parent)."""

import math

import cv2
import numpy as np

from toonmotion.capture.coarse_search import locate, search_round
from toonmotion.capture.joint_plan import BoneRule, Templates, plan_joint
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.search_tuning import SearchTuning
from toonmotion.capture.template_match import match

SIDE = 21


def _patch(rng, blur=2.0):
    """``(SIDE, SIDE, 3)`` float32 noise, smooth enough to keep its looks at half resolution."""
    noise = cv2.GaussianBlur(rng.uniform(0, 255, (SIDE, SIDE, 3)).astype(np.float32), (0, 0), blur)
    return np.clip((noise - noise.mean()) / noise.std() * 60 + 128, 0, 255).astype(np.float32)


def _scene(seed=0):
    """A plain grey picture with two copies of one textured patch, at (60, 50) and (90, 50)."""
    patch = _patch(np.random.default_rng(seed))
    image = np.full((100, 140, 3), 128, np.uint8)
    for x in (60, 90):
        image[50 - SIDE // 2:50 + SIDE // 2 + 1, x - SIDE // 2:x + SIDE // 2 + 1] = patch.astype(np.uint8)
    return image


def _plan(radius=18.0):
    return plan_joint((SIDE, SIDE), radius, 1 / 255**2, 1 / radius**2, parent=0, hangs_from=0)


def test_a_look_alike_at_the_wrong_bone_length_loses_to_the_joint():
    """Two identical patches equally far from the prediction: the colour and the prediction
    cannot tell them apart, the bone's length can."""
    image = _scene()
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    predicted = np.array([75.0, 50.0])  # midway
    joint = _plan()
    near = BoneRule(parent=np.array([20.0, 50.0]), length=40.0, weight=joint.w_beta)
    far = BoneRule(parent=np.array([20.0, 50.0]), length=70.0, weight=joint.w_beta)
    assert np.allclose(match(image, templates, predicted, 0.0, joint, near).xy, (60, 50), atol=0.05)
    assert np.allclose(match(image, templates, predicted, 0.0, joint, far).xy, (90, 50), atol=0.05)


def test_the_anchor_found_as_cut_beats_a_plain_place_nearer_the_prediction():
    """The joint's texture, as cut, 16 px from the prediction, and a copy 8 grey levels off (plain:
    conf 0.96) 14 px from it: the prediction decides among plain places, but not against the
    anchor found as it was cut."""
    image = _scene()
    image[:, 75:] = np.clip(image[:, 75:].astype(int) + 8, 0, 255).astype(np.uint8)  # the copy at x 90
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    joint = _plan()
    found = match(image, templates, np.array([76.0, 50.0]), 0.0, joint)
    assert np.allclose(found.xy, (60, 50), atol=0.05) and found.confidence > 0.99


def test_a_flat_anchor_found_as_cut_only_far_along_its_fill_stays_at_the_prediction():
    """A flat fill is found as cut all along a stretch, which tells nothing of where the joint is:
    with the fill shaded 8 grey levels lighter round the prediction, and as cut 35 px off within
    the window, the prediction still chooses."""
    image = np.full((100, 200, 3), (200, 120, 60), np.uint8)
    image[:, 75:] += 8
    templates = Templates.cut(image, np.array([30.0, 50.0]), 0.0, (SIDE, SIDE))
    joint = _plan(radius=40.0)
    found = match(image, templates, np.array([100.0, 50.0]), 0.0, joint)
    assert np.allclose(found.xy, (100, 50), atol=0.05) and 0.8 < found.confidence < 0.99


def test_nothing_is_taken_beyond_the_bones_reach():
    image = _scene()
    templates = Templates.cut(image, np.array([90.0, 50.0]), 0.0, (SIDE, SIDE))
    joint = _plan()
    short = BoneRule(parent=np.array([20.0, 50.0]), length=70.0, weight=joint.w_beta, longest=45.0)
    found = match(image, templates, np.array([75.0, 50.0]), 0.0, joint, short)
    xy, confidence = found.xy, found.confidence
    assert np.hypot(*(xy - (20, 50))) <= 45.0 + 1.0  # the copy within reach, not the template's own place
    assert np.allclose(xy, (60, 50), atol=0.05) and confidence > 0.9


def test_a_hidden_joint_is_found_round_its_parent_turned_with_its_bone():
    """A patch 40 px from its parent, cut pointing right, is found after its bone turned 130
    degrees, far from where it was; the coarse search gives the place to within a few pixels
    and the angle its bone has there."""
    patch = _patch(np.random.default_rng(3))
    parent = np.array([70.0, 60.0])

    def picture(theta):
        image = np.full((120, 140, 3), 128, np.float32)
        centre = parent + 40 * np.array([math.cos(theta), math.sin(theta)])
        c, s = math.cos(theta), math.sin(theta)
        h = (SIDE - 1) / 2
        M = np.array([[c, -s, centre[0] - c * h + s * h], [s, c, centre[1] - s * h - c * h]])
        warped = cv2.warpAffine(patch, M, (140, 120), flags=cv2.INTER_LINEAR, borderValue=(128, 128, 128))
        cover = np.ones((SIDE, SIDE), np.float32)
        mask = cv2.warpAffine(cover, M, (140, 120), flags=cv2.INTER_LINEAR)[..., None]
        return np.clip(image * (1 - mask) + warped * mask, 0, 255).astype(np.uint8), centre

    first, start = picture(0.0)
    templates = Templates.cut(first, start, 0.0, (SIDE, SIDE))
    later, truth = picture(math.radians(130))
    joint = _plan()
    bone = BoneRule(parent=parent, length=40.0, weight=joint.w_beta, longest=48.0)
    places = search_round(cv2.pyrDown(later), templates, joint, bone, 0.0, math.pi, 0.0)
    assert len(places) == 2  # the best two, a rectangle apart
    (xy, coarse, angle), *_ = places
    assert np.hypot(*(xy - truth)) < SIDE / 4 and abs(angle - math.radians(130)) < math.radians(15)
    found = match(later, templates, xy, angle, joint, bone)
    assert np.hypot(*(found.xy - truth)) < 0.5 and found.confidence > 0.8
    # Only where the bone reaches: a span of 60 degrees from where it was does not get there.
    assert all(np.hypot(*(p - truth)) > SIDE for p, _, _ in
               search_round(cv2.pyrDown(later), templates, joint, bone, 0.0, math.radians(60), 0.0))


def test_a_joint_whose_bone_grew_while_it_hid_is_looked_for_where_it_shows():
    """A textured foot hidden while its shin swung out of foreshortening: its bone was 40 px when
    last seen and the foot shows 70 px from the knee. The places round the knee are picked where
    the foot's look is (a rectangle apart), and only ordered by the bone's last length: picked by
    that length (as a flat-coloured joint's are), the grid's best place near the foot is one 30 px
    nearer the knee, and the foot is never looked for where it shows."""
    patch = _patch(np.random.default_rng(6)).astype(np.uint8)
    image = np.full((120, 160, 3), 128, np.uint8)
    image[60 - SIDE // 2:60 + SIDE // 2 + 1, 100 - SIDE // 2:100 + SIDE // 2 + 1] = patch
    templates = Templates.cut(image, np.array([100.0, 60.0]), 0.0, (SIDE, SIDE))
    joint = _plan()
    bone = BoneRule(parent=np.array([30.0, 60.0]), length=40.0, weight=joint.w_beta, longest=80.0)
    places = search_round(cv2.pyrDown(image), templates, joint, bone, 0.0, math.pi, 0.0, by_look=True)
    assert min(np.hypot(*(xy - (100, 60))) for xy, _, _ in places) < SIDE / 4
    by_length = search_round(cv2.pyrDown(image), templates, joint, bone, 0.0, math.pi, 0.0)
    assert min(np.hypot(*(xy - (100, 60))) for xy, _, _ in by_length) > SIDE
    # As the tracker does: the places are matched finely in order until one is found again.
    found = next(f for f in (match(image, templates, xy, angle, joint, bone) for xy, _, angle in places)
                 if f.confidence >= SearchTuning().reacquire_confidence)
    assert np.hypot(*(found.xy - (100, 60))) < 0.5 and found.confidence > 0.8


def test_the_coarse_search_finds_a_joint_far_outside_the_fine_window():
    image = _scene()
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    xy, confidence, angle = locate(cv2.pyrDown(image), templates, np.array([30.0, 40.0]), 0.0, _plan(), 40.0)
    assert np.hypot(*(xy - (60, 50))) <= 2.0 and confidence > 0.5 and angle == 0.0


def test_a_search_round_a_long_bone_with_many_places_is_made_in_batches():
    """Thousands of places, stacked taller than OpenCV's remap takes in one call (32767 rows)."""
    image = np.full((900, 900, 3), 128, np.uint8)
    image[440:461, 740:761] = _patch(np.random.default_rng(4)).astype(np.uint8)
    templates = Templates.cut(image, np.array([750.0, 450.0]), 0.0, (SIDE, SIDE))
    joint = _plan()
    bone = BoneRule(parent=np.array([450.0, 450.0]), length=300.0, weight=joint.w_beta, longest=400.0)
    places = search_round(cv2.pyrDown(image), templates, joint, bone, 0.0, math.pi, 0.0)
    assert len(places) == 2 and np.hypot(*(places[0][0] - (750, 450))) < SIDE / 4


def test_the_coarse_search_all_round_finds_a_patch_turned_half_round():
    """A bone seen end-on gives its rectangle no angle: the search at MatchTuning.spin_turns finds the patch
    turned 160 deg, and its angle, where the usual few turns do not."""
    patch = _patch(np.random.default_rng(5))
    image = np.full((100, 140, 3), 128, np.uint8)
    image[50 - SIDE // 2:50 + SIDE // 2 + 1, 60 - SIDE // 2:60 + SIDE // 2 + 1] = patch.astype(np.uint8)
    templates = Templates.cut(image, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE))
    turned = cv2.warpAffine(image, cv2.getRotationMatrix2D((60, 50), -160, 1.0), (140, 100),
                            borderValue=(128, 128, 128))
    small, start = cv2.pyrDown(turned), np.array([62.0, 49.0])
    _, few, _ = locate(small, templates, start, 0.0, _plan(), 18.0)
    all_round = MatchTuning().spin_turns
    xy, confidence, angle = locate(small, templates, start, 0.0, _plan(), 18.0, turns=all_round)
    assert few < 0.5 < confidence and np.hypot(*(xy - (60, 50))) <= 2.0
    assert math.degrees(angle) % 360 == 160.0


def test_the_places_alike_to_a_match_span_a_flat_fill_and_not_a_texture():
    """Along a flat band every place matches as well as any other: the alike places run the
    search's length along it, and stay within a pixel of the band's middle across it. On a
    texture they are the match's own cell or its neighbours."""
    image = np.full((100, 140, 3), 235, np.uint8)
    image[40:61] = (200, 120, 60)  # a band 21 px high, across the picture
    image[38:40] = image[61:63] = 40  # its outline
    joint = _plan(radius=12.0)
    centre = np.array([70.0, 50.0])
    band = match(image, Templates.cut(image, centre, 0.0, (SIDE, SIDE)), centre + (3, 2), 0.0, joint).alike
    assert np.ptp(band[:, 0]) == 2 * joint.radius and np.abs(band[:, 1] - 50).max() <= 1
    textured = _scene()
    spot = match(textured, Templates.cut(textured, np.array([60.0, 50.0]), 0.0, (SIDE, SIDE)),
                 np.array([62.0, 51.0]), 0.0, joint).alike
    assert np.hypot(*(spot - (60, 50)).T).max() <= 1.5
