"""Tests for the toonmotion command line (toonmotion.cli)."""

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import typer.main
from PIL import Image

from toonmotion.cli import app, main
from toonmotion.io.image import load_image, load_mask, png_bytes
from toonmotion.io.project import PROJECT_FILE, load_project
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.rig.pipeline import rig_drawing


def run(argv, capsys):
    """Run the CLI in-process; return (exit code, stdout, stderr)."""
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    code = info.value.code
    return (0 if code is None else code), out, err


def assert_user_error(result, message):
    code, out, err = result
    assert code == 2, (code, out, err)
    assert "Traceback" not in err and "Traceback" not in out
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("toonmotion: error: "), err
    assert re.search(message, lines[0]), lines[0]


def _drawing(tmp_path, name="figure.png"):
    """A small RGBA drawing: an opaque blob on a transparent background."""
    mask = np.zeros((48, 40), dtype=bool)
    mask[8:40, 10:30] = True
    mask[20:26, 2:38] = True
    rgba = np.zeros((48, 40, 4), dtype=np.uint8)
    rgba[mask] = (180, 90, 40, 255)
    path = tmp_path / name
    path.write_bytes(png_bytes(rgba))
    return path


@pytest.fixture(scope="module")
def shared_project(tmp_path_factory):
    """char2 rigged through the CLI with its mask and char_cfg skeleton."""
    from tests.conftest import DRAWINGS_DIR, _require

    folder = _require(DRAWINGS_DIR) / "char2"
    out = tmp_path_factory.mktemp("cli") / "char2-project"
    with pytest.raises(SystemExit) as info:
        main([
            "rig", str(folder / "texture.png"), "--mask", str(folder / "mask.png"),
            "--skeleton", str(folder / "char_cfg.yaml"), "--vertices", "500", "-o", str(out),
        ])
    assert info.value.code in (0, None)
    return folder, out


def test_rig_writes_a_loadable_project(shared_project):
    folder, out = shared_project
    character = load_project(out)
    texture = load_image(folder / "texture.png")
    np.testing.assert_array_equal(character.texture, texture)
    np.testing.assert_array_equal(character.mask, load_mask(folder / "mask.png"))
    expected = load_skeleton_file(folder / "char_cfg.yaml")
    assert character.skeleton.names == expected.names
    np.testing.assert_array_equal(character.skeleton.positions, expected.positions)
    assert abs(len(character.mesh.V) - 500) <= 25
    assert character.settings.vertices == 500 and character.settings.spacing is None
    n = len(character.mesh.V)
    assert character.binding.bone.shape == (n,)


def test_rig_reports_what_it_wrote(tmp_path, capsys):
    code, out, err = run(["rig", _drawing(tmp_path), "-o", tmp_path / "p", "--spacing", "4"],
                         capsys)
    assert code == 0, err
    assert re.fullmatch(r"rigged figure.png: \d+ vertices, \d+ triangles, \d+ joints -> .*p\n",
                        out), out
    assert err == ""
    assert load_project(tmp_path / "p").mesh.spacing == 4.0


def test_show_writes_a_png(shared_project, tmp_path, capsys):
    _, project = shared_project
    target = tmp_path / "overview.png"
    code, out, err = run(["show", project, "-o", target, "--height", "200"], capsys)
    assert code == 0, err
    assert out.strip() == f"wrote {target}"
    with Image.open(target) as image:
        assert image.format == "PNG" and image.mode == "RGB"
        assert 200 < image.height < 260
    assert sorted(p.name for p in tmp_path.iterdir()) == ["overview.png"]


@pytest.mark.parametrize("suffix", [".json", ".yaml"])
def test_sample_writes_a_drawing_and_skeleton_that_rig(tmp_path, capsys, suffix):
    png, skeleton = tmp_path / "x.png", tmp_path / f"x{suffix}"
    code, out, err = run(["sample", "-o", png, "--skeleton", skeleton], capsys)
    assert code == 0, err
    assert out.strip() == f"wrote {png}, {skeleton}"
    rgba = load_image(png)
    assert rgba.shape[2] == 4 and rgba[..., 3].min() < 255  # transparent background
    bones = load_skeleton_file(skeleton, image_size=(rgba.shape[1], rgba.shape[0]))
    assert len(bones.bones) >= 1
    # The pair rigs, through the library ...
    character = rig_drawing(rgba, skeleton=bones)
    assert character.binding.bone.shape == (len(character.mesh.V),)
    # ... and through the CLI.
    code, out, err = run(["rig", png, "--skeleton", skeleton, "--vertices", "400",
                          "-o", tmp_path / "proj"], capsys)
    assert code == 0, err
    assert load_project(tmp_path / "proj").skeleton.names == bones.names


def test_sample_without_skeleton(tmp_path, capsys):
    code, out, err = run(["sample", "-o", tmp_path / "only.png"], capsys)
    assert code == 0, err
    assert out.strip() == f"wrote {tmp_path / 'only.png'}"
    assert [p.name for p in tmp_path.iterdir()] == ["only.png"]


def _options(command):
    return {opt for param in command.params for opt in (*param.opts, *param.secondary_opts)}


COMMANDS = ("rig", "show", "sample", "pose", "sketch", "animate", "filter", "depth", "correct", "undo",
            "redo", "track", "retarget", "keyshapes", "capture-contours", "retarget-keyshapes",
            "retarget-line", "capture-video", "lift", "proxy-export", "proxy-preview", "project-mocap",
            "edits", "remesh",
            "tune", "edit", "scene", "export", "batch", "doctor")


def test_every_command_is_in_the_command_reference_and_the_readme_table():
    from pathlib import Path

    assert set(typer.main.get_command(app).commands) == set(COMMANDS)
    root = Path(__file__).resolve().parents[1]
    reference = (root / "docs" / "commands.md").read_text(encoding="utf-8")
    readme = (root / "README.md").read_text(encoding="utf-8")
    for command in COMMANDS:
        assert f"`toonmotion {command} " in reference, command
        assert f"`{command}`" in readme, command


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_help_exits_zero_and_names_only_real_options(capsys, command):
    argv = ["--help"] if command is None else [command, "--help"]
    code, out, err = run(argv, capsys)
    assert code == 0, err
    group = typer.main.get_command(app)
    known = _options(group if command is None else group.commands[command]) | {"--help"}
    named = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", out))
    assert named, out
    assert named <= known, f"help names options that do not exist: {named - known}"
    if command is None:
        assert {"rig", "show", "sample"} <= set(re.findall(r"\w+", out))


