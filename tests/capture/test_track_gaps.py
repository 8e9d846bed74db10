"""Tests for toonmotion.capture.track_gaps: hidden spans re-placed from both their ends."""

import numpy as np

from toonmotion.capture.track_gaps import fill_hidden_spans


def _turning_bone(T=12):
    """A still parent at (100, 100) and a child 50 px from it turning 10 degrees a frame."""
    angle = np.radians(10.0 * np.arange(T))
    child = 100 + 50 * np.column_stack([np.cos(angle), np.sin(angle)])
    return np.stack([np.full((T, 2), 100.0), child], axis=1)


def test_a_bone_turning_steadily_is_filled_exactly_and_found_frames_are_kept():
    truth = _turning_bone()
    P = truth.copy()
    C = np.ones((12, 2))
    P[3:8, 1] = (7.0, 7.0)  # guesses, far off
    C[3:8, 1] = 0.2
    filled = fill_hidden_spans(P, C, np.array([-1, 0]), np.ones(12, bool), np.zeros(12, bool))
    np.testing.assert_allclose(filled, truth, atol=1e-9)
    assert filled is not P and (P[3:8, 1] == 7.0).all()


def test_a_span_never_closed_keeps_its_guesses_and_held_frames_repeat_their_drawing():
    truth = _turning_bone()
    P, C = truth.copy(), np.ones((12, 2))
    P[8:, 1], C[8:, 1] = (7.0, 7.0), 0.2  # hidden to the end
    held = np.zeros(12, bool)
    held[[4, 5]] = True  # frames 4 and 5 repeat frame 3
    P[3:6, 1], C[3:6, 1] = (9.0, 9.0), 0.2  # hidden over the hold
    filled = fill_hidden_spans(P, C, np.array([-1, 0]), np.ones(12, bool), held)
    assert (filled[8:, 1] == 7.0).all()
    # The span is frames 3..5 between drawings 2 and 6: frame 3, a quarter of the way in time, turns a
    # quarter of the way (to 30 degrees); 4 and 5 repeat it.
    thirty = np.radians(30)
    np.testing.assert_allclose(filled[3, 1], 100 + 50 * np.array([np.cos(thirty), np.sin(thirty)]))
    np.testing.assert_array_equal(filled[4], filled[3])
    np.testing.assert_array_equal(filled[5], filled[3])


def test_a_root_hidden_is_bent_to_meet_where_it_is_found_again():
    P = np.array([[[0.0, 0.0]], [[2.0, 0.0]], [[4.0, 0.0]], [[6.0, 0.0]], [[12.0, 0.0]]])
    C = np.array([[1.0], [1.0], [0.1], [0.1], [1.0]])
    filled = fill_hidden_spans(P, C, np.array([-1]), np.ones(5, bool), np.zeros(5, bool))
    # The guesses went on at 2 px a frame; found at 12, not 8: the 4 px grow in over the span.
    np.testing.assert_allclose(filled[:, 0, 0], [0, 2, 4 + 4 / 3, 6 + 8 / 3, 12])


def test_a_root_hidden_between_children_found_throughout_is_put_where_they_hold_it():
    # A pelvis carried along a curve with its two hip joints, which show; it is hidden for frames
    # 3..9, guessed right until frame 7 and then drifting off (as a root carried by its children's
    # mean move drifts when one of them is lost). Bent to meet its found end, the late drift would
    # spread over the whole span; held by its hips, it is exact.
    T = 12
    path = np.column_stack([300 + 4.0 * np.arange(T), 200 + 0.5 * np.arange(T) ** 2])
    truth = np.stack([path, path + (-20.0, 10.0), path + (20.0, 10.0)], axis=1)
    P, C = truth.copy(), np.ones((T, 3))
    C[3:10, 0] = 0.2
    P[8:10, 0] += ((9.0, -12.0), (18.0, -24.0))
    filled = fill_hidden_spans(P, C, np.array([-1, 0, 0]), np.ones(T, bool), np.zeros(T, bool))
    np.testing.assert_allclose(filled, truth, atol=1e-9)
    # One hip hidden at a frame of the span: only the other holds the pelvis.
    C[5, 2] = 0.2
    filled = fill_hidden_spans(P, C, np.array([-1, 0, 0]), np.ones(T, bool), np.zeros(T, bool))
    np.testing.assert_allclose(filled[:, 0], truth[:, 0], atol=1e-9)
