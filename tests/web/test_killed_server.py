"""The editor server run as its own process: killed (kill -9) in the middle of its saves it leaves
the project loadable, with every edit it acknowledged, and the next save leaves no temporary file
behind; and its terminal shows no traceback for work that went well."""

from __future__ import annotations

import json
import random
import re
import signal
import subprocess
import sys
import time

import pytest
from websockets.sync.client import connect

from toonmotion import api
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.samples import sample_character

KILLS = 5


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path_factory.mktemp("killed-server") / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    return folder


def _start(project, stderr=subprocess.DEVNULL):
    child = subprocess.Popen(
        [sys.executable, "-m", "toonmotion.cli", "edit", str(project)],
        stdout=subprocess.PIPE,
        stderr=stderr,
        text=True,
    )
    line = child.stdout.readline()
    match = re.search(r"http://([^/]+)/\?token=(\S+)", line)
    assert match, f"the editor printed {line!r}"
    return child, f"ws://{match.group(1)}/ws?token={match.group(2)}"


def test_a_killed_server_keeps_every_acknowledged_edit(project):
    chance = random.Random("killed server")
    hand = api.load_project(project).skeleton.positions[7].tolist()
    for _ in range(KILLS):
        child, url = _start(project)
        acknowledged = before = len(api.load_project(project).edits)
        try:
            with connect(url, open_timeout=20) as socket:
                deadline = time.perf_counter() + chance.uniform(0.2, 0.8)
                by = 1
                while time.perf_counter() < deadline:  # edits as fast as the server saves them
                    socket.send(json.dumps({"type": "depth", "at": hand, "by": by}))
                    reply = json.loads(socket.recv())
                    assert reply["type"] == "regions", reply
                    acknowledged, by = reply["edits"], -by
                socket.send(json.dumps({"type": "depth", "at": hand, "by": by}))  # in flight when killed
                child.send_signal(signal.SIGKILL)
        finally:
            child.kill()
            child.wait()
        assert acknowledged > before  # edits were saved in this round
        saved = api.load_project(project)  # loadable: the old or the new edit, never half of one
        assert len(saved.edits) in (acknowledged, acknowledged + 1)
    child, url = _start(project)
    try:
        with connect(url, open_timeout=20) as socket:
            socket.send(json.dumps({"type": "undo"}))
            assert json.loads(socket.recv())["type"] == "undone"  # the history survived the kills too
    finally:
        child.kill()
        child.wait()
    assert [p.name for p in project.iterdir() if p.name.endswith(".tmp")] == []


def test_the_server_writes_a_video_without_printing_a_traceback(tmp_path):
    """ffmpeg started from the server's worker threads: the export is written, and the terminal
    shows no "Exception ignored in _after_fork" traceback (imageio-ffmpeg's preexec_fn)."""
    drawing, skeleton = sample_character(scale=0.5)
    folder = tmp_path / "hero"
    api.save_project(folder, rig_drawing(drawing, skeleton=skeleton))
    rest = api.load_project(folder).skeleton.positions
    child, url = _start(folder, stderr=subprocess.PIPE)
    try:
        with connect(url, open_timeout=20) as socket:
            for frame in (0, 4):
                socket.send(json.dumps({"type": "set_key", "frame": frame, "positions": rest.tolist()}))
                assert json.loads(socket.recv())["type"] == "keys"
            socket.send(json.dumps({"type": "export", "format": "mp4", "name": "clip"}))
            reply = json.loads(socket.recv())
            while reply["type"] == "progress":
                reply = json.loads(socket.recv())
            assert reply["type"] == "exported", reply
    finally:
        child.terminate()
        _, said = child.communicate(timeout=30)
    assert (folder / "exports" / "clip.mp4").stat().st_size > 0
    assert "Traceback" not in said and "Exception ignored" not in said, said