def test_rig_help_mentions_the_main_options(capsys):
    code, out, _ = run(["rig", "--help"], capsys)
    assert code == 0
    for option in ("--mask", "--skeleton", "--spacing", "--vertices", "-o", "--output"):
        assert re.search(rf"(?<![\w-]){option}(?![\w-])", out), option
    # The defaults stated in the help text are shown, not swallowed as markup.
    assert "[default: 1500]" in re.sub(r"[\s│]+", " ", out)


def test_version(capsys):
    from toonmotion import __version__

    code, out, _ = run(["--version"], capsys)
    assert code == 0 and out.strip() == f"toonmotion {__version__}"


# --- user errors: exit 2, one line, no traceback -------------------------------------------------


def test_missing_image(tmp_path, capsys):
    result = run(["rig", tmp_path / "nope.png", "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"cannot read .*nope.png: no such file")
    assert not (tmp_path / "p").exists()


def test_truncated_image(tmp_path, capsys):
    data = _drawing(tmp_path).read_bytes()
    (tmp_path / "cut.png").write_bytes(data[: len(data) // 2])
    result = run(["rig", tmp_path / "cut.png", "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"cut.png: the file is damaged or truncated")


def test_empty_mask(tmp_path, capsys):
    image = _drawing(tmp_path)
    Image.fromarray(np.zeros((48, 40), dtype=np.uint8)).save(tmp_path / "mask.png")
    result = run(["rig", image, "--mask", tmp_path / "mask.png", "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"the mask is empty")


def test_mask_of_the_wrong_size(tmp_path, capsys):
    image = _drawing(tmp_path)
    Image.fromarray(np.full((40, 48), 255, dtype=np.uint8)).save(tmp_path / "mask.png")
    result = run(["rig", image, "--mask", tmp_path / "mask.png", "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"mask mask.png is 48x40 but the drawing is 40x48")


def _cycle_yaml(tmp_path):
    path = tmp_path / "cycle.yaml"
    path.write_text(
        "width: 40\nheight: 48\nskeleton:\n"
        "- {name: a, parent: b, loc: [20, 10]}\n"
        "- {name: b, parent: a, loc: [20, 30]}\n"
    )
    return path


def test_skeleton_with_a_cycle(tmp_path, capsys):
    result = run(["rig", _drawing(tmp_path), "--skeleton", _cycle_yaml(tmp_path),
                  "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"the skeleton has a cycle through joints a, b")


def test_spacing_and_vertices_together(tmp_path, capsys):
    result = run(["rig", _drawing(tmp_path), "--spacing", "4", "--vertices", "300",
                  "-o", tmp_path / "p"], capsys)
    assert_user_error(result, r"give either --spacing or --vertices, not both")


def test_unknown_background(tmp_path, capsys):
    rgb = np.full((30, 30, 3), 255, dtype=np.uint8)
    rgb[10:20, 10:20] = 0
    Image.fromarray(rgb).save(tmp_path / "rgb.png")
    result = run(["rig", tmp_path / "rgb.png", "--background", "sky", "-o", tmp_path / "p"],
                 capsys)
    assert_user_error(result, r"segmentation must be one of auto, flat, paper, got 'sky'")


def test_image_over_max_pixels(tmp_path, capsys):
    result = run(["rig", _drawing(tmp_path), "--max-pixels", "100", "-o", tmp_path / "p"],
                 capsys)
    assert_user_error(result, r"over the limit of 100; .*--max-pixels")


@pytest.mark.parametrize(
    ("version", "message"),
    [(99, r"is project version 99, newer .*; upgrade toonmotion"),
     ("two", r"has unknown project version 'two'")],
    ids=["newer", "unknown"],
)
def test_show_a_project_of_another_version(tmp_path, capsys, version, message):
    folder = tmp_path / "proj"
    folder.mkdir()
    (folder / PROJECT_FILE).write_text(
        json.dumps({"format": "toonmotion.project", "version": version})
    )
    result = run(["show", folder, "-o", tmp_path / "o.png"], capsys)
    assert_user_error(result, message)
    assert not (tmp_path / "o.png").exists()


def test_show_a_missing_project(tmp_path, capsys):
    result = run(["show", tmp_path / "nothing", "-o", tmp_path / "o.png"], capsys)
    assert_user_error(result, r"no project at")


def test_show_to_a_non_png(shared_project, tmp_path, capsys):
    _, project = shared_project
    result = run(["show", project, "-o", tmp_path / "overview.jpg"], capsys)
    assert_user_error(result, r"give an output ending in .png, not overview.jpg")
    assert not (tmp_path / "overview.jpg").exists()


def test_failed_rig_leaves_an_existing_project_untouched(tmp_path, capsys):
    image = _drawing(tmp_path)
    project = tmp_path / "p"
    code, _, err = run(["rig", image, "-o", project, "--vertices", "200"], capsys)
    assert code == 0, err
    before = {p.name: p.read_bytes() for p in project.iterdir()}
    Image.fromarray(np.zeros((48, 40), dtype=np.uint8)).save(tmp_path / "empty.png")
    for argv in (
        ["--mask", tmp_path / "empty.png"],
        ["--skeleton", _cycle_yaml(tmp_path)],
        ["--spacing", "3", "--vertices", "300"],
    ):
        result = run(["rig", image, "-o", project, *argv], capsys)
        assert_user_error(result, ".")
        assert {p.name: p.read_bytes() for p in project.iterdir()} == before


def test_rig_into_a_file_is_a_user_error(tmp_path, capsys):
    (tmp_path / "taken").write_text("x")
    result = run(["rig", _drawing(tmp_path), "-o", tmp_path / "taken", "--vertices", "200"],
                 capsys)
    assert_user_error(result, r"is a file; a project is a folder")
    assert (tmp_path / "taken").read_text() == "x"


def test_error_exit_code_in_a_real_process(tmp_path):
    script = Path(sys.executable).parent / "toonmotion"
    command = [str(script)] if script.is_file() else [sys.executable, "-m", "toonmotion.cli"]
    completed = subprocess.run(
        [*command, "rig", str(tmp_path / "missing.png"), "-o", str(tmp_path / "p")],
        capture_output=True, text=True, timeout=60, cwd=tmp_path,
    )
    assert completed.returncode == 2, completed
    lines = completed.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("toonmotion: error: cannot read"), lines
    assert "Traceback" not in completed.stderr
    module = subprocess.run(
        [sys.executable, "-m", "toonmotion.cli", "show", str(tmp_path), "-o", "x.gif"],
        capture_output=True, text=True, timeout=60, cwd=tmp_path,
    )
    assert module.returncode == 2
    assert module.stderr.startswith("toonmotion: error: the overview is a PNG")


def test_unwritable_output_is_a_user_error(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    result = run(["rig", _drawing(tmp_path), "-o", tmp_path / "file" / "p", "--vertices", "200"],
                 capsys)
    assert_user_error(result, r"file\S* is a file, not a folder")
    result = run(["sample", "-o", tmp_path / "file" / "s.png"], capsys)
    assert_user_error(result, r"file\S* is a file, not a folder")
    assert (tmp_path / "file").read_text() == "x"
    # Refused as the file is written: named as the user gave it, not by its temporary name.
    result = run(["sample", "-o", "/proc/toonmotion-sample.png"], capsys)
    assert_user_error(result, r"cannot write /proc/toonmotion-sample.png: ")


def test_sample_refuses_a_skeleton_file_rig_cannot_read(tmp_path, capsys):
    result = run(["sample", "-o", tmp_path / "s.png", "--skeleton", tmp_path / "s.txt"], capsys)
    assert_user_error(result, r"ending in .json or .yaml .*not s.txt")
    assert list(tmp_path.iterdir()) == []


# --- pose, animate, depth (issue 3) ------------------------------------------------------------


def _run(*argv):
    """Run the CLI in-process; return the exit code (output goes where pytest captures it)."""
    try:
        main([str(a) for a in argv])
    except SystemExit as stop:
        return 0 if stop.code is None else stop.code
    return 0


@pytest.fixture(scope="module")
def posable(tmp_path_factory):
    """The sample character rigged into a project, with its key-frames and a pose file."""
    from toonmotion.io.pose_json import save_pose
    from toonmotion.rig.pose import Pose, rotate_about

    folder = tmp_path_factory.mktemp("posable")
    png, skeleton_file, keys = folder / "hero.png", folder / "hero.json", folder / "keys.json"
    assert _run("sample", "-o", str(png), "--skeleton", str(skeleton_file), "--keys", str(keys)) == 0
    assert _run("rig", str(png), "--skeleton", str(skeleton_file), "-o", str(folder / "hero")) == 0
    skeleton = load_project(folder / "hero").skeleton
    bent = rotate_about(skeleton, skeleton.positions, "right_elbow", 1.0)
    save_pose(folder / "pose.json", skeleton, Pose(bent))
    return folder


def test_pose_writes_a_frame_of_the_asked_size(posable, tmp_path, capsys):
    out = tmp_path / "posed.png"
    code = _run("pose", str(posable / "hero"), str(posable / "pose.json"), "-o", str(out),
                "--size", "200x300", "--overlay", "skeleton,rest")
    assert code == 0
    image = Image.open(out)
    assert image.size == (200, 300) and image.mode == "RGBA"
    assert "stage two" in capsys.readouterr().out


def test_pose_with_blended_skinning_renders_another_frame(posable, tmp_path, capsys):
    args = [str(posable / "hero"), str(posable / "pose.json"), "--size", "200x300", "--background", "white"]
    assert _run("pose", *args, "-o", str(tmp_path / "one.png")) == 0
    assert _run("pose", *args, "-o", str(tmp_path / "blended.png"), "--skinning", "weights") == 0
    one = np.asarray(Image.open(tmp_path / "one.png"), dtype=int)
    blended = np.asarray(Image.open(tmp_path / "blended.png"), dtype=int)
    assert one.shape == blended.shape and (np.abs(one - blended).max(axis=2) > 48).mean() > 1e-3
    capsys.readouterr()
    assert _run("pose", *args, "-o", str(tmp_path / "x.png"), "--skinning", "linear") == 2
    err = capsys.readouterr().err
    assert "skinning must be one of one-bone, weights" in err and "Traceback" not in err
    assert not (tmp_path / "x.png").exists()


def test_sketch_writes_the_pose_its_strokes_draw(posable, tmp_path, capsys):
    from toonmotion.io.pose_json import load_pose
    from toonmotion.io.sketch_json import save_sketch

    skeleton = load_project(posable / "hero").skeleton
    bent = load_pose(posable / "pose.json", skeleton).positions  # the forearm turned by 1 rad
    elbow, hand = skeleton.index("right_elbow"), skeleton.index("right_hand")
    save_sketch(tmp_path / "arm.json", [np.linspace(bent[elbow], bent[hand], 10)])
    assert _run("sketch", posable / "hero", tmp_path / "arm.json", "-o", tmp_path / "arm_pose.json") == 0
    assert "sketched right_hand ->" in capsys.readouterr().out
    np.testing.assert_allclose(load_pose(tmp_path / "arm_pose.json", skeleton).positions, bent, atol=1e-3)
    assert _run("pose", posable / "hero", tmp_path / "arm_pose.json", "-o", tmp_path / "arm.png") == 0


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('{"format": "toonmotion.sketch", "version": 1, "strokes": []}', "at least one stroke"),
        ('{"format": "toonmotion.sketch", "version": 1, "strokes": [[[1, 2]]]}', "at least 2"),
        ('{"format": "toonmotion.sketch", "version": 2, "strokes": [[[1, 2], [3, 4]]]}', "version 2"),
        ('{"format": "toonmotion.pose", "version": 1, "joints": {}}', "not a toonmotion sketch file"),
        ('{"format": "toonmotion.sketch", "version": 1, "strokes": [[[0, 0], [9, 0]], [[9, 0], [5, 8]], '
         '[[5, 8], [0, 0]], [[0, 0], [4, 3]], [[40, 40], [41, 60]], [[80, 0], [80, 30]], '
         '[[0, 90], [30, 90]], [[60, 90], [90, 90]], [[0, 130], [30, 130]], [[60, 130], [90, 130]], '
         '[[0, 170], [30, 170]], [[60, 170], [90, 170]], [[0, 210], [30, 210]], [[60, 210], [90, 210]], '
         '[[0, 250], [30, 250]], [[60, 250], [90, 250]], [[0, 290], [30, 290]], [[60, 290], [90, 290]]]}',
         "more than the skeleton's"),
    ],
)
def test_a_bad_sketch_file_is_one_line(posable, tmp_path, capsys, content, message):
    (tmp_path / "bad.json").write_text(content)
    code = _run("sketch", posable / "hero", tmp_path / "bad.json", "-o", tmp_path / "out.json")
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "out.json").exists()


def test_animate_writes_every_frame_of_the_timeline(posable, tmp_path, capsys):
    out = tmp_path / "anim.gif"
    assert _run("animate", str(posable / "hero"), str(posable / "keys.json"), "-o", str(out),
                "--size", "84x120", "--fps", "24") == 0
    gif = Image.open(out)
    assert gif.n_frames == 37  # the built-in key-frames end at frame 36
    assert gif.size == (84, 120)
    assert "GIF plays" not in capsys.readouterr().err
    assert _run("animate", str(posable / "hero"), str(posable / "keys.json"), "-o", str(out),
                "--size", "42x60", "--fps", "200") == 0  # faster than a GIF can play: said
    assert "a GIF plays at most 50 frames a second" in capsys.readouterr().err


def test_export_writes_a_glb_a_spine_rig_and_a_sprite_sheet(posable, tmp_path, capsys):
    import pygltflib as gl

    project, keys = str(posable / "hero"), str(posable / "keys.json")
    assert _run("export", project, keys, "-o", str(tmp_path / "hero.glb")) == 0
    out = capsys.readouterr().out
    assert out.startswith("exported 7 key-frames as glb: 37 frames at 12 fps ->"), out
    glb = gl.GLTF2.load_binary(tmp_path / "hero.glb")
    assert len(glb.animations) == 1 and len(glb.skins) == 1 and glb.meshes[0].primitives[0].targets
    assert _run("export", project, keys, "-o", str(tmp_path / "hero.json"), "--format", "spine") == 0
    assert sorted(p.name for p in tmp_path.glob("hero.*")) == ["hero.atlas", "hero.glb", "hero.json",
                                                              "hero.png"]
    assert _run("export", project, keys, "-o", str(tmp_path / "sheet.json"), "--format", "sheet",
                "--padding", "0", "--no-trim", "--size", "42x60") == 0
    atlas = json.loads((tmp_path / "sheet.json").read_text())
    assert len(atlas["frames"]) == 37 and atlas["meta"]["image"] == "sheet.png"
    first = next(iter(atlas["frames"].values()))
    assert first["sourceSize"] == {"w": 42, "h": 60} and not first["trimmed"]
    assert "42x60 ->" in capsys.readouterr().out


def test_export_keeps_transparency_in_webm_and_plays_a_motion(posable, tmp_path, capsys):
    from toonmotion.io.ffmpeg_video import read_webm_rgba

    project = str(posable / "hero")
    motion = tmp_path / "motion.json"
    assert _run("animate", project, str(posable / "keys.json"), "-o", str(tmp_path / "a.gif"),
                "--size", "42x60", "--save-motion", str(motion)) == 0
    assert _run("export", project, str(motion), "-o", str(tmp_path / "hero.webm"), "--size", "42x60") == 0
    assert "exported a motion of 37 frames as webm" in capsys.readouterr().out
    frames = read_webm_rgba(tmp_path / "hero.webm")
    assert frames.shape == (37, 60, 42, 4)
    assert frames[..., 3].min() < 16 and frames[..., 3].max() > 240  # see-through and solid both


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["-o", "hero.json"], "give --format spine or --format sheet"),
        (["-o", "hero.glb", "--format", "fbx"], "unknown export format 'fbx'"),
        (["-o", "hero.fbx"], "cannot export to hero.fbx: give .glb, .json with --format spine or sheet"),
        (["-o", "hero.glb", "--format", "spine"], "a spine export is a .json file"),
        (["-o", "hero.json", "--format", "sheet", "--max-size", "64"], "more than max_size 64"),
    ],
)
def test_export_refuses_what_it_cannot_write_in_one_line(posable, tmp_path, capsys, extra, message):
    (tmp_path / "hero.json").write_text("previous")
    argv = [str(posable / "hero"), str(posable / "keys.json"), *extra]
    argv[argv.index("-o") + 1] = str(tmp_path / argv[argv.index("-o") + 1])
    code = _run("export", *argv)
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["hero.json"]
    assert (tmp_path / "hero.json").read_text() == "previous"


def test_animate_to_png_frames(posable, tmp_path):
    out = tmp_path / "frames"
    assert _run("animate", str(posable / "hero"), str(posable / "keys.json"), "-o", str(out),
                "--size", "42x60") == 0
    assert len(list(out.glob("*.png"))) == 37


def test_depth_sets_a_region_by_name_and_by_point_and_saves_it(posable, tmp_path, capsys):
    import shutil

    project = tmp_path / "hero"
    shutil.copytree(posable / "hero", project)
    hand = load_project(project).skeleton.positions[load_project(project).skeleton.index("right_hand")]
    assert _run("depth", str(project), "left_elbow=2", f"@{hand[0]},{hand[1]}=-1") == 0
    character = load_project(project)
    names = character.skeleton.bone_names
    assert character.depth[names.index("left_elbow")] == 2
    assert -1 in character.depth.tolist()


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.jpg"], "give an output ending in .png"),
        (["pose", "{p}/hero", "{p}/missing.json", "-o", "{t}/x.png"], "no such file"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--size", "0x5"], "--size takes WxH"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--weights", "1,2"], "--weights takes 3"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--overlay", "bones"], "unknown overlay"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--background", "mauve"], "--background"),
        (["animate", "{p}/hero", "{p}/keys.json", "-o", "{t}/x.avi"], "give a .gif or .mp4 file"),
        (["animate", "{p}/hero", "{p}/keys.json", "-o", "{t}/x.gif", "--ease", "bouncy"], "ease must be"),
        (["animate", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.gif"], "is not a key-frames file"),
        (["depth", "{p}/hero", "tail=1"], "no bone is called 'tail'"),
        (["depth", "{p}/hero", "left_elbow=up"], "whole-number depth"),
    ],
)
def test_posing_errors_are_one_line_and_exit_2(posable, tmp_path, capsys, args, message):
    args = [a.format(p=posable, t=tmp_path) for a in args]
    assert _run(*args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("toonmotion: error: ") and "\n" not in err
    assert message in err


def _copy_project(posable, tmp_path):
    import shutil

    project = tmp_path / "hero"
    shutil.copytree(posable / "hero", project)
    return project


def test_animate_exaggerated_saves_a_motion_that_filter_and_animate_read(posable, tmp_path, capsys):
    from toonmotion.io.motion_json import load_motion

    plain, wild = tmp_path / "plain.json", tmp_path / "wild.json"
    assert _run("animate", posable / "hero", posable / "keys.json", "-o", tmp_path / "a.gif",
                "--size", "42x60", "--save-motion", plain) == 0
    assert _run("animate", posable / "hero", posable / "keys.json", "-o", tmp_path / "b.gif",
                "--size", "42x60", "--save-motion", wild, "--exaggerate", "1.5") == 0
    assert "exaggerated (A=1.5)" in capsys.readouterr().out
    a, b = load_motion(plain), load_motion(wild)
    assert a.positions.shape == b.positions.shape == (37, 17, 2) and a.fps == b.fps == 12
    assert np.abs(a.positions - b.positions).max() > 2.0

    filtered = tmp_path / "filtered.json"
    assert _run("filter", plain, "--strength", "1.5", "-o", filtered) == 0
    assert "filtered 37 frames" in capsys.readouterr().out
    # The CLI filter of the saved motion is the exaggeration animate applied.
    np.testing.assert_allclose(load_motion(filtered).positions, b.positions, atol=1e-9)
    out = tmp_path / "motion.gif"
    assert _run("animate", posable / "hero", filtered, "-o", out, "--size", "42x60") == 0
    assert Image.open(out).n_frames == 37


def test_animate_saves_the_motion_as_its_frames_show_it(posable, tmp_path):
    from toonmotion.io.frames import load_frames
    from toonmotion.io.motion_json import load_motion

    frames, seen, canvas = tmp_path / "frames", tmp_path / "seen.json", tmp_path / "canvas.json"
    assert _run("animate", posable / "hero", posable / "keys.json", "-o", frames, "--size", "120x160",
                "--save-frame-motion", seen, "--save-motion", canvas) == 0
    pictures = load_frames(frames, alpha=True)[0]
    a, b = load_motion(seen), load_motion(canvas)
    # One scale and offset take the drawing's pixels to the frames'.
    scale = np.ptp(a.positions[..., 0]) / np.ptp(b.positions[..., 0])
    np.testing.assert_allclose(a.positions, scale * b.positions + (a.positions - scale * b.positions)[0, 0],
                               atol=1e-9)
    # The joints lie on the drawn figure in the frames (inside its opaque pixels).
    col, row = np.rint(a.positions[..., 0]).astype(int), np.rint(a.positions[..., 1]).astype(int)
    on_figure = pictures[np.arange(len(pictures))[:, None], row, col, 3] > 0
    assert on_figure.mean() > 0.95


def test_filter_only_chosen_joints(posable, tmp_path):
    from toonmotion.io.motion_json import load_motion

    plain, hand = tmp_path / "plain.json", tmp_path / "hand.json"
    assert _run("animate", posable / "hero", posable / "keys.json", "-o", tmp_path / "a.gif",
                "--size", "42x60", "--save-motion", plain) == 0
    assert _run("filter", plain, "--strength", "2", "--joints", "right_hand", "-o", hand) == 0
    before, after = load_motion(plain), load_motion(hand)
    moved = np.abs(after.positions - before.positions).max(axis=(0, 2))
    names = before.skeleton.names
    assert moved[names.index("right_hand")] > 0.5
    assert moved[[i for i, n in enumerate(names) if n != "right_hand"]].max() == 0


def test_pose_with_the_single_frame_filter_keeps_the_feet(posable, tmp_path, capsys):
    out = tmp_path / "crouch.png"
    assert _run("pose", posable / "hero", posable / "pose.json", "-o", out,
                "--accel", "0,-30", "--fixed", "right_foot,left_foot") == 0
    assert Image.open(out).mode == "RGBA"


def test_correct_undo_redo_and_list_edits(posable, tmp_path, capsys):
    project = _copy_project(posable, tmp_path)
    before = load_project(project).binding.bone
    assert _run("correct", project, "right_hand", "40,200", "120,200", "120,300", "40,300") == 0
    assert "attached" in capsys.readouterr().out
    corrected = load_project(project).binding.bone
    assert (corrected != before).any()
    assert _run("depth", project, "head=3") == 0
    capsys.readouterr()
    assert _run("edits", project) == 0
    listing = capsys.readouterr().out.splitlines()
    assert len(listing) == 2 and "right_hand" in listing[0] and "depth 3 for head" in listing[1]
    assert _run("undo", project, "--steps", "2") == 0
    assert capsys.readouterr().out.count("undid") == 2
    undone = load_project(project)
    np.testing.assert_array_equal(undone.binding.bone, before)
    assert not undone.depth.any()
    assert _run("redo", project) == 0
    np.testing.assert_array_equal(load_project(project).binding.bone, corrected)
    assert _run("edits", project) == 0
    out = capsys.readouterr().out
    assert "redo depth 3 for head" in out


def test_remesh_replays_the_edits(posable, tmp_path, capsys):
    project = _copy_project(posable, tmp_path)
    assert _run("depth", project, "right_elbow=1") == 0
    assert _run("remesh", project, "--vertices", "700") == 0
    assert "1 edit replayed" in capsys.readouterr().out
    character = load_project(project)
    assert abs(len(character.mesh.V) - 700) < 200
    assert character.depth[character.skeleton.bone_names.index("right_elbow")] == 1



def test_remesh_too_coarse_warns_and_too_fine_is_refused_keeping_the_project(posable, tmp_path, capsys):
    from toonmotion.shape.mesh import left_out

    project = _copy_project(posable, tmp_path)
    assert _run("remesh", project, "--vertices", "40") == 0
    coarse = load_project(project)
    said = capsys.readouterr().err
    assert left_out(coarse.mesh, coarse.mask) > 0.05 and "of the figure" in said and "more --vertices" in said
    before = (project / "project.json").read_bytes()
    assert _run("remesh", project, "--vertices", "60000") == 2
    assert "mesh_vertices=50,000" in capsys.readouterr().err
    assert (project / "project.json").read_bytes() == before
    assert _run("remesh", project, "--vertices", "1500") == 0
    assert "of the figure" not in capsys.readouterr().err

def test_tune_adds_lists_and_undoes_edits_in_a_pose_file(posable, tmp_path, capsys):
    import shutil

    from toonmotion.io.pose_json import load_pose_edits

    pose = tmp_path / "pose.json"
    shutil.copy(posable / "pose.json", pose)
    head = load_project(posable / "hero").skeleton.positions[4]
    x, y = head
    assert _run("tune", posable / "hero", pose, "--drag", f"{x},{y}:{x + 3},{y - 2}",
                "-o", tmp_path / "tuned.png") == 0
    assert "added edit 1: drag" in capsys.readouterr().out
    assert len(load_pose_edits(pose)) == 1
    assert Image.open(tmp_path / "tuned.png").mode == "RGBA"
    assert _run("pose", posable / "hero", pose, "-o", tmp_path / "p.png") == 0
    assert "1 edit" in capsys.readouterr().out
    assert _run("tune", posable / "hero", pose) == 0
    assert "drag" in capsys.readouterr().out
    assert _run("tune", posable / "hero", pose, "--undo") == 0
    assert load_pose_edits(pose) == ()


def test_tune_a_key_of_a_key_frames_file(posable, tmp_path, capsys):
    import shutil

    from toonmotion.io.pose_json import load_keyframes

    keys = tmp_path / "keys.json"
    shutil.copy(posable / "keys.json", keys)
    skeleton = load_project(posable / "hero").skeleton
    x, y = skeleton.positions[4]
    assert _run("tune", posable / "hero", keys, "--key", "12", "--drag", f"{x},{y}:{x},{y - 3}") == 0
    timeline = load_keyframes(keys, skeleton)
    assert [len(k.edits) for k in timeline.keys] == [0, 0, 1, 0, 0, 0, 0]
    assert _run("animate", posable / "hero", keys, "-o", tmp_path / "a.gif", "--size", "42x60") == 0


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["filter", "{t}/m.json", "--strength", "-1", "-o", "{t}/o.json"], "strength must be a finite"),
        (["filter", "{t}/m.json", "--strength", "nan", "-o", "{t}/o.json"], "strength must be a finite"),
        (["filter", "{t}/m.json", "--strength", "1", "--sigma", "0", "-o", "{t}/o.json"], "sigma"),
        (["filter", "{t}/m.json", "--strength", "1", "--joints", "tail", "-o", "{t}/o.json"], "tail"),
        (["filter", "{p}/keys.json", "--strength", "1", "-o", "{t}/o.json"], "is not a motion file"),
        (["filter", "{t}/m.json", "--strength", "1", "-o", "{t}/o.gif"], "ending in .json"),
        (["animate", "{p}/hero", "{p}/keys.json", "-o", "{t}/x.gif", "--exaggerate", "-2"], "strength"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--accel", "0,-9"], "go together"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--accel", "0,-9", "--fixed", "root"],
         "not on a chain from the root"),
        (["pose", "{p}/hero", "{p}/pose.json", "-o", "{t}/x.png", "--accel", "0", "--fixed", "left_foot"],
         "--accel takes 2"),
        (["tune", "{p}/hero", "{p}/pose.json", "--curve", "10,10"], "at least 2 points"),
        (["tune", "{p}/hero", "{p}/pose.json", "--drag", "10,10"], "X,Y:X2,Y2"),
        (["tune", "{p}/hero", "{p}/pose.json", "--drag", "-500,-500:0,0"], "no vertex within"),
        (["tune", "{p}/hero", "{p}/pose.json", "--undo"], "no edits to undo"),
        (["tune", "{p}/hero", "{p}/keys.json", "--key", "5", "--undo"], "no key at frame 5"),
        (["undo", "{p}/hero"], "no edits to undo"),
        (["redo", "{p}/hero"], "nothing to redo"),
        (["correct", "{p}/hero", "tail", "0,0", "9,0", "0,9"], "no bone is called 'tail'"),
        (["correct", "{p}/hero", "head", "0,0", "9,0"], "at least 3"),
        (["remesh", "{p}/hero"], "give --spacing, --vertices"),
    ],
)
def test_filter_and_edit_errors_are_one_line_and_exit_2(posable, tmp_path, capsys, args, message):
    from toonmotion.animate.motion import Motion
    from toonmotion.io.motion_json import save_motion

    skeleton = load_project(posable / "hero").skeleton
    save_motion(tmp_path / "m.json", Motion(skeleton, np.stack([skeleton.positions] * 5), fps=12))
    pose_before = (posable / "pose.json").read_bytes()
    args = [a.format(p=posable, t=tmp_path) for a in args]
    assert _run(*args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("toonmotion: error: ") and "\n" not in err
    assert message in err
    assert (posable / "pose.json").read_bytes() == pose_before, "a failed edit must not touch the file"


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    """A waving arm named like the sample's, rendered as PNG frames, with its true joints."""
    from toonmotion.capture.synthetic import limb_figure_frames
    from toonmotion.io.track_json import save_joints
    from toonmotion.io.video import save_animation
    from toonmotion.rig.skeleton import Skeleton

    folder = tmp_path_factory.mktemp("footage")
    t = np.arange(12)[:, None]
    shoulder = np.repeat([[150.0, 100.0]], 12, axis=0)
    elbow = shoulder + 50 * np.hstack([np.cos(0.04 * t), np.sin(0.04 * t)])
    hand = elbow + 45 * np.hstack([np.cos(0.1 * t), np.sin(0.1 * t)])
    truth = np.stack([shoulder, elbow, hand], axis=1)
    frames, radius = limb_figure_frames(truth, np.array([-1, 0, 1]), size=(320, 240), width=14, seed=4)
    opaque = np.concatenate([frames, np.full(frames.shape[:3] + (1,), 255, np.uint8)], axis=3)
    save_animation(folder / "frames", iter(opaque), fps=12)
    skeleton = Skeleton.from_joints([("right_shoulder", None, tuple(truth[0, 0])),
                                     ("right_elbow", "right_shoulder", tuple(truth[0, 1])),
                                     ("right_hand", "right_elbow", tuple(truth[0, 2]))])
    save_joints(folder / "joints.json", skeleton, np.full((3, 2), 2 * radius))
    return folder, truth


def test_track_writes_a_motion_csv_and_overlay(footage, tmp_path, capsys):
    from toonmotion.io.motion_json import load_motion

    folder, truth = footage
    out = tmp_path / "m.json"
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", out, "--fps", "12",
                "--csv", tmp_path / "m.csv", "--overlay", tmp_path / "o.gif") == 0
    assert "tracked 3 joints through 12 frames" in capsys.readouterr().out
    motion = load_motion(out)
    assert motion.fps == 12 and motion.confidence.shape == (12, 3)
    assert np.hypot(*(motion.positions - truth).reshape(-1, 2).T).max() < 2.0
    assert len((tmp_path / "m.csv").read_text().splitlines()) == 13
    assert Image.open(tmp_path / "o.gif").n_frames == 12


def test_track_warns_of_rectangles_much_smaller_than_the_figure_asks_for(footage, tmp_path, capsys):
    from toonmotion.io.track_json import load_joints, save_joints

    folder, _ = footage
    skeleton, sizes, _ = load_joints(folder / "joints.json")  # twice the arm's thickness: no warning
    out = tmp_path / "m.json"
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", out) == 0
    assert "small" not in capsys.readouterr().err
    save_joints(tmp_path / "small.json", skeleton, sizes / 3)
    assert _run("track", folder / "frames", "--joints", tmp_path / "small.json", "-o", out) == 0
    said = capsys.readouterr().err
    assert f"median {sizes[0, 0] / 3:.0f} px" in said and "rectangles are small" in said
    assert "apart" not in said


def test_track_warns_of_joints_that_start_on_one_another(footage, tmp_path, capsys):
    from toonmotion.io.track_json import load_joints, save_joints
    from toonmotion.rig.skeleton import Skeleton

    folder, _ = footage
    skeleton, sizes, _ = load_joints(folder / "joints.json")
    joints = list(skeleton.joints())
    shoulder = joints[0][2]
    joints[2] = (joints[2][0], joints[2][1], (shoulder[0] + 3, shoulder[1]))  # the hand on the shoulder
    save_joints(tmp_path / "folded.json", Skeleton.from_joints(joints), sizes)
    folded = tmp_path / "folded.json"
    assert _run("track", folder / "frames", "--joints", folded, "-o", tmp_path / "m.json") == 0
    assert "joints right_shoulder and right_hand start 3 px apart" in capsys.readouterr().err


@pytest.mark.parametrize("options", [[], ["--background", "#f6f0e2"], ["--free"], ["--frame-by-frame"],
                                     ["--both-ways"]])
def test_track_follows_a_cartoon_on_plain_paper(footage, tmp_path, options):
    """The waving arm drawn flat-coloured on paper (#f6f0e2): joints held to the figure read off
    the border, or off the given colour, or left free."""
    from toonmotion.capture.synthetic import limb_figure_frames
    from toonmotion.io.motion_json import load_motion
    from toonmotion.io.video import save_animation

    folder, truth = footage
    frames, _ = limb_figure_frames(truth, np.array([-1, 0, 1]), size=(320, 240), width=14, seed=4,
                                   style="flat")
    assert (frames[:, 0, 0] == (246, 240, 226)).all()
    opaque = np.concatenate([frames, np.full(frames.shape[:3] + (1,), 255, np.uint8)], axis=3)
    save_animation(tmp_path / "cartoon", iter(opaque), fps=12)
    out = tmp_path / "m.json"
    assert _run("track", tmp_path / "cartoon", "--joints", folder / "joints.json", "-o", out, *options) == 0
    assert np.hypot(*(load_motion(out).positions - truth).reshape(-1, 2).T).max() < 2.0


def test_track_flags_set_the_whole_sequence_pass_and_the_working_resolution(footage, tmp_path, monkeypatch):
    from toonmotion import api
    from toonmotion.capture.track_scale import WORKING_SIDE

    folder, _ = footage
    real, settings = api.track_footage, []

    def spy(*args, **kwargs):
        settings.append(kwargs["settings"])
        return real(*args, **kwargs)

    monkeypatch.setattr(api, "track_footage", spy)
    for flag in ([], ["--frame-by-frame"], ["--both-ways"], ["--full-resolution"]):
        assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", tmp_path / "m.json",
                    *flag) == 0
    assert [(s.best_path, s.both_ways) for s in settings] == [(True, False), (False, False), (True, True),
                                                              (True, False)]
    assert [s.fill_gaps for s in settings] == [True, True, True, True]
    # Large footage is halved to track by default; --full-resolution tracks it at its own size.
    assert [s.working_side for s in settings] == [WORKING_SIDE] * 3 + [None]


def test_track_says_how_many_frames_repeat_a_drawing(footage, tmp_path, capsys):
    from toonmotion.io.motion_json import load_motion

    folder, truth = footage
    twos = tmp_path / "twos"
    twos.mkdir()
    for t, name in enumerate(sorted((folder / "frames").iterdir())[:6]):
        for copy in (0, 1):  # each drawing held two frames
            (twos / f"f_{2 * t + copy:02d}.png").write_bytes(name.read_bytes())
    out = tmp_path / "m.json"
    assert _run("track", twos, "--joints", folder / "joints.json", "-o", out) == 0
    assert "tracked 3 joints through 12 frames (from frame 0); 6 frames repeat the frame before" in \
        capsys.readouterr().out
    held = np.arange(12) // 2
    assert np.hypot(*(load_motion(out).positions - truth[held]).reshape(-1, 2).T).max() < 2.0


def test_track_names_the_joints_that_matched_poorly_and_where(footage, tmp_path, capsys):
    """A hand covered in frames 6-9 is named, with where its longest poorly matched stretch starts,
    and how to put it right; with every joint seen, nothing is named."""
    folder, truth = footage
    covered = tmp_path / "covered"
    covered.mkdir()
    for t, name in enumerate(sorted((folder / "frames").iterdir())):
        frame = np.array(Image.open(name))
        if 6 <= t <= 9:
            x, y = np.round(truth[t, 2]).astype(int)
            frame[y - 20:y + 21, x - 20:x + 21, :3] = 255  # white paper over the hand
        Image.fromarray(frame).save(covered / name.name)
    out = tmp_path / "m.json"
    assert _run("track", covered, "--joints", folder / "joints.json", "-o", out) == 0
    said = capsys.readouterr().out.splitlines()
    named = "matched poorly most: right_hand in 33% of frames (longest from frame 6, 4 frames)"
    assert said[1].startswith(named)
    assert f"--joints {folder / 'joints.json'} --resume {out} --at FRAME --set NAME=X,Y" in said[1]
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", out) == 0
    assert len(capsys.readouterr().out.splitlines()) == 1


def test_track_corrections_resume_from_a_frame(footage, tmp_path):
    from toonmotion.io.motion_json import load_motion

    folder, truth = footage
    first = tmp_path / "m.json"
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", first) == 0
    x, y = truth[6, 2] + (0.5, -0.5)
    out = tmp_path / "fixed.json"
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", out, "--resume", first,
                "--at", "6", "--set", f"right_hand={x},{y}") == 0
    before, after = load_motion(first), load_motion(out)
    hand = after.skeleton.index("right_hand")
    np.testing.assert_allclose(after.positions[6, hand], (x, y), atol=1e-9)
    np.testing.assert_array_equal(after.positions[:6], before.positions[:6])


