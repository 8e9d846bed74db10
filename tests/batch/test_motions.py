"""Batch jobs with key-shape motions, folders of clips and deformation options (issue 46): each
output is the same as the library's own calls make it."""

import json
import shutil

import numpy as np
import pytest
from PIL import Image, ImageSequence

from tests.conftest import SHARED_DATA, _require
from toonmotion import api
from toonmotion.batch import run_batch
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import BatchError
from toonmotion.io.batch_job import load_job
from toonmotion.io.keyshape_json import load_keymotion, load_model, save_contours
from toonmotion.io.pose_json import load_keyframes, save_keyframes
from toonmotion.keyshape.model import warp
from toonmotion.rig.pose import Pose
from toonmotion.samples import sample_rig

SIZE = 96


def _frames(path):
    with Image.open(path) as gif:
        return [np.asarray(f.convert("RGBA")) for f in ImageSequence.Iterator(gif)]


@pytest.fixture(scope="module")
def keyshaped(tmp_path_factory):
    """A cartoon captured by key-shapes (the sample's outline in three poses, moving along), the
    sample character as a project, and its key poses: one per key."""
    folder = tmp_path_factory.mktemp("keyshapes")
    hero = sample_rig()
    loop = hero.mesh.boundary[0][::4]
    poses = [hero.skeleton.positions, api.rotate_joint(hero, "right_elbow", -1.2).positions,
             api.rotate_joint(hero, "left_shoulder", 0.9).positions]
    outlines = np.stack([api.pose_character(hero, Pose(p)).deformation.U[loop] for p in poses])
    save_contours(folder / "keys.json", outlines)
    weights = [[1, 0, 0], [0.5, 0.5, 0], [0, 1, 0], [0, 0.5, 0.5], [0, 0, 1]]
    save_contours(folder / "clip.json", [warp([[1, 0, 8 * t], [0, 1, 0]], w, outlines)
                                         for t, w in enumerate(weights)], fps=8)
    from toonmotion.cli.app import main

    for argv in (["keyshapes", "keys.json", "-o", "model.json"],
                 ["capture-contours", "model.json", "clip.json", "--keys", "-o", "hop.json"]):
        with pytest.raises(SystemExit) as done:
            main([*argv[:1], *(str(folder / a) if a.endswith(".json") else a for a in argv[1:])])
        assert done.value.code == 0
    timeline = api.set_key(hero.skeleton, None, 0, Pose(poses[0]))
    for frame, pose in enumerate(poses[1:], start=1):
        timeline = api.set_key(hero.skeleton, timeline, frame, Pose(pose))
    save_keyframes(folder / "hero_poses.json", hero.skeleton, timeline)
    api.save_project(folder / "hero", hero)
    return folder


def test_a_key_shape_motion_is_replayed_on_each_characters_key_poses(keyshaped):
    job = keyshaped / "job.toml"
    job.write_text(f"""
[[character]]
name = "hero"
project = "hero"

[[motion]]
name = "hop"
keyshapes = "hop.json"
model = "model.json"
poses = {{ hero = "hero_poses.json" }}

[output]
formats = ["gif"]
size = [{SIZE}, {SIZE}]
deform = {{ stage_two = false }}
""")
    report = run_batch(job, workers=1)
    assert report.count("done") == 1, [r.message for r in report.results]
    # The same through the library: retarget-keyshapes --project, then animate, as the CLI does.
    hero = api.load_project(keyshaped / "hero")
    captured, fps, _ = load_keymotion(keyshaped / "hop.json")
    timeline = load_keyframes(keyshaped / "hero_poses.json", hero.skeleton)
    keys = load_model(keyshaped / "model.json").keys
    motion = api.retarget_keyposes(captured, keys, hero.skeleton, timeline, fps=fps,
                                   reference=hero.mesh.V[hero.mesh.boundary[0]])
    settings = DeformSettings(stage_two=False)
    animation = api.animate_character(hero, motion, settings=settings, fps=fps)
    api.export_animation(keyshaped / "library.gif", hero, animation, size=(SIZE, SIZE), settings=settings)
    ours, theirs = _frames(report.folder / "hero-hop.gif"), _frames(keyshaped / "library.gif")
    assert len(ours) == len(theirs) == 5
    for a, b in zip(ours, theirs, strict=True):
        np.testing.assert_array_equal(a, b)
    # The deformation options were used: with stage two the frames differ.
    api.export_animation(keyshaped / "two.gif", hero, api.animate_character(hero, motion, fps=fps),
                         size=(SIZE, SIZE))
    assert any((a != b).any() for a, b in zip(ours, _frames(keyshaped / "two.gif"), strict=True))


