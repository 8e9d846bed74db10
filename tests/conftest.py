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


def rig_character(folder=None):
    """The bundled sample (``folder`` None) or the shared drawing in ``folder``, rigged with its own
    mask and char_cfg skeleton."""
    from toonmotion.io.char_cfg import load_char_cfg
    from toonmotion.io.image import load_image, load_mask
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    if folder is None:
        rgba, skeleton = sample_character()
        return rig_drawing(rgba, skeleton=skeleton)
    texture = load_image(folder / "texture.png")
    size = (texture.shape[1], texture.shape[0])
    skeleton, cfg_size = load_char_cfg(folder / "char_cfg.yaml")
    assert cfg_size in (None, size)
    mask = load_mask(folder / "mask.png", size=size)
    return rig_drawing(texture, mask=mask, skeleton=skeleton)