def test_track_suggests_joints_when_none_are_given(footage, tmp_path, capsys):
    folder, _ = footage
    assert _run("track", folder / "frames", "-o", tmp_path / "m.json") == 0
    assert "suggested" in capsys.readouterr().err
    assert (tmp_path / "m.joints.json").is_file()


def test_track_says_which_figure_it_suggested_joints_on(tmp_path, capsys):
    """Drawn on white inside a dark frame: the border says the paper is dark, and the message says
    so and how to give the colour; given white, the joints are suggested on the character alone."""
    import json

    from toonmotion.samples import sample_character_on

    picture = np.pad(sample_character_on("white", scale=0.5)[0], ((20, 20), (20, 20), (0, 0)),
                     constant_values=255)
    picture[:4] = picture[-4:] = picture[:, :4] = picture[:, -4:] = 20
    frames = [Image.fromarray(np.roll(picture, t, axis=1)) for t in range(3)]
    frames[0].save(tmp_path / "framed.gif", save_all=True, append_images=frames[1:], duration=80)
    assert _run("track", tmp_path / "framed.gif", "-o", tmp_path / "a.json") == 0
    said = capsys.readouterr().err
    assert "on the figure that differs from the border's colour #141414 (--background sets another)" in said
    assert _run("track", tmp_path / "framed.gif", "-o", tmp_path / "b.json", "--background", "white") == 0
    assert "on the figure drawn on #ffffff" in capsys.readouterr().err
    character = np.argwhere(picture[4:-4, 4:-4].min(axis=2) < 200) + 4
    (top, left), (bottom, right) = character.min(axis=0), character.max(axis=0)
    joints = json.loads((tmp_path / "b.joints.json").read_text())["joints"]
    assert all(left <= j["position"][0] <= right and top <= j["position"][1] <= bottom for j in joints)


