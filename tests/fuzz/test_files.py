"""Generated bad files through every command that reads them (see harness.py for the property)."""

from __future__ import annotations

import io
import json
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

from tests.fuzz.harness import TALLY, check, digest, run_cli
from tests.fuzz.mutate import spoiled_image, spoiled_json
from toonmotion import limits
from toonmotion.io.image import load_image
from toonmotion.io.motion_json import load_motion
from toonmotion.io.project import load_project


def _workspace(valid: Path) -> Path:
    """A scratch copy of the valid files, with an earlier output that a failing run must keep."""
    work = Path(tempfile.mkdtemp(prefix="fuzz-"))
    for name in (
        "hero.png",
        "hero.json",
        "P",
        "pose.json",
        "sketch.json",
        "contours.json",
        "model.json",
        "keys.json",
        "motion.json",
        "frames",
        "joints.json",
    ):
        source = valid / name
        (shutil.copytree if source.is_dir() else shutil.copy)(source, work / name)
    shutil.copytree(valid / "P", work / "OUT")
    shutil.copy(valid / "hero.png", work / "out.png")
    shutil.copy(valid / "motion.json", work / "out.json")
    return work


def _json_case(valid, data, kind, source, argv, outputs, valid_result=None):
    document = json.loads((valid / source).read_text())
    text, must_refuse, what = data.draw(spoiled_json(document), label="spoiled")
    work = _workspace(valid)
    try:
        target = work / source if not source.startswith("P/") else work / "P" / "project.json"
        target.write_text(text)
        kept = {work / o: digest(work / o) for o in outputs}
        outcome = run_cli(argv, work)
        check(
            outcome,
            kind=kind,
            must_refuse=must_refuse,
            kept=kept,
            valid=(lambda: valid_result(work)) if valid_result else None,
        )
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _png_ok(work, name="out.png"):
    picture = load_image(work / name)
    assert picture.shape[0] * picture.shape[1] <= limits.current().canvas_pixels


@given(data=st.data())
def test_skeleton_json(valid, data):
    _json_case(
        valid,
        data,
        "skeleton json",
        "hero.json",
        ["rig", "hero.png", "--skeleton", "hero.json", "-o", "OUT"],
        ["OUT"],
        lambda w: load_project(w / "OUT"),
    )


@given(data=st.data())
def test_pose_json(valid, data):
    _json_case(
        valid,
        data,
        "pose json",
        "pose.json",
        ["pose", "P", "pose.json", "-o", "out.png"],
        ["out.png"],
        _png_ok,
    )


@given(data=st.data())
def test_sketch_json(valid, data):
    _json_case(
        valid,
        data,
        "sketch json",
        "sketch.json",
        ["sketch", "P", "sketch.json", "-o", "out.json"],
        ["out.json"],
    )


@given(data=st.data())
def test_contours_json(valid, data):
    _json_case(
        valid,
        data,
        "contours json",
        "contours.json",
        ["keyshapes", "contours.json", "-o", "out.json"],
        ["out.json"],
    )


@given(data=st.data())
def test_keyshape_model_json(valid, data):
    _json_case(
        valid,
        data,
        "key-shape model json",
        "model.json",
        ["capture-contours", "model.json", "contours.json", "-o", "out.json"],
        ["out.json"],
    )


@given(data=st.data())
def test_keyframes_json(valid, data):
    _json_case(
        valid,
        data,
        "keyframes json",
        "keys.json",
        ["animate", "P", "keys.json", "-o", "frames_out", "--size", "40x60"],
        [],
        lambda w: Image.open(next((w / "frames_out").glob("*.png"))).verify(),
    )


@given(data=st.data())
def test_motion_json(valid, data):
    _json_case(
        valid,
        data,
        "motion json",
        "motion.json",
        ["filter", "motion.json", "-o", "out.json", "--strength", "1"],
        ["out.json"],
        lambda w: load_motion(w / "out.json"),
    )


@given(data=st.data())
def test_project_json(valid, data):
    _json_case(
        valid,
        data,
        "project json",
        "P/project.json",
        ["pose", "P", "pose.json", "-o", "out.png"],
        ["out.png", "P"],
        _png_ok,
    )


