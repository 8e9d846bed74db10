"""Fixtures the file-format tests share."""

import numpy as np
import pytest

from toonmotion.api import animate_character
from toonmotion.render.sequence import render_animation
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_rig


@pytest.fixture(scope="session")
def sample_frames():
    """Twelve distinct rendered frames of the sample character, 96x120: soft, partly transparent
    edges on a clear field."""
    hero = sample_rig()
    animation = animate_character(hero, sample_keyframes(hero.skeleton, fps=8.0))
    frames = list(render_animation(hero, animation, size=(96, 120)))[:12]
    assert len({f.tobytes() for f in frames}) == len(frames)
    alpha = np.stack(frames)[..., 3]
    assert ((alpha > 0) & (alpha < 255)).sum() > 1000  # plenty of partly transparent pixels
    return frames
