"""An editor server killed (kill -9) in the middle of its saves leaves the project loadable, with
every edit it acknowledged, and the next save leaves no temporary file behind."""

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


def _start(project):
    child = subprocess.Popen(
        [sys.executable, "-m", "toonmotion.cli", "edit", str(project)],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
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
