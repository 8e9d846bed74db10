"""Key-shape files (io/keyshape_json.py) and the commands that read them: exact round trips,
one-line refusals, nothing saved overwritten by a failed run."""

import json

import numpy as np
import pytest

from tests.conftest import run_cli
from toonmotion import api
from toonmotion.errors import KeyShapeError
from toonmotion.io.image import save_png
from toonmotion.io.keyshape_json import (
    load_contours,
    load_keymotion,
    load_model,
    save_contours,
    save_keymotion,
    save_model,
)
from toonmotion.keyshape.model import warp


def test_files_round_trip_exactly(tmp_path, smooth_keys):
    save_contours(tmp_path / "keys.json", smooth_keys, fps=24, closed=True)
    keys, fps, closed = load_contours(tmp_path / "keys.json")
    np.testing.assert_array_equal(keys, smooth_keys)
    assert (fps, closed) == (24.0, True)
    space = api.keyshape_space(smooth_keys)
    save_model(tmp_path / "model.json", space)
    again = load_model(tmp_path / "model.json")
    for name in ("keys", "mean", "eigen"):
        np.testing.assert_array_equal(getattr(again, name), getattr(space, name))
    found = api.capture_contours(smooth_keys, space)
    save_keymotion(tmp_path / "motion.json", found, fps=24, space="extended")
    back, fps, kind = load_keymotion(tmp_path / "motion.json")
    np.testing.assert_array_equal(back.weights, found.weights)
    np.testing.assert_array_equal(back.affine, found.affine)



@pytest.mark.parametrize("count", [1, 2])
def test_one_key_or_keys_all_alike_make_a_model_of_affine_motion_alone(tmp_path, smooth_keys, count, capsys):
    """No eigen-shapes: the model saves, loads and captures a key moved affinely, exactly."""
    save_contours(tmp_path / "keys.json", [smooth_keys[0]] * count)
    assert run_cli("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json") == 0
    assert "0 eigen-shapes" in capsys.readouterr().out
    space = load_model(tmp_path / "model.json")
    assert space.eigen.shape == (0, *smooth_keys.shape[1:])
    np.testing.assert_allclose(space.mean, smooth_keys[0], atol=1e-9)
    A = np.array([[[1.0, 0.1, 30], [-0.1, 0.9, -12]], [[0.8, -0.3, 5], [0.3, 0.8, 7]]])
    frames = [warp(a, [1.0], smooth_keys[:1]) for a in A]
    save_contours(tmp_path / "clip.json", frames)
    for extra in ((), ("--keys",)):
        assert run_cli("capture-contours", tmp_path / "model.json", tmp_path / "clip.json", *extra,
                       "-o", tmp_path / "motion.json") == 0
        found, _, _ = load_keymotion(tmp_path / "motion.json")
        np.testing.assert_allclose(found.affine, A, atol=1e-6)
        assert found.error.max() < 1e-6

def test_contours_read_from_csv(tmp_path, smooth_keys):
    rows = ["contour,point,x,y"] + [f"{c},{p},{float(x)!r},{float(y)!r}"
                                    for c, shape in enumerate(smooth_keys) for p, (x, y) in enumerate(shape)]
    (tmp_path / "keys.csv").write_text("\n".join(rows) + "\n")
    np.testing.assert_array_equal(load_contours(tmp_path / "keys.csv")[0], smooth_keys)


def test_the_commands_build_a_model_and_capture_contours(tmp_path, smooth_keys, capsys):
    save_contours(tmp_path / "keys.json", smooth_keys)
    assert run_cli("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json",
                "--sheet", tmp_path / "sheet.png") == 0
    assert "eigen-shapes" in capsys.readouterr().out and (tmp_path / "sheet.png").stat().st_size > 0
    rng = np.random.default_rng(0)
    truth = [[0.2, 0.5, 0.3], [0.6, 0.0, 0.4], [1.1, -0.2, 0.1]]
    A = [[[1.0, 0.1, 30], [-0.1, 0.9, -12]]] * 3
    noise = rng.normal(0, 0.1, (3, *smooth_keys.shape[1:]))
    frames = [warp(a, w, smooth_keys) + e for a, w, e in zip(A, truth, noise, strict=True)]
    save_contours(tmp_path / "clip.json", frames, fps=12)
    assert run_cli("capture-contours", tmp_path / "model.json", tmp_path / "clip.json", "--keys",
                "-o", tmp_path / "motion.json") == 0
    found, fps, kind = load_keymotion(tmp_path / "motion.json")
    assert kind == "keys" and fps == 12
    np.testing.assert_allclose(found.weights, truth, atol=0.02)
    assert run_cli("capture-contours", tmp_path / "model.json", tmp_path / "clip.json",
                "-o", tmp_path / "extended.json") == 0
    assert load_keymotion(tmp_path / "extended.json")[0].error.max() < 0.6


