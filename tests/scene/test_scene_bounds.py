"""Every input of a 3D scene is bounded before anything is built (issue 45): the bodies to simulate
(the limit ``scene_bodies``), the sizes given to elements (at most ``MAX_SIZE`` figure heights),
and messages that name each kind of element in good grammar."""

import tracemalloc

import pytest

from tests.conftest import run_cli
from tests.scene.test_scene import figure_drawing, kicking, standing
from toonmotion import limits
from toonmotion.errors import LimitError, SceneError
from toonmotion.io.image import save_png
from toonmotion.io.proxy_json import save_proxy
from toonmotion.scene.build import STRING_LINKS, build_scene, check_scene, figure_height, scene_bodies
from toonmotion.scene.cloth import SCARF_BODIES, SKIRT_ROWS
from toonmotion.scene.elements import MAX_SIZE, Balloon, Balls, Cape, Rain, Scarf, Skirt

HUGE = [
    [Rain(count=1_000_000_000)],
    [Balls("m2", count=100_000)],
    [Skirt("m0", strands=10_000_000)],
    [Balloon("m2")] * 100,  # 900 bodies: many small elements add up
]


def test_the_count_is_the_bodies_mujoco_simulates():
    proxy = standing(T=2)
    elements = [Rain(count=5), Balls("m2", count=2), Balloon("m2"), Scarf("m1"), Skirt("m0", strands=3)]
    # A skirt of 3 strands is a ring of 6 cloth vertices (skirt_columns), its waistband pinned.
    assert scene_bodies(elements) == 5 + 2 + (STRING_LINKS + 1) + SCARF_BODIES + 6 * (SKIRT_ROWS - 1)
    model = build_scene(proxy, elements).model
    proxy_bodies = 1 + len(proxy.names) + len(proxy.limbs)  # the world, the markers and the limbs
    assert model.nbody - proxy_bodies == scene_bodies(elements)


@pytest.mark.parametrize("elements", HUGE, ids=["rain", "balls", "skirt", "balloons"])
def test_too_many_bodies_are_refused_at_once_in_one_line(elements):
    tracemalloc.start()
    try:
        with pytest.raises(LimitError) as refused:
            build_scene(standing(T=2), elements)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(refused.value)
    assert "\n" not in message
    assert f"it is {scene_bodies(elements):,}" in message
    assert "over the limit scene_bodies=500" in message and "--limit scene_bodies=N" in message
    assert peak < 5_000_000  # nothing was built: no drops placed, no XML written


def test_the_refusal_says_what_the_bodies_are():
    elements = [Rain(count=400), Balls("m2", count=50), Balloon("m2"), Balloon("m2"), Scarf("m1"),
                Skirt("m0", strands=16), Cape("m1", "m2")]
    listed = ("400 drops, 50 balls, 2 balloons of 9 bodies, 1 scarf of 36 cloth points, 1 skirt "
              "\\(112 cloth points\\) and 1 cape of 50 cloth points")
    with pytest.raises(LimitError, match=rf"\({listed}\) is over the limit scene_bodies=500 \(it is 666\)"):
        check_scene(standing(T=2), elements)


def test_raising_the_limit_lets_a_larger_scene_through_and_lowering_it_refuses_a_small_one():
    proxy = standing(T=2)
    rain = [Rain(count=510)]
    with pytest.raises(LimitError, match="it is 510"):
        build_scene(proxy, rain)
    with limits.using(scene_bodies=510):
        scene = build_scene(proxy, rain)
    assert len(scene.rain) == 510
    with limits.using(scene_bodies=10), pytest.raises(LimitError, match="scene_bodies=10 "):
        build_scene(proxy, [Balloon("m2"), Balls("m2", count=2)])


SIZES = [
    (lambda s: Balloon("m2", string_length=s), "a balloon's string", "longer"),
    (lambda s: Balloon("m2", radius=s), "a balloon's radius", "larger"),
    (lambda s: Balls("m2", radius=s), "a ball's radius", "larger"),
    (lambda s: Scarf("m1", length=s), "a scarf's length", "longer"),
    (lambda s: Scarf("m1", width=s), "a scarf's width", "wider"),
    (lambda s: Skirt("m0", length=s), "a skirt's length", "longer"),
    (lambda s: Skirt("m0", radius=s), "a skirt's radius", "larger"),
    (lambda s: Skirt("m0", width=s), "a skirt's strand width", "wider"),
    (lambda s: Cape("m0", "m1", length=s), "a cape's length", "longer"),
    (lambda s: Rain(radius=s), "a drop's radius", "larger"),
]


