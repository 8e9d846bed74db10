"""Key-shape files (io/keyshape_json.py) and the commands that read them: exact round trips,
one-line refusals, nothing saved overwritten by a failed run."""

import json

import numpy as np
import pytest

from toonmotion import api
from toonmotion.cli import main
from toonmotion.errors import KeyShapeError
from toonmotion.io.keyshape_json import (
    load_contours,
    load_keymotion,
    load_model,
    save_contours,
    save_keymotion,
    save_model,
)
from toonmotion.keyshape.model import warp


def _run(*argv):
    try:
        main([str(a) for a in argv])
    except SystemExit as stop:
        return 0 if stop.code is None else stop.code
    return 0


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


def test_contours_read_from_csv(tmp_path, smooth_keys):
    rows = ["contour,point,x,y"] + [f"{c},{p},{float(x)!r},{float(y)!r}"
                                    for c, shape in enumerate(smooth_keys) for p, (x, y) in enumerate(shape)]
    (tmp_path / "keys.csv").write_text("\n".join(rows) + "\n")
    np.testing.assert_array_equal(load_contours(tmp_path / "keys.csv")[0], smooth_keys)


def test_the_commands_build_a_model_and_capture_contours(tmp_path, smooth_keys, capsys):
    save_contours(tmp_path / "keys.json", smooth_keys)
    assert _run("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json",
                "--sheet", tmp_path / "sheet.png") == 0
    assert "eigen-shapes" in capsys.readouterr().out and (tmp_path / "sheet.png").stat().st_size > 0
    rng = np.random.default_rng(0)
    truth = [[0.2, 0.5, 0.3], [0.6, 0.0, 0.4], [1.1, -0.2, 0.1]]
    A = [[[1.0, 0.1, 30], [-0.1, 0.9, -12]]] * 3
    noise = rng.normal(0, 0.1, (3, *smooth_keys.shape[1:]))
    frames = [warp(a, w, smooth_keys) + e for a, w, e in zip(A, truth, noise, strict=True)]
    save_contours(tmp_path / "clip.json", frames, fps=12)
    assert _run("capture-contours", tmp_path / "model.json", tmp_path / "clip.json", "--keys",
                "-o", tmp_path / "motion.json") == 0
    found, fps, kind = load_keymotion(tmp_path / "motion.json")
    assert kind == "keys" and fps == 12
    np.testing.assert_allclose(found.weights, truth, atol=0.02)
    assert _run("capture-contours", tmp_path / "model.json", tmp_path / "clip.json",
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
    code = _run("keyshapes", tmp_path / "keys.json", "-o", tmp_path / "model.json")
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
    assert (tmp_path / "model.json").read_text() == "earlier"


def test_a_csv_with_a_gap_is_refused(tmp_path):
    (tmp_path / "k.csv").write_text("contour,point,x,y\n0,0,0,0\n0,2,1,1\n")
    with pytest.raises(KeyShapeError, match="numbered 0, 1, 2"):
        load_contours(tmp_path / "k.csv")