@pytest.mark.parametrize(("content", "message"), [
    ({"format": "toonmotion.contours", "version": 1,
      "contours": [[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1]]]}, "at least 3"),
    ({"format": "toonmotion.contours", "version": 1,
      "contours": [[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 0], [1, 1], [0, 1]]]}, "same count"),
    ({"format": "toonmotion.contours", "version": 1, "contours": [[[0, 0], [1, 1], [2, 2]]]}, "one line"),
    ({"format": "toonmotion.contours", "version": 2, "contours": []}, "version 2"),
    ({"format": "toonmotion.pose", "version": 1}, "not a contours file"),
])
def test_bad_key_files_are_one_line_and_overwrite_nothing(tmp_path, capsys, content, message):
    (tmp_path / "keys.json").write_text(json.dumps(content))
    (tmp_path / "model.json").write_text("earlier")
    code = run_cli("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json")
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert (tmp_path / "model.json").read_text() == "earlier"


def test_a_csv_with_a_gap_is_refused(tmp_path):
    (tmp_path / "k.csv").write_text("contour,point,x,y\n0,0,0,0\n0,2,1,1\n")
    with pytest.raises(KeyShapeError, match="numbered 0, 1, 2"):
        load_contours(tmp_path / "k.csv")


def test_contours_captured_with_keys_retarget_onto_other_keys_and_onto_a_rigged_character(
        tmp_path, outlines, capsys):
    from toonmotion.io.keyshape_json import load_contours
    from toonmotion.io.motion_json import load_motion
    from toonmotion.io.pose_json import save_keyframes
    from toonmotion.rig.pose import Pose
    from toonmotion.samples import sample_rig

    save_contours(tmp_path / "keys.json", outlines)
    weights = [[1, 0, 0], [0.5, 0.5, 0], [0, 1, 0], [0, 0.5, 0.5], [0, 0, 1]]
    clip = [warp([[1, 0, 8 * t], [0, 1, 0]], w, outlines) for t, w in enumerate(weights)]
    save_contours(tmp_path / "clip.json", clip, fps=8)
    assert run_cli("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json") == 0
    assert run_cli("capture-contours", tmp_path / "model.json", tmp_path / "clip.json", "--keys",
                "-o", tmp_path / "motion.json") == 0
    save_contours(tmp_path / "other.json", outlines * 0.5)
    assert run_cli("retarget-keyshapes", tmp_path / "motion.json", tmp_path / "model.json",
                "--onto", tmp_path / "other.json", "-o", tmp_path / "out.json") == 0
    shapes, fps, _ = load_contours(tmp_path / "out.json")
    assert fps == 8
    np.testing.assert_allclose(shapes, np.array(clip) * 0.5, atol=1e-5)  # the keys at half size
    # The output character's picture, drawn in its first key's pixels, animated directly.
    picture = np.zeros((400, 300, 4), np.uint8)
    picture[..., :3], picture[..., 3] = (90, 160, 220), 255
    save_png(tmp_path / "other.png", picture)
    assert run_cli("retarget-keyshapes", tmp_path / "motion.json", tmp_path / "model.json",
                "--onto", tmp_path / "other.json", "--drawing", tmp_path / "other.png",
                "-o", tmp_path / "frames") == 0
    assert len(list((tmp_path / "frames").glob("*.png"))) == len(clip)
    assert run_cli("retarget-keyshapes", tmp_path / "motion.json", tmp_path / "model.json",
                "--project", tmp_path / "nowhere", "--poses", tmp_path / "poses.json",
                "--drawing", tmp_path / "other.png", "-o", tmp_path / "frames2") == 2
    assert "--drawing goes with --onto" in capsys.readouterr().err
    hero = sample_rig()
    from toonmotion import api as toon

    poses = [hero.skeleton.positions, toon.rotate_joint(hero, "right_elbow", -1.2).positions,
             toon.rotate_joint(hero, "left_shoulder", 0.9).positions]
    timeline = toon.set_key(hero.skeleton, None, 0, Pose(poses[0]))
    for frame, pose in enumerate(poses[1:], start=1):
        timeline = toon.set_key(hero.skeleton, timeline, frame, Pose(pose))
    save_keyframes(tmp_path / "poses.json", hero.skeleton, timeline)
    toon.save_project(tmp_path / "hero", hero)
    assert run_cli("retarget-keyshapes", tmp_path / "motion.json", tmp_path / "model.json",
                "--project", tmp_path / "hero", "--poses", tmp_path / "poses.json",
                "-o", tmp_path / "hero.json") == 0
    motion = load_motion(tmp_path / "hero.json")
    assert motion.positions.shape == (5, len(hero.skeleton), 2) and motion.fps == 8
    # Key 2's pose, moved as the input moved (16 px; the outline it is measured by is the input's
    # own, every 4th point of the same outline: the scale is 1 to within a pixel's worth).
    size = np.hypot(*np.ptp(hero.mesh.V[hero.mesh.boundary[0]], axis=0))
    shift = 16 * size / np.hypot(*np.ptp(outlines[0], axis=0))
    np.testing.assert_allclose(motion.positions[2] - [shift, 0], poses[1], atol=1e-4)
    # A foot held in place on every frame: exactly there, the whole figure moved by as much.
    assert run_cli("retarget-keyshapes", tmp_path / "motion.json", tmp_path / "model.json",
                   "--project", tmp_path / "hero", "--poses", tmp_path / "poses.json",
                   "--pin", "left_foot=100,280", "-o", tmp_path / "held.json") == 0
    held = load_motion(tmp_path / "held.json")
    foot = hero.skeleton.index("left_foot")
    np.testing.assert_allclose(held.positions[:, foot], np.tile([100.0, 280.0], (5, 1)), atol=1e-9)
    offset = held.positions - motion.positions
    np.testing.assert_allclose(offset, np.broadcast_to(offset[:, :1], offset.shape), atol=1e-9)
    assert run_cli("animate", tmp_path / "hero", tmp_path / "hero.json", "-o", tmp_path / "hero.gif") == 0
    assert "retargeted" in capsys.readouterr().out