def test_retarget_replays_a_tracked_motion_and_keeps_it_in_the_project(footage, posable, tmp_path):
    folder, _ = footage
    project = _copy_project(posable, tmp_path)
    motion = tmp_path / "wave.json"
    assert _run("track", folder / "frames", "--joints", folder / "joints.json", "-o", motion) == 0
    assert _run("retarget", motion, project, "-o", tmp_path / "r.gif", "--size", "42x60") == 0
    assert Image.open(tmp_path / "r.gif").n_frames == 12
    assert (project / "motions" / "wave.json").is_file()
    load_project(project)  # the project still loads


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["track", "{t}/bad.mp4", "--joints", "{f}/joints.json", "-o", "{t}/m.json"], "bad.mp4"),
        (["track", "{t}/mixed", "--joints", "{f}/joints.json", "-o", "{t}/m.json"], "size"),
        (["track", "{f}/frames", "--joints", "{t}/far.json", "-o", "{t}/m.json"], "inside"),
        (["track", "{f}/frames", "--joints", "{f}/joints.json", "-o", "{t}/m.txt"], "ending in .json"),
        (["track", "{f}/frames", "--joints", "{f}/joints.json", "-o", "{t}/m.json", "--at", "3"],
         "go together"),
        (["track", "{f}/frames", "--joints", "{f}/joints.json", "-o", "{t}/m.json", "--background",
          "transparent"], "the colour the footage is drawn on (white, black or #rrggbb), got 'transparent'"),
        (["track", "{f}/frames", "--joints", "{f}/joints.json", "-o", "{t}/m.json", "--background",
          "sky"], "the colour the footage is drawn on (white, black or #rrggbb), got 'sky'"),
        (["track", "{f}/frames", "--joints", "{f}/joints.json", "-o", "{t}/m.json", "--both-ways",
          "--frame-by-frame"], "--both-ways and --frame-by-frame do not go together"),
        (["retarget", "{t}/alien.json", "{p}/hero", "-o", "{t}/r.gif"], "no bone of the target matches"),
        (["retarget", "{t}/alien.json", "{p}/hero", "-o", "{t}/r.gif", "--map", "head"], "--map takes"),
    ],
)
def test_capture_errors_are_one_line_and_keep_the_old_motion(footage, posable, tmp_path, capsys, args,
                                                             message):
    from toonmotion.animate.motion import Motion
    from toonmotion.io.motion_json import save_motion
    from toonmotion.io.track_json import load_joints, save_joints
    from toonmotion.rig.skeleton import Skeleton

    folder, _ = footage
    (tmp_path / "bad.mp4").write_bytes(np.random.default_rng(0).bytes(5000))
    (tmp_path / "mixed").mkdir()
    Image.new("RGB", (40, 30)).save(tmp_path / "mixed" / "f_1.png")
    Image.new("RGB", (41, 30)).save(tmp_path / "mixed" / "f_2.png")
    skeleton, sizes, _ = load_joints(folder / "joints.json")
    save_joints(tmp_path / "far.json", skeleton, sizes * 0 + (400, 20))
    alien = Skeleton.from_joints([("a", None, (0, 0)), ("b", "a", (5, 0))])
    save_motion(tmp_path / "alien.json", Motion(alien, np.zeros((3, 2, 2)) + [[0, 0], [5, 0]], fps=12))
    (tmp_path / "m.json").write_text("previous motion")
    args = [a.format(p=posable, t=tmp_path, f=folder) for a in args]
    assert _run(*args) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("toonmotion: error: ") and "\n" not in err
    assert message in err
    assert (tmp_path / "m.json").read_text() == "previous motion"