@given(data=st.data())
def test_track_joints_json(valid, data):
    _json_case(
        valid,
        data,
        "track joints json",
        "joints.json",
        ["track", "frames", "--joints", "joints.json", "-o", "out.json"],
        ["out.json"],
        lambda w: load_motion(w / "out.json"),
    )


@given(data=st.data(), role=st.sampled_from(["drawing", "mask", "frame"]))
def test_images(valid, data, role):
    # Spoil a picture of the size it stands in for: a frame must match the other frames.
    base = valid / ("frames/f_1.png" if role == "frame" else "hero.png")
    rgba = np.asarray(Image.open(base).convert("RGBA"))
    limit = limits.current().image_pixels
    payload, suffix, must_refuse, what = data.draw(spoiled_image(rgba, limit), label="image")
    work = _workspace(valid)
    try:
        name = work / f"spoiled{suffix}"
        name.write_bytes(payload)
        if role == "drawing":
            argv, outputs, result = (
                ["rig", name.name, "-o", "OUT"],
                ["OUT"],
                lambda: load_project(work / "OUT"),
            )
        elif role == "mask":
            argv, outputs, result = (
                ["rig", "hero.png", "--mask", name.name, "-o", "OUT"],
                ["OUT"],
                lambda: load_project(work / "OUT"),
            )
            must_refuse = must_refuse or "size" in what  # a mask must match the drawing's size
        else:
            must_refuse = must_refuse and "alpha" not in what  # footage frames drop their alpha
            frames = work / "frames"
            first = sorted(frames.iterdir())[1]
            first.unlink()
            shutil.move(name, frames / ("f_1" + suffix))
            argv, outputs, result = (
                ["track", "frames", "--joints", "joints.json", "-o", "out.json"],
                ["out.json"],
                lambda: load_motion(work / "out.json"),
            )
        kept = {work / o: digest(work / o) for o in outputs}
        check(run_cli(argv, work), kind=f"image as {role}", must_refuse=must_refuse, kept=kept, valid=result)
    finally:
        shutil.rmtree(work, ignore_errors=True)


@given(data=st.data())
def test_char_cfg_yaml(valid, data):
    import yaml

    document = yaml.safe_load((valid / "hero.yaml").read_text())
    text, must_refuse, what = data.draw(spoiled_json(document), label="spoiled")
    if "deep" in what:
        text = "[" * 100_000 + "]" * 100_000  # YAML flow style nests like JSON
    work = _workspace(valid)
    try:
        (work / "hero.yaml").write_text(text)  # JSON is YAML
        kept = {work / "OUT": digest(work / "OUT")}
        # YAML's own types are looser (a name may be a number, 05.0 is a number): only text that is
        # not YAML, or nests too deep, must be refused.
        must_refuse = "deep" in what or ("text" in what and not _is_yaml(text))
        check(
            run_cli(["rig", "hero.png", "--skeleton", "hero.yaml", "-o", "OUT"], work),
            kind="char_cfg yaml",
            must_refuse=must_refuse,
            kept=kept,
            valid=lambda: load_project(work / "OUT"),
        )
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _is_yaml(text: str) -> bool:
    import yaml

    try:
        yaml.safe_load(text)
    except yaml.YAMLError:
        return False
    return True


BVH = """HIERARCHY
ROOT Hips
{
 OFFSET 0 0 0
 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
 JOINT Chest
 {
  OFFSET 0 5 0
  CHANNELS 3 Zrotation Xrotation Yrotation
  JOINT Head
  {
   OFFSET 0 5 0
   CHANNELS 3 Zrotation Xrotation Yrotation
   End Site
   {
    OFFSET 0 2 0
   }
  }
 }
 JOINT Leg
 {
  OFFSET 1 -5 0
  CHANNELS 3 Zrotation Xrotation Yrotation
  End Site
  {
   OFFSET 0 -5 0
  }
 }
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 10 0 0 0 0 5 0 0 0 0 0 1 2 3
1 10 0 0 0 10 5 0 0 0 0 0 1 2 3
2 10 0 0 0 20 5 0 0 0 0 0 1 2 3
"""

BVH_TOKENS = [
    "1e308",
    "-1e308",
    "nan",
    "inf",
    "-1",
    "0",
    "1000000000000",
    str(2**70),
    "abc",
    "",
    "{",
    "}",
    "Frames:",
    "CHANNELS",
    "0.0",
    "1e-300",
    "ROOT",
    "JOINT",
]