def test_contours_of_any_count_direction_and_start_are_resampled_into_correspondence(tmp_path, outlines):
    from toonmotion.keyshape.model import resample_contour

    shape = outlines[0]
    a = resample_contour(shape, 50, start=shape[10])
    b = resample_contour(np.roll(shape, 17, axis=0)[::-1], 50, start=shape[10])  # other start, other way
    np.testing.assert_allclose(a, b, atol=1e-9)
    np.testing.assert_allclose(a[0], shape[10], atol=1e-9)
    # A file of contours with different point counts: refused as they are, read with --points.
    save_contours(tmp_path / "ragged.json", [outlines[0]], closed=True)
    ragged = json.loads((tmp_path / "ragged.json").read_text())
    ragged["contours"] = [outlines[0].tolist(), outlines[1][::2].tolist(), outlines[2][::-1].tolist()]
    (tmp_path / "ragged.json").write_text(json.dumps(ragged))
    assert run_cli("keyshapes", tmp_path / "ragged.json", "-o", tmp_path / "m.json") == 2
    x, y = outlines[0][0]
    assert run_cli("keyshapes", tmp_path / "ragged.json", "-o", tmp_path / "m.json", "--points", "60",
                "--start", f"{x},{y}") == 0
    assert load_model(tmp_path / "m.json").keys.shape == (3, 60, 2)


def test_an_svg_files_shapes_are_contours_resampled_into_correspondence(tmp_path, capsys):
    svg = """<svg xmlns="http://www.w3.org/2000/svg" width="200" height="200">
      <path d="M 60,100 C 60,40 140,40 140,100 C 140,160 60,160 60,100 Z"/>
      <g transform="translate(10, 0)"><ellipse cx="90" cy="100" rx="50" ry="30"/></g>
      <polygon points="50,70 150,70 150,130 50,130"/>
    </svg>"""
    (tmp_path / "keys.svg").write_text(svg)
    keys, _, closed = load_contours(tmp_path / "keys.svg", points=40, start=(100, 0))
    assert keys.shape == (3, 40, 2) and closed
    assert abs(keys[1][:, 0].mean() - 100) < 0.01  # the group's transform (10 px) applied
    np.testing.assert_allclose(keys[2][0], (100, 70), atol=1e-6)  # starts nearest (100, 0)
    np.testing.assert_allclose(keys[2].min(axis=0), (50, 70), atol=1e-6)
    assert run_cli("keyshapes", tmp_path / "keys.svg", "-o", tmp_path / "model.json") == 0
    assert load_model(tmp_path / "model.json").keys.shape == (3, 100, 2)  # 100 points by default
    (tmp_path / "bad.svg").write_text("<svg><not closed")
    assert run_cli("keyshapes", tmp_path / "bad.svg", "-o", tmp_path / "model.json") == 2
    assert "cannot read bad.svg as SVG" in capsys.readouterr().err