@pytest.mark.parametrize("make, what, larger", SIZES, ids=[what for _, what, _ in SIZES])
def test_a_size_over_five_figure_heights_is_refused_naming_it_the_figure_and_the_bound(make, what, larger):
    proxy = standing(T=2)
    height = figure_height(proxy)
    assert height == pytest.approx(0.9)
    check_scene(proxy, [make(MAX_SIZE * height)])  # the bound itself is allowed
    with pytest.raises(SceneError) as refused:
        build_scene(proxy, [make(1000.0)])
    assert str(refused.value).startswith(
        f"{what} (1000 m) is {larger} than 4.5 m, 5 times the figure's height of 0.9 m; give sizes in metres")
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize("element, words", [
    (Balloon("wrist"), "a balloon is held at 'wrist', which the proxy lacks"),
    (Balls("wrist"), "balls are laid in the path of 'wrist', which the proxy lacks"),
    (Scarf("wrist"), "a scarf is tied at 'wrist', which the proxy lacks"),
    (Skirt("wrist"), "a skirt hangs round 'wrist', which the proxy lacks"),
    (Cape("m1", "wrist"), "a cape hangs from 'wrist', which the proxy lacks"),
])
def test_a_missing_marker_is_named_in_good_grammar_for_every_element(element, words):
    """Issue 45: "the balls is held at ..."."""
    with pytest.raises(SceneError) as refused:
        build_scene(standing(T=2), [element])
    assert str(refused.value).startswith(words + "; its markers are m0, m1, m2")


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("bounds")
    proxy = kicking(T=4)
    save_proxy(folder / "proxy.json", proxy)
    (folder / "frames").mkdir()
    for t in range(proxy.frame_count):
        save_png(folder / "frames" / f"f_{t}.png", figure_drawing(proxy, t))
    return folder


@pytest.mark.parametrize("argv, message", [
    (["--rain", "1000000000"], "bodies to simulate (1,000,000,000 drops) is over the limit scene_bodies=500"),
    (["--balls", "m2,m1", "--ball-count", "100000"], "(200,000 balls) is over the limit scene_bodies=500"),
    (["--balloon", "m2", "--string-length", "1000"], "a balloon's string (1000 m) is longer than 4.5 m"),
    (["--balloon", "m2", "--balloon-radius", "1e300"], "a balloon's radius (1e+300 m) is larger than 4.5 m"),
    (["--balls", "m2", "--ball-radius", "4.6"], "a ball's radius (4.6 m) is larger than 4.5 m"),
    (["--balls", "wrist"], "balls are laid in the path of 'wrist', which the proxy lacks"),
    (["--cape", "m1"], "--cape takes two markers, LEFT,RIGHT (the figure's own shoulders), got 'm1'"),
    (["--cape", "m1,m1"], "a cape hangs between two markers, got 'm1' twice"),
])
def test_the_command_refuses_in_one_line_exit_2_before_reading_the_frames(files, capsys, argv, message):
    out = files / "kept.gif"
    out.write_bytes(b"earlier work")
    for frames in (files / "frames", files / "no such frames"):  # refused before the frames are read
        code = run_cli("scene", files / "proxy.json", "--frames", frames, "-o", out, *argv)
        err = capsys.readouterr().err
        assert code == 2
        assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
        assert out.read_bytes() == b"earlier work"


def test_the_command_takes_a_raised_limit_and_counts_scarves_in_good_grammar(files, capsys):
    out = files / "out"
    try:
        code = run_cli("--limit", "scene_bodies=72", "scene", files / "proxy.json", "--frames",
                       files / "frames", "--scarf", "m0", "--scarf", "m1", "--shading", "flat", "-o", out)
        assert code == 0
        assert "simulated 2 scarves over 4 frames" in capsys.readouterr().out
        code = run_cli("--limit", "scene_bodies=71", "scene", files / "proxy.json", "--frames",
                       files / "frames", "--scarf", "m0", "--scarf", "m1", "-o", out)
        err = capsys.readouterr().err
        assert code == 2 and "(2 scarves of 36 cloth points) is over the limit scene_bodies=71" in err
    finally:
        limits.set_limits(limits.Limits())