def test_a_picture_over_the_limits_is_refused_before_the_pose_is_worked_out(posable, tmp_path, monkeypatch,
                                                                             capsys):
    from toonmotion import api

    def no_pose(*args, **kwargs):
        raise AssertionError("posed before the size was checked")

    monkeypatch.setattr(api, "pose_character", no_pose)
    monkeypatch.setattr(api, "animate_character", no_pose)
    project = posable / "hero"
    for argv in (["pose", project, posable / "pose.json", "-o", tmp_path / "p.png"],
                 ["animate", project, posable / "keys.json", "-o", tmp_path / "a.gif"]):
        assert _run(*argv, "--size", "16000x12000") == 2
        assert "over the limit canvas_pixels=64,000,000" in capsys.readouterr().err


def test_tune_tries_an_edit_under_the_deformation_options_pose_takes(posable, tmp_path, monkeypatch):
    import shutil

    from toonmotion import api

    seen, real = [], api.pose_character

    def spy(*args, **kwargs):
        seen.append(kwargs["settings"])
        return real(*args, **kwargs)

    monkeypatch.setattr(api, "pose_character", spy)
    shutil.copy(posable / "pose.json", tmp_path / "pose.json")
    assert _run("tune", posable / "hero", tmp_path / "pose.json", "--skinning", "weights", "--no-area",
                "--joint-width", "2") == 0
    assert [(s.skinning, s.preserve_area, s.joint_width) for s in seen] == [("weights", False, 2.0)]
