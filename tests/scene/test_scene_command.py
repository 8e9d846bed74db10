"""``toonmotion scene``: a proxy file and its drawn frames in, a composited video or PNGs out; bad
input is one line and exit 2, with nothing overwritten."""

import numpy as np
import pytest

from tests.conftest import run_cli
from tests.scene.test_scene import H, W, figure_drawing, kicking
from toonmotion.io.frames import load_frames
from toonmotion.io.image import save_png
from toonmotion.io.proxy_json import save_proxy


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scene")
    proxy = kicking(T=8)
    save_proxy(folder / "proxy.json", proxy)
    frames = folder / "frames"
    frames.mkdir()
    for t in range(proxy.frame_count):
        save_png(frames / f"f_{t:03d}.png", figure_drawing(proxy, t))
    return folder, proxy


def test_balls_and_a_balloon_are_composited_into_every_frame(files, capsys):
    folder, proxy = files
    out = folder / "out"
    code = run_cli("scene", folder / "proxy.json", "--frames", folder / "frames", "--balloon", "m0",
                   "--balls", "m2", "--ball-count", "2", "--shading", "flat", "-o", out)
    assert code == 0
    assert "simulated 1 balloon and 2 balls over 8 frames" in capsys.readouterr().out
    made, _ = load_frames(out)
    drawn, _ = load_frames(folder / "frames")
    assert made.shape == drawn.shape == (8, H, W, 3)
    changed = np.any(made != drawn, axis=-1)
    assert changed.any(axis=(1, 2)).all()  # something of the scene is seen on every frame
    # Pixels the scene does not touch are the drawing's.
    assert np.array_equal(made[~changed], drawn[~changed])


def test_no_elements_writes_the_drawing_and_says_so(files, capsys):
    folder, _ = files
    out = folder / "same"
    assert run_cli("scene", folder / "proxy.json", "--frames", folder / "frames", "-o", out) == 0
    assert "no elements given" in capsys.readouterr().err
    assert np.array_equal(load_frames(out)[0], load_frames(folder / "frames")[0])


@pytest.mark.parametrize("argv, message", [
    (["--balloon", "wrist"], "'wrist', which the proxy lacks"),
    (["--balls", "m2", "--shading", "glossy"], "shading must be one of"),
    (["--balls", "m2", "--ball-radius", "-1"], "a ball's radius must be a positive"),
    (["--balls", "m2", "--background", "transparent"], "--background takes white, black or #rrggbb"),
    (["--balls", "m2", "--antialias", "5"], "--antialias"),
    (["--balls", "m2", "--antialias", "0"], "--antialias"),
])
def test_bad_input_is_one_line_exit_2_and_overwrites_nothing(files, capsys, argv, message):
    folder, _ = files
    out = folder / "kept.gif"
    out.write_bytes(b"earlier work")
    code = run_cli("scene", folder / "proxy.json", "--frames", folder / "frames", "-o", out, *argv)
    err = capsys.readouterr().err
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1
    assert out.read_bytes() == b"earlier work"


def test_frames_that_are_not_the_proxy_s_are_refused(files, tmp_path, capsys):
    folder, _ = files
    few = tmp_path / "few"
    few.mkdir()
    for t in range(3):
        save_png(few / f"f_{t}.png", np.full((H, W, 3), 255, np.uint8))
    out = tmp_path / "out.mp4"
    assert run_cli("scene", folder / "proxy.json", "--frames", few, "--balls", "m2", "-o", out) == 2
    assert "the drawing has 3 frames but the proxy 8" in capsys.readouterr().err
    assert not out.exists()


def test_passes_are_written_for_compositing_elsewhere(files, tmp_path):
    from PIL import Image

    from toonmotion.api import scene_passes, simulate_scene
    from toonmotion.scene.elements import Balls

    folder, proxy = files
    passes = tmp_path / "passes"
    assert run_cli("scene", folder / "proxy.json", "--frames", folder / "frames", "--balls", "m2",
                   "--ball-count", "1", "-o", tmp_path / "out.gif", "--passes", passes) == 0
    assert len(list(passes.glob("*.png"))) == 3 * proxy.frame_count
    expected = list(scene_passes(proxy, simulate_scene(proxy, [Balls("m2", count=1)])))
    for t, (beauty, depth, occlusion) in enumerate(expected):
        read = np.asarray(Image.open(passes / f"depth_{t:04d}.png"))
        assert np.array_equal(read, depth)  # 16 bits, millimetres
        assert np.array_equal(np.asarray(Image.open(passes / f"beauty_{t:04d}.png")), beauty)
        assert np.array_equal(np.asarray(Image.open(passes / f"occlusion_{t:04d}.png")), occlusion)
        assert np.array_equal(occlusion > 0, beauty[..., 3] > 0) and np.array_equal(occlusion > 0, depth > 0)
    assert any((o > 0).any() for _, _, o in expected)


def test_antialias_sets_the_rays_a_pixel_and_one_ray_gives_hard_edges(files, tmp_path):
    from toonmotion.api import composite_scene, simulate_scene
    from toonmotion.scene.elements import Balls

    folder, proxy = files
    drawn, _ = load_frames(folder / "frames")
    motion = simulate_scene(proxy, [Balls("m2", count=2)])
    for k in (1, 3):
        out = tmp_path / f"k{k}"
        assert run_cli("scene", folder / "proxy.json", "--frames", folder / "frames", "--balls", "m2",
                       "--ball-count", "2", "--antialias", str(k), "-o", out) == 0
        made, _ = load_frames(out)
        expected = np.stack(list(composite_scene(proxy, drawn, motion, antialias=k)))
        assert np.array_equal(made, expected)
    hard, soft = load_frames(tmp_path / "k1")[0], load_frames(tmp_path / "k3")[0]
    assert (hard != soft).any()  # the edges differ; the insides of the balls do not
    assert np.mean(np.any(hard != soft, axis=-1)) < 0.05


def test_a_scene_whose_balls_sink_deep_says_so_after_writing(tmp_path, capsys):
    proxy = kicking(T=8, speed=60.0)
    save_proxy(tmp_path / "proxy.json", proxy)
    (tmp_path / "frames").mkdir()
    for t in range(proxy.frame_count):
        save_png(tmp_path / "frames" / f"f_{t:03d}.png", figure_drawing(proxy, t))
    out = tmp_path / "out.gif"
    assert run_cli("scene", tmp_path / "proxy.json", "--frames", tmp_path / "frames", "--balls", "m2",
                   "--ball-count", "1", "-o", out) == 0
    err = capsys.readouterr().err
    assert out.exists() and "balls sank up to" in err and len(err.strip().splitlines()) == 1