def _number(word: str) -> bool:
    try:
        float(word)
    except ValueError:
        return False
    return True


def _finite(word: str) -> bool:
    return _number(word) and bool(np.isfinite(float(word)))


@given(data=st.data())
def test_bvh(tmp_path_factory, data):
    """BVH is read by the library (benchmarks, motion-capture tests): a clip or a MotionError."""
    from toonmotion.capture.bvh_kinematics import forward_kinematics
    from toonmotion.errors import ToonmotionError
    from toonmotion.io.bvh import load_bvh

    lines = BVH.splitlines()
    how = data.draw(st.sampled_from(["token", "token", "line", "repeat", "cut"]), label="how")
    must_refuse = False
    if how == "token":
        row = data.draw(st.integers(0, len(lines) - 1))
        words = lines[row].split() or [""]
        at = data.draw(st.integers(0, len(words) - 1))
        new = data.draw(st.sampled_from(BVH_TOKENS))
        # A number (an offset, a channel value, the frame count or time) replaced by a non-number.
        must_refuse = _number(words[at]) and not _finite(new)
        words[at] = new
        lines[row] = " ".join(words)
    elif how == "line":
        del lines[data.draw(st.integers(0, len(lines) - 1))]
    elif how == "repeat":
        row = data.draw(st.integers(0, len(lines) - 1))
        lines.insert(row, lines[row])
    text = "\n".join(lines)
    if how == "cut":
        text = text[: data.draw(st.integers(0, len(text)))]
    path = tmp_path_factory.mktemp("bvh") / "clip.bvh"
    path.write_text(text)
    must_refuse = must_refuse or (how == "cut" and "Frame Time" not in text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a library warning before the result is a failure too
            clip = load_bvh(path)
            positions = forward_kinematics(clip)
    except ToonmotionError as error:
        TALLY["bvh", "refused"] += 1
        assert "\n" not in str(error)
        return
    TALLY["bvh", "accepted"] += 1
    assert not must_refuse, "a BVH without a frame time or with a value that is no number was accepted"
    assert positions.shape == (len(clip.motion), len(clip.names), 3)
    assert np.all(np.isfinite(positions))


@given(data=st.data())
def test_footage_files(valid, data):
    """Non-videos, truncated GIFs and odd files given to track."""
    gif = io.BytesIO()
    frames = [Image.open(p).convert("RGB") for p in sorted((valid / "frames").iterdir())]
    frames[0].save(gif, format="GIF", save_all=True, append_images=frames[1:], duration=80)
    payloads = {
        "gif": gif.getvalue(),
        "text": b"this is not a video\n" * 10,
        "empty": b"",
        "zeros": bytes(5000),
        "mp4 header": b"\x00\x00\x00\x18ftypmp42\x00\x00\x00\x00mp42isom" + bytes(200),
    }
    kind = data.draw(st.sampled_from(sorted(payloads)), label="kind")
    payload = payloads[kind]
    cut = data.draw(st.integers(0, len(payload)), label="cut") if payload else 0
    suffix = data.draw(st.sampled_from([".gif", ".mp4", ".avi", ".webm", ".txt"]), label="suffix")
    body = payload[:cut] if kind == "gif" and data.draw(st.booleans(), label="cut it") else payload
    work = _workspace(valid)
    try:
        (work / f"clip{suffix}").write_bytes(body)
        kept = {work / "out.json": digest(work / "out.json")}
        must_refuse = kind != "gif"
        check(
            run_cli(["track", f"clip{suffix}", "--joints", "joints.json", "-o", "out.json"], work),
            kind="footage file",
            must_refuse=must_refuse,
            kept=kept,
            valid=lambda: load_motion(work / "out.json"),
        )
    finally:
        shutil.rmtree(work, ignore_errors=True)


@given(data=st.data())
def test_markers_json(tmp_path_factory, data):
    """Markers files are read by the library (as `toonmotion lift` reads them): markers or a
    one-line ProxyError; a spoil every reader must refuse is refused."""
    from toonmotion.errors import ProxyError
    from toonmotion.io.markers_json import load_markers, save_markers
    from toonmotion.proxy3d.markers import Markers

    folder = tmp_path_factory.mktemp("markers")
    valid = Markers(("hips", "knee", "foot"), np.arange(18.0).reshape(3, 3, 2) * 7.5, fps=12)
    save_markers(folder / "valid.json", valid)
    document = json.loads((folder / "valid.json").read_text())
    text, must_refuse, what = data.draw(spoiled_json(document), label="spoiled")
    (folder / "markers.json").write_text(text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            markers = load_markers(folder / "markers.json")
    except ProxyError as error:
        TALLY["markers json", "refused"] += 1
        assert "\n" not in str(error)
        return
    TALLY["markers json", "accepted"] += 1
    assert not must_refuse, f"accepted a markers file that should have been refused ({what})"
    assert markers.positions.shape == (markers.frame_count, len(markers.names), 2)
    assert np.all(np.isfinite(markers.positions))


@given(data=st.data())
def test_markers_csv(tmp_path_factory, data):
    """Markers CSV with a cell replaced, a row dropped or repeated, or the text cut: markers or a
    one-line ProxyError; a coordinate that is not a finite number is refused."""
    from toonmotion.errors import ProxyError
    from toonmotion.io.markers_json import load_markers

    rows = [["frame", "marker", "x", "y"]] + [[str(t), name, str(1.5 * t), str(-2.0 * t)]
                                              for t in range(3) for name in ("hips", "knee")]
    how = data.draw(st.sampled_from(["cell", "cell", "drop", "repeat", "cut"]), label="how")
    must_refuse = False
    if how == "cell":
        r, c = data.draw(st.integers(0, len(rows) - 1)), data.draw(st.integers(0, 3))
        new = data.draw(st.sampled_from(BVH_TOKENS + ["hips,knee", '"', "\u00e9"]))
        must_refuse = r > 0 and c >= 2 and not _finite(new)
        rows[r][c] = new
    elif how == "drop":
        del rows[data.draw(st.integers(0, len(rows) - 1))]
    elif how == "repeat":
        r = data.draw(st.integers(0, len(rows) - 1))
        rows.insert(r, list(rows[r]))
    text = "\n".join(",".join(row) for row in rows) + "\n"
    if how == "cut":
        text = text[: data.draw(st.integers(0, len(text)))]
    path = tmp_path_factory.mktemp("markers_csv") / "markers.csv"
    path.write_text(text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            markers = load_markers(path)
    except ProxyError as error:
        TALLY["markers csv", "refused"] += 1
        assert "\n" not in str(error)
        return
    TALLY["markers csv", "accepted"] += 1
    assert not must_refuse, "a markers CSV with a coordinate that is no finite number was accepted"
    assert np.all(np.isfinite(markers.positions))


@given(data=st.data())
def test_proxy_json(tmp_path_factory, data):
    """Proxy files are read by the library: a proxy or a one-line ProxyError; a spoil every reader
    must refuse is refused; whatever is accepted saves and loads back unchanged."""
    from tests.proxy3d.synthetic_proxy import synthetic_proxy
    from toonmotion.errors import ProxyError
    from toonmotion.io.proxy_json import load_proxy, save_proxy

    folder = tmp_path_factory.mktemp("proxy")
    valid = synthetic_proxy({"hips": None, "knee": "hips", "foot": "knee", "hat": None}, frames=2)
    save_proxy(folder / "valid.json", valid)
    document = json.loads((folder / "valid.json").read_text())
    text, must_refuse, what = data.draw(spoiled_json(document), label="spoiled")
    (folder / "proxy.json").write_text(text)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            proxy = load_proxy(folder / "proxy.json")
    except ProxyError as error:
        TALLY["proxy json", "refused"] += 1
        assert "\n" not in str(error)
        return
    TALLY["proxy json", "accepted"] += 1
    assert not must_refuse, f"accepted a proxy file that should have been refused ({what})"
    T, N, K = proxy.frame_count, len(proxy.names), len(proxy.limbs)
    assert proxy.points.shape == proxy.skeleton.shape == (T, N, 3)
    assert proxy.limb_rotations.shape == (T, K, 4) and proxy.rest.shape == (K, 3)
    assert np.all(np.isfinite(proxy.points)) and np.all(np.isfinite(proxy.skeleton))
    save_proxy(folder / "again.json", proxy)
    again = load_proxy(folder / "again.json")
    for field in ("points", "skeleton", "rest", "limb_rotations"):
        assert getattr(again, field).tobytes() == getattr(proxy, field).tobytes()
