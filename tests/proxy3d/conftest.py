"""Shared pieces of the proxy3d tests: real CMU clips as priors (skipped without the shared data)."""

import pytest

from tests.conftest import SHARED_DATA, _require

MOCAP_DIR = SHARED_DATA / "mocap"


def clip_path(name):
    return _require(MOCAP_DIR) / name


@pytest.fixture(scope="session")
def walk_clip():
    from toonmotion.io.bvh import load_bvh

    return load_bvh(clip_path("cmu_07_01_walk.bvh"))


@pytest.fixture(scope="session")
def walk_prior(walk_clip):
    """The CMU walk's 16 standard joints (its T-pose frame left out), at 30 fps."""
    from toonmotion.capture.mocap import STANDARD_JOINTS
    from toonmotion.proxy3d.prior import prior_from_bvh, resample_prior

    return resample_prior(prior_from_bvh(walk_clip, STANDARD_JOINTS, start=1), 30)