def test_a_key_shape_motion_without_a_characters_poses_is_refused_at_once(keyshaped, tmp_path):
    job = keyshaped / "job_missing.toml"
    job.write_text("""
[[character]]
name = "hero"
project = "hero"
[[character]]
name = "villain"
project = "hero"
[[motion]]
name = "hop"
keyshapes = "hop.json"
model = "model.json"
poses = { hero = "hero_poses.json" }
[output]
formats = ["gif"]
""")
    with pytest.raises(BatchError, match="no key poses for character 'villain'"):
        load_job(job)
    text = job.read_text()
    job.write_text('pairs = [["hero", "hop"]]\n' + text)
    assert load_job(job).pairs == (("hero", "hop"),)
    job.write_text(text.replace('model = "model.json"\n', ""))
    with pytest.raises(BatchError, match="needs its 'model'"):
        load_job(job)
    job.write_text(text.replace("hero_poses.json", "nowhere.json"))
    with pytest.raises(BatchError, match=r"motion\[0\]\.poses\.hero: no such file"):
        load_job(job)


def test_a_folder_of_clips_is_one_motion_per_clip(tmp_path):
    mocap = _require(SHARED_DATA / "mocap")
    clips = tmp_path / "clips"
    clips.mkdir()
    for name in ("cmu_07_01_walk.bvh", "cmu_02_03_run.bvh"):
        shutil.copy(mocap / name, clips / name.replace("cmu_", "a b "))  # a space is not kept in a name
    (clips / "notes.txt").write_text("not a clip")
    job = tmp_path / "job.toml"
    job.write_text('pairs = [["hero", "mocap"]]\n[[character]]\nname = "hero"\ndrawing = "hero.png"\n'
                   '[[motion]]\nname = "mocap"\nbvh = "clips"\nview = [90, 0]\n[output]\nformats = ["gif"]\n')
    (tmp_path / "hero.png").write_bytes(b"")
    loaded = load_job(job)
    assert [m.name for m in loaded.motions] == ["mocap-a_b_02_03_run", "mocap-a_b_07_01_walk"]
    assert all(m.view == (90, 0) for m in loaded.motions)
    assert loaded.pairs == (("hero", "mocap-a_b_02_03_run"), ("hero", "mocap-a_b_07_01_walk"))
    for f in clips.glob("*.bvh"):
        f.unlink()
    with pytest.raises(BatchError, match="holds no .bvh file"):
        load_job(job)


@pytest.mark.parametrize("deform, message", [
    ("{ joint_width = -1 }", "greater than or equal to 0"),
    ('{ skinning = "bones" }', "one-bone"),
    ("{ weights = [0, 0, 0] }", "weights"),
])
def test_deformation_options_out_of_range_are_refused_before_anything_runs(tmp_path, deform, message):
    job = tmp_path / "job.toml"
    (tmp_path / "hero.png").write_bytes(b"")
    (tmp_path / "keys.json").write_text(json.dumps({"format": "toonmotion.keyframes", "version": 1,
                                                    "keys": [{"frame": 0, "rest": True}]}))
    job.write_text('[[character]]\nname = "hero"\ndrawing = "hero.png"\n[[motion]]\nname = "still"\n'
                   f'keys = "keys.json"\n[output]\nformats = ["gif"]\ndeform = {deform}\n')
    with pytest.raises(BatchError, match=message) as error:
        run_batch(job, workers=1)
    assert "\n" not in str(error.value) and not (tmp_path / "job_outputs").exists()
