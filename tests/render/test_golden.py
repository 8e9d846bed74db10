"""Golden image: the bundled character, posed and rendered, against a stored picture.

Regenerate (after a deliberate change to rigging, deformation or rendering) with
``TOONMOTION_UPDATE_GOLDEN=1 pytest tests/render/test_golden.py``: that writes the picture and
skips the comparison, which does not pass against itself. Look at the new picture, then run the
test again without the variable before committing it.
"""

import os
from pathlib import Path

import numpy as np
import pytest

from toonmotion.deform.deformer import Deformer
from toonmotion.io.image import load_image, save_png
from toonmotion.render.frame import render_frame
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character

GOLDEN = Path(__file__).parent / "golden" / "sample_wave.png"
WAVE_FRAME = 24

# Library versions may round a few edge pixels differently; anything more is a regression.
MAX_CHANGED_FRACTION = 0.005  # pixels whose largest channel difference exceeds 8 levels
MAX_MEAN_DIFFERENCE = 0.5  # levels, over all pixels and channels


@pytest.fixture(scope="module")
def rendered():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    key = next(k for k in sample_keyframes(skeleton).keys if k.frame == WAVE_FRAME)
    U = Deformer(character).deform(key.pose).U
    return render_frame(character, U, pose=key.pose, size=(280, 400),
                        view=(-70.5, -100.5, 489.5, 699.5), background=(255, 255, 255),
                        overlays=("skeleton",))


def test_the_posed_sample_character_matches_its_golden_image(rendered):
    if os.environ.get("TOONMOTION_UPDATE_GOLDEN") == "1":
        save_png(GOLDEN, rendered)
        pytest.skip(f"golden image updated: {GOLDEN.name}; look at it, then rerun without the variable")
    golden = load_image(GOLDEN)
    assert golden.shape == rendered.shape
    difference = np.abs(golden.astype(int) - rendered.astype(int))
    changed = float((difference.max(axis=2) > 8).mean())
    assert changed <= MAX_CHANGED_FRACTION, f"{changed:.2%} of pixels changed"
    assert difference.mean() <= MAX_MEAN_DIFFERENCE


def test_the_golden_image_shows_the_figure(rendered):
    """Guard against a blank or wrong golden file: the figure covers a sensible share."""
    figure = (rendered[..., :3] < 250).any(axis=2)
    assert 0.15 < figure.mean() < 0.6
