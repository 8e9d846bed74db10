"""Time alignment by dynamic time warping (toonmotion.proxy3d.timewarp, paper 3.1.2)."""

import numpy as np
import pytest

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.descriptor import descriptor_features
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import camera
from toonmotion.proxy3d.prior import Prior, sample_frames
from toonmotion.proxy3d.timewarp import align_prior, band_limits, dtw, warp_prior


def _brute_force(A, B, lo, hi):
    """The textbook recurrence, cell by cell, within the same band."""
    n, m = len(A), len(B)
    D = np.full((n + 1, m + 1), np.inf)
    D[0, 0] = 0
    for i in range(n):
        for j in range(lo[i], hi[i] + 1):
            D[i + 1, j + 1] = ((A[i] - B[j]) ** 2).sum() + min(D[i, j], D[i, j + 1], D[i + 1, j])
    return D[n, m]


@pytest.mark.parametrize("n, m, band", [(7, 11, 0.3), (11, 7, 0.2), (20, 20, 0.1), (1, 5, 0.1), (5, 1, 0.1),
                                        (30, 45, 0.05), (13, 13, 1.0), (40, 25, 0.02)])
@pytest.mark.parametrize("method", ["dtaidistance", "numpy"])
def test_dtw_is_optimal_within_its_band(n, m, band, method):
    rng = np.random.default_rng(n * 100 + m)
    A, B = rng.normal(size=(n, 4)), rng.normal(size=(m, 4))
    lo, hi = band_limits(n, m, band)
    found = dtw(A, B, band=band, method=method)
    assert found.cost == pytest.approx(_brute_force(A, B, lo, hi), rel=1e-12)
    path = found.path
    assert path[0].tolist() == [0, 0] and path[-1].tolist() == [n - 1, m - 1]
    steps = np.diff(path, axis=0)
    assert {tuple(s) for s in steps.tolist()} <= {(1, 1), (1, 0), (0, 1)}
    assert np.all((path[:, 1] >= lo[path[:, 0]]) & (path[:, 1] <= hi[path[:, 0]]))


def test_both_implementations_find_the_same_path():
    rng = np.random.default_rng(3)
    A, B = np.cumsum(rng.normal(size=(300, 6)), 0), np.cumsum(rng.normal(size=(420, 6)), 0)
    ours, theirs = dtw(A, B, band=0.1, method="numpy"), dtw(A, B, band=0.1)
    assert np.array_equal(ours.path, theirs.path)
    assert ours.cost == pytest.approx(theirs.cost, rel=1e-12)


@pytest.mark.parametrize("method", ["dtaidistance", "numpy"])
def test_dtw_recovers_a_uniform_stretch_of_a_real_walk(walk_prior, method):
    """A 1.5x slowed copy of the CMU walk's descriptors maps back onto the walk within a frame."""
    limbs = walk_prior.limbs
    seen = walk_prior.positions @ camera(60, 10).T
    stretch = 1.5
    slow = sample_frames(seen, np.arange(int((len(seen) - 1) * stretch) + 1) / stretch)
    found = dtw(descriptor_features(slow, limbs), descriptor_features(seen, limbs), band=0.1, method=method)
    truth = np.arange(len(slow)) / stretch
    assert np.abs(found.frames - truth).max() <= 1.0
    slope = np.polyfit(np.arange(len(slow)), found.frames, 1)[0]
    assert 1 / slope == pytest.approx(stretch, rel=0.01)


def test_align_prior_end_to_end_on_a_stretched_drawing(walk_prior):
    """Drawn markers: the walk slowed 1.5x, seen from (30, 10), scaled and moved; prior: the walk."""
    R = camera(30, 10)
    times = np.arange(int((walk_prior.frame_count - 1) * 1.5) + 1) / 1.5
    drawn = Markers(walk_prior.names, 7 * sample_frames(walk_prior.positions, times) @ R.T + [300, 200],
                    fps=walk_prior.fps)
    found = align_prior(drawn, walk_prior, R)
    assert np.abs(found.frames - times).max() <= 1.0
    warped = warp_prior(walk_prior, found, drawn.fps)
    assert warped.frame_count == drawn.frame_count and warped.names == walk_prior.names
    truth = sample_frames(walk_prior.positions, times)
    step = np.linalg.norm(np.diff(walk_prior.positions, axis=0), axis=-1).max()
    assert np.linalg.norm(warped.positions - truth, axis=-1).max() <= step  # within a frame's motion


def test_a_prior_too_short_is_refused_in_one_line(walk_prior):
    drawn = Markers(walk_prior.names, walk_prior.positions @ camera(0, 0).T, fps=walk_prior.fps)
    short = Prior(walk_prior.names, walk_prior.parents, walk_prior.positions[:30], walk_prior.fps)
    with pytest.raises(ProxyError, match=r"the prior is too short to align: .* for 79 drawn frames; "
                                         r"give a prior at least 40 frames") as caught:
        align_prior(drawn, short, camera(0, 0))
    assert "\n" not in str(caught.value)
    one = Prior(walk_prior.names, walk_prior.parents, walk_prior.positions[:1], walk_prior.fps)
    with pytest.raises(ProxyError, match="too short"):
        align_prior(drawn, one, camera(0, 0))
    few = Markers(drawn.names, drawn.positions[:10], drawn.fps)
    with pytest.raises(ProxyError, match=r"too long to align: .* \(at most 20 frames\)$"):
        align_prior(few, walk_prior, camera(0, 0))
    # At another rate, the most it may be is said in the clip's own frames too (what --segment cuts).
    slower = Markers(drawn.names, drawn.positions[:10], drawn.fps / 2)
    with pytest.raises(ProxyError, match=rf"\(at most 20 frames, 40 of its own at {walk_prior.fps:g} fps\)$"):
        align_prior(slower, walk_prior, camera(0, 0))


def test_align_prior_needs_the_markers_names(walk_prior):
    drawn = Markers(walk_prior.names[:-1] + ("tail",), np.zeros((50, 16, 2)), fps=walk_prior.fps)
    with pytest.raises(ProxyError, match="lacks the markers tail"):
        align_prior(drawn, walk_prior, camera(0, 0))


def test_dtw_refuses_bad_input():
    with pytest.raises(ValueError, match="method must be one of"):
        dtw(np.zeros((3, 2)), np.zeros((3, 2)), method="fast")
    with pytest.raises(ProxyError, match="band must be"):
        dtw(np.zeros((3, 2)), np.zeros((3, 2)), band=0)
    with pytest.raises(ProxyError, match="non-finite"):
        dtw(np.full((3, 2), np.nan), np.zeros((3, 2)))
    with pytest.raises(ProxyError, match="differ in size"):
        dtw(np.zeros((3, 2)), np.zeros((3, 4)))
