"""A short run of benchmarks/track.py: real mocap rendered as a textured figure, tracked.

The rendering, tracking and scoring are ``toonmotion.testing.mocap_tracking``, which the benchmark
runs on every clip.
"""

import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require
from toonmotion.testing.mocap_tracking import render_bvh_clip, track_from_truth, tracking_scores

# The bar for the jumping-jacks clip: mean error at most 3 px.
MEAN_BAR_PX = 3.0
FRAMES = 40  # the jumping starts about frame 12


@pytest.fixture(scope="module")
def jumping_jacks():
    clip = _require(SHARED_DATA / "mocap") / "cmu_jumping_jacks.bvh"
    return render_bvh_clip(clip, frames=FRAMES)


def test_the_rendered_clip_is_what_the_tracker_is_scored_on(jumping_jacks):
    images, truth, skeleton = jumping_jacks.images, jumping_jacks.truth, jumping_jacks.skeleton
    assert images.shape == (FRAMES, 480, 640, 3)
    assert truth.shape == (FRAMES, 16, 2) and len(skeleton) == 16
    assert 20 < jumping_jacks.side < 40 and jumping_jacks.fps == pytest.approx(30, abs=0.1)
    assert (truth >= 0).all() and (truth[..., 0] < 640).all() and (truth[..., 1] < 480).all()


def test_tracking_jumping_jacks_is_accurate(jumping_jacks):
    found, _ = track_from_truth(jumping_jacks)
    figures = tracking_scores(found, jumping_jacks.truth)
    print(figures)
    assert figures["mean_px"] <= MEAN_BAR_PX
    assert np.isfinite(found).all()
