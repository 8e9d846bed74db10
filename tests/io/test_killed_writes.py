"""A write killed at a random moment (kill -9) leaves the old output intact, and the next
successful run leaves no temporary file behind (io/atomic.py, io/video.py, io/project.py).

Each case runs the real command in a child process 20 times, kills it at a random moment
between its start-up and its end (a run that ends first sets how long the next are taken to
last), checks the earlier output, then runs it once to the end.
"""

from __future__ import annotations

import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from toonmotion import api
from toonmotion.animate.timeline import Keyframe, make_timeline
from toonmotion.io.image import save_png
from toonmotion.io.pose_json import save_keyframes
from toonmotion.io.project import load_project
from toonmotion.io.skeleton_json import save_skeleton_json
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.samples import sample_character

KILLS = 20


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    folder = tmp_path_factory.mktemp("killed")
    rgba, skeleton = sample_character(scale=0.5)
    save_png(folder / "hero.png", rgba)
    save_skeleton_json(folder / "hero.json", skeleton, (rgba.shape[1], rgba.shape[0]))
    bent = Pose(rotate_about(skeleton, skeleton.positions, "right_shoulder", 1.0))
    keys = [Keyframe(0, Pose(skeleton.positions)), Keyframe(12, bent), Keyframe(24, Pose(skeleton.positions))]
    save_keyframes(folder / "keys.json", skeleton, make_timeline(skeleton, keys, fps=12.0))
    api.save_project(folder / "P", api.rig_image(rgba, skeleton=skeleton))
    return folder


def _command(*args: str) -> list[str]:
    return [sys.executable, "-m", "toonmotion.cli", *args]


def _leftovers(folder: Path) -> list[str]:
    """Temporary files or folders, and project assets the project does not name."""
    found = [p.name for p in folder.rglob("*") if p.name.startswith(".") and p.name.endswith(".tmp")]
    project = folder / "project.json"
    if project.is_file():
        named = set(project.read_text().split('"'))
        found += [p.name for p in folder.glob("*.png") if p.name not in named]
    return found


def _gif_frames(path: Path) -> int:
    with Image.open(path) as image:
        return image.n_frames


CASES = {
    "gif": (["animate", "P", "keys.json", "-o", "out.gif", "--size", "200x280"], "out.gif"),
    "png folder": (["animate", "P", "keys.json", "-o", "frames", "--size", "200x280"], "frames"),
    "project": (["rig", "hero.png", "--skeleton", "hero.json", "-o", "P2"], "P2"),
}


def _intact(kind: str, output: Path, before) -> None:
    """The output is the complete earlier one (or a complete new one: same content, here)."""
    if kind == "gif":
        assert _gif_frames(output) == before
    elif kind == "png folder":
        frames = sorted(output.glob("frame_*.png"))
        assert len(frames) == before
        for frame in frames:
            assert np.asarray(Image.open(frame)).shape[:2] == (280, 200)
    else:
        np.testing.assert_array_equal(load_project(output).mesh.V, before)


@pytest.mark.parametrize("kind", sorted(CASES))
def test_a_killed_write_keeps_the_old_output_and_the_next_run_sweeps_its_temporaries(folder, kind):
    args, name = CASES[kind]
    output = folder / name
    start = time.perf_counter()
    subprocess.run(_command(*args), cwd=folder, check=True, capture_output=True)
    took = time.perf_counter() - start
    before = {"gif": lambda: _gif_frames(output), "png folder": lambda: len(list(output.glob("*.png"))),
              "project": lambda: load_project(output).mesh.V}[kind]()
    chance = random.Random(f"kill {kind}")
    killed = 0
    for _ in range(KILLS):
        began = time.perf_counter()
        child = subprocess.Popen(_command(*args), cwd=folder, stdout=subprocess.DEVNULL,
                                 stderr=subprocess.DEVNULL)
        try:
            child.wait(timeout=chance.uniform(0.3, 1.0) * took)
            # It finished first: runs are quicker now than when timed (the machine was busier);
            # aim the next kills by this run.
            took = time.perf_counter() - began
        except subprocess.TimeoutExpired:
            child.send_signal(signal.SIGKILL)
            killed += child.wait() == -signal.SIGKILL
        _intact(kind, output, before)
    assert killed >= KILLS // 2, f"only {killed} of {KILLS} runs were killed before they finished"
    subprocess.run(_command(*args), cwd=folder, check=True, capture_output=True)
    _intact(kind, output, before)
    assert _leftovers(output if output.is_dir() else folder) == []
