"""A short run of benchmarks/track.py: real mocap rendered as a textured figure, tracked."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import SHARED_DATA, _require

# The bar for the jumping-jacks clip: mean error at most 3 px.
MEAN_BAR_PX = 3.0
FRAMES = 40  # the jumping starts about frame 12


def _harness():
    path = Path(__file__).resolve().parents[2] / "benchmarks" / "track.py"
    spec = importlib.util.spec_from_file_location("track_benchmark", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def jumping_jacks():
    clip = _require(SHARED_DATA / "mocap") / "cmu_jumping_jacks.bvh"
    harness = _harness()
    return harness, harness.rendered_clip(clip, frames=FRAMES)


def test_the_rendered_clip_is_what_the_tracker_is_scored_on(jumping_jacks):
    _, (images, truth, skeleton, side, fps) = jumping_jacks
    assert images.shape == (FRAMES, 480, 640, 3)
    assert truth.shape == (FRAMES, 16, 2) and len(skeleton) == 16
    assert 20 < side < 40 and fps == pytest.approx(30, abs=0.1)
    assert (truth >= 0).all() and (truth[..., 0] < 640).all() and (truth[..., 1] < 480).all()


def test_tracking_jumping_jacks_is_accurate(jumping_jacks):
    harness, (images, truth, skeleton, side, _) = jumping_jacks
    found, _ = harness.run_toonmotion(images, skeleton, side)
    figures = harness.scores(found, truth)
    print(figures)
    assert figures["mean_px"] <= MEAN_BAR_PX
    assert np.isfinite(found).all()
