"""Shared fixtures: paths to the real drawings and motion clips in ../shared/data.

Tests that need them skip when the folder is absent, except under CI=true, where a missing
folder is a failure (CI always has it beside the clone).
"""

import os
from pathlib import Path

import pytest

SHARED_DATA = Path(
    os.environ.get("TOONMOTION_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
DRAWINGS_DIR = SHARED_DATA / "drawings"


def _require(path):
    if not path.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"shared data missing under CI: {path}")
        pytest.skip(f"shared data not found at {path}")
    return path


def drawing_names():
    """Names of the shared drawings (empty when the data is absent)."""
    if not DRAWINGS_DIR.is_dir():
        return ["<missing>"]
    return sorted(p.name for p in DRAWINGS_DIR.iterdir() if (p / "texture.png").is_file())


@pytest.fixture(params=drawing_names())
def drawing_dir(request):
    """Each shared drawing's folder: texture.png, mask.png, char_cfg.yaml."""
    return _require(DRAWINGS_DIR) / request.param


@pytest.fixture
def drawings_root():
    return _require(DRAWINGS_DIR)
