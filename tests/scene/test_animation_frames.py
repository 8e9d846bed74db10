"""A rigged character's animation as the frames of a scene: each figure pixel's depth follows the
proxy limb of the bone it moves with, and an animation the proxy was not lifted from is refused."""

import numpy as np
import pytest

from tests.conftest import run_cli
from toonmotion.api import animate_character, animation_frames, motion_in_frames
from toonmotion.errors import SceneError
from toonmotion.io.pose_json import save_keyframes
from toonmotion.io.project import save_project
from toonmotion.io.proxy_json import save_proxy
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.render.sequence import render_animation
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_rig

DEPTH = 6.0  # metres: the drawing seen flat, every marker this far from the camera


@pytest.fixture(scope="module")
def hero():
    character = sample_rig(scale=0.25)
    keys = sample_keyframes(character.skeleton, fps=12.0)
    return character, keys, animate_character(character, keys)


def flat_proxy(character, animation, size):
    """A proxy whose markers are the animation's joints in its frames, every one at ``DEPTH``."""
    seen = motion_in_frames(character, animation, size=size)
    T = seen.frame_count
    camera = PerspectiveCamera(500.0, *size, [[0, 0, 0, 0, 0, 0]] * T)
    names = seen.skeleton.names
    points = camera.at(seen.positions, np.full(seen.positions.shape[:2], DEPTH))
    parents = np.asarray(seen.skeleton.parents)
    K = int((parents >= 0).sum())
    turns = np.tile([0.0, 0, 0, 1], (T, K, 1))
    return Proxy(names, parents, seen.fps, camera, points, None, points, np.zeros((K, 3)), turns)


def test_frames_are_the_rendered_animation_and_labels_name_the_bone_s_limb(hero):
    character, _, animation = hero
    size = (120, 150)
    proxy = flat_proxy(character, animation, size)
    frames, limbs = animation_frames(character, animation, proxy)
    expected = np.stack(list(render_animation(character, animation, size=size)))
    assert np.array_equal(frames, expected)
    assert limbs.shape == frames.shape[:3]
    on_figure = frames[..., 3] > 0
    assert (limbs[~on_figure] == -1).all()
    assert (limbs[on_figure] >= 0).mean() > 0.95  # the root's bone has no limb in the proxy
    # Each labelled pixel lies nearer its own limb's segment than the typical figure's half-width.
    pixels = proxy.camera.project(proxy.points)
    t = len(frames) // 2
    rows, cols = np.nonzero(limbs[t] >= 0)
    k = limbs[t][rows, cols]
    a, b = pixels[t, proxy.limbs[k, 0]], pixels[t, proxy.limbs[k, 1]]
    ab = b - a
    s = np.clip(((np.stack([cols, rows], 1) - a) * ab).sum(1) / np.maximum((ab * ab).sum(1), 1e-9), 0, 1)
    gap = np.linalg.norm(a + s[:, None] * ab - np.stack([cols, rows], 1), axis=1)
    assert np.median(gap) < 0.15 * max(size)


def test_an_animation_the_proxy_was_not_lifted_from_is_refused(hero):
    character, _, animation = hero
    proxy = flat_proxy(character, animation, (120, 150))
    other = flat_proxy(character, animation, (100, 150))  # the same joints at another size
    moved = Proxy(proxy.names, proxy.parents, proxy.fps, proxy.camera, other.points, None, other.points,
                  proxy.rest, proxy.limb_rotations)
    with pytest.raises(SceneError, match="px from the proxy's markers"):
        animation_frames(character, animation, moved)


def test_the_scene_command_takes_a_project_and_its_keys(hero, tmp_path, capsys):
    character, keys, animation = hero
    save_project(tmp_path / "hero", character)
    save_keyframes(tmp_path / "keys.json", character.skeleton, keys)
    size = (120, 150)
    save_proxy(tmp_path / "proxy.json", flat_proxy(character, animation, size))
    out = tmp_path / "out"
    assert run_cli("scene", tmp_path / "proxy.json", "--project", tmp_path / "hero", "--keys",
                   tmp_path / "keys.json", "--balls", "right_foot", "-o", out) == 0
    assert "over 37 frames" in capsys.readouterr().out
    assert len(list(out.glob("*.png"))) == 37
    assert run_cli("scene", tmp_path / "proxy.json", "--project", tmp_path / "hero", "-o", out) == 2
    assert "--project, --keys" in capsys.readouterr().err
