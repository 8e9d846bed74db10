"""Lifting a rigged character's animation: its joints in its frames are the markers, its frames give
the volumes, in one library call that ``lift --project --keys`` and the editor's 3D panel share."""

import numpy as np
import pytest

from tests.conftest import run_cli
from tests.proxy3d.conftest import clip_path
from toonmotion import api
from toonmotion.errors import ProxyError
from toonmotion.io.bvh import load_bvh
from toonmotion.io.frames import lay_on
from toonmotion.io.pose_json import save_keyframes
from toonmotion.io.project import save_project
from toonmotion.io.proxy_json import load_proxy
from toonmotion.render.sequence import render_animation
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_rig

PRIOR = "cmu_16_07_jump.bvh"


@pytest.fixture(scope="module")
def hero():
    character = sample_rig(scale=0.25)
    keys = sample_keyframes(character.skeleton, fps=6.0)
    return character, keys, api.animate_character(character, keys)


@pytest.fixture(scope="module")
def lifted(hero):
    character, _, animation = hero
    return api.lift_animation(character, animation, load_bvh(clip_path(PRIOR)), view=(0.0, 0.0))


def test_lifting_an_animation_is_lifting_its_joints_in_its_frames(hero, lifted):
    character, _, animation = hero
    proxy, report = lifted
    motion = api.motion_in_frames(character, animation)
    frames = lay_on(np.stack(list(render_animation(character, animation))))
    expected, _ = api.lift_proxy(motion, load_bvh(clip_path(PRIOR)), view=(0.0, 0.0), frames=frames,
                                 size=(frames.shape[2], frames.shape[1]))
    assert np.array_equal(proxy.points, expected.points) and np.array_equal(proxy.radii, expected.radii)
    assert proxy.frame_count == len(animation.meshes)
    assert (proxy.camera.width, proxy.camera.height) == (frames.shape[2], frames.shape[1])
    # The points lie on the drawn joints, and the scene's frames are the same animation's.
    seen = proxy.camera.project(proxy.points)
    drawn = motion.positions[:, [motion.skeleton.names.index(n) for n in proxy.names]]
    assert np.abs(seen - drawn).max() < 0.5
    api.animation_frames(character, animation, proxy)  # refuses an animation the proxy was not lifted from


def test_an_animation_gives_its_own_frames(hero):
    character, _, animation = hero
    with pytest.raises(ProxyError, match="an animation gives its own frames"):
        api.lift_animation(character, animation, load_bvh(clip_path(PRIOR)), frames=np.zeros((1, 2, 2, 3)))


def test_the_lift_command_takes_a_project_and_its_keys(hero, lifted, tmp_path, capsys):
    character, keys, _ = hero
    save_project(tmp_path / "hero", character)
    save_keyframes(tmp_path / "keys.json", character.skeleton, keys)
    prior = str(clip_path(PRIOR))
    code = run_cli("lift", "--project", tmp_path / "hero", "--keys", tmp_path / "keys.json",
                   "--prior", prior, "--view", "0,0", "-o", tmp_path / "proxy.json")
    assert code == 0, capsys.readouterr().err
    assert np.allclose(load_proxy(tmp_path / "proxy.json").points, lifted[0].points, atol=1e-9)
    for given in (["--frames", str(tmp_path / "x.gif")], [str(tmp_path / "keys.json")], []):
        args = ["--project", tmp_path / "hero", "--keys", tmp_path / "keys.json"] if given else []
        capsys.readouterr()
        code = run_cli("lift", *given, *args, "--prior", prior, "-o", tmp_path / "again.json")
        said = capsys.readouterr().err.strip()
        assert code == 2 and ("give the drawn markers" in said or "--project gives its own" in said), said
        assert len(said.splitlines()) == 1
    assert not (tmp_path / "again.json").exists()
