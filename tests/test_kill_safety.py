"""Kill safety of every output the CLI writes (io/atomic.py, io/video.py, io/project.py).

For each kind of output the real ``toonmotion`` command runs in a child process 20 times and is
killed with SIGKILL at a random moment of its run. After every kill the output an earlier
successful run wrote must still be whole: the same bytes, or a complete new version. One last run
to the end must then leave no temporary file or folder and no orphaned project asset behind: the
temporaries of the killed runs are swept.

Start-up takes most of a run, so half the kills fall at a random time between 40% and 100% of a
run's length, and the other half a random time after the child is seen to start writing (a new
entry in the folder it writes to) but within the time its write took in a timed run. Each project
save gets a recoloured drawing (the same alpha, so the same mask and mesh, but a texture of its
own), so each save writes a new texture asset before ``project.json``: a save killed in between
leaves an asset nothing names, which a later save has to remove.
"""

from __future__ import annotations

import hashlib
import json
import os
import random
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from toonmotion.io.project import load_project

KILLS = 20
MIN_KILLED = 10
SIZE = (100, 100)  # animation frames, small to keep each run short
VERTICES = "400"  # a coarser mesh than the default 1500 rigs and animates faster
_ASSET = re.compile(r"(texture|mask)-([0-9a-f]{16})\.png")
_POLL = 0.0005


def _cli(*args: str | Path) -> list[str]:
    return [sys.executable, "-m", "toonmotion.cli", *map(str, args)]


def _start(args: list) -> subprocess.Popen:
    return subprocess.Popen(_cli(*args), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _run(*args: str | Path) -> float:
    """Run the command to the end; return how long it took in seconds."""
    start = time.perf_counter()
    subprocess.run(_cli(*args), check=True, capture_output=True)
    return time.perf_counter() - start


def _entries(folder: Path) -> set[str]:
    try:
        return set(os.listdir(folder))
    except FileNotFoundError:
        return set()


def _stamp(path: Path):
    try:
        stat = os.stat(path)
    except FileNotFoundError:
        return None
    return stat.st_ino, stat.st_mtime_ns


def _leftovers(folder: Path) -> set[str]:
    """Hidden ``*.tmp`` files or folders under ``folder``, and texture/mask assets beside a
    ``project.json`` that it does not name."""
    found = {str(p.relative_to(folder)) for p in folder.rglob(".*.tmp")}
    for project in folder.rglob("project.json"):
        data = json.loads(project.read_text(encoding="utf-8"))
        named = {data["texture"], data["mask"]}
        found |= {str(p.relative_to(folder)) for p in project.parent.iterdir()
                  if _ASSET.fullmatch(p.name) and p.name not in named}
    return found


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    folder = tmp_path_factory.mktemp("kill-safety")
    _run("sample", "-o", folder / "hero.png", "--skeleton", folder / "hero.json",
         "--keys", folder / "keys.json")
    _run("rig", folder / "hero.png", "--skeleton", folder / "hero.json", "-o", folder / "P",
         "--vertices", VERTICES)
    return folder


class Case:
    """One kind of output: its path, the folder its temporaries go in, the file whose replacement
    ends a write, and the command of run ``i`` (run 0 writes the output the kills must spare)."""

    def __init__(self, kind: str, data: Path, out: Path):
        self.kind, self.data, self.out = kind, data, out
        self.drawings: dict[Path, np.ndarray] = {}
        if kind == "gif":
            self.output = self.marker = out / "out.gif"
            self.folder = out
        elif kind == "png":
            self.output = self.folder = out / "frames"
            self.marker = self.output / "frame_00000.png"
        else:
            self.output = self.folder = out / "P"
            self.marker = self.output / "project.json"

    def command(self, i: int) -> list:
        if self.kind != "project":
            return ["animate", self.data / "P", self.data / "keys.json", "--size", f"{SIZE[0]}x{SIZE[1]}",
                    "-o", self.output]
        return ["rig", self._drawing(i), "--skeleton", self.data / "hero.json", "-o", self.output,
                "--vertices", VERTICES]

    def _drawing(self, i: int) -> Path:
        """The sample drawing recoloured by ``i``: another texture, the same alpha."""
        path = self.out / f"drawing-{i}.png"
        rgba = np.asarray(Image.open(self.data / "hero.png").convert("RGBA")).copy()
        rgba[..., :3] = (rgba[..., :3].astype(int) + 37 * i) % 256
        Image.fromarray(rgba).save(path)
        self.drawings[path] = rgba
        return path

    def snapshot(self):
        if self.kind == "gif":
            with Image.open(self.output) as image:
                return self.output.read_bytes(), image.n_frames
        if self.kind == "png":
            return {p.name: p.read_bytes() for p in self.output.iterdir() if not p.name.startswith(".")}
        return load_project(self.output)

    def check_intact(self, before) -> None:
        """The output is the earlier one byte for byte, or a complete valid new version of it."""
        if self.kind == "gif":
            data, frames = before
            if self.output.read_bytes() != data:
                with Image.open(self.output) as image:
                    assert image.n_frames == frames
                    for i in range(frames):
                        image.seek(i)
                        image.load()
                        assert image.size == SIZE
        elif self.kind == "png":
            assert _entries(self.output) - _leftovers(self.output) == set(before)
            for name, data in before.items():
                if (self.output / name).read_bytes() != data:
                    with Image.open(self.output / name) as image:
                        image.load()
                        assert image.size == SIZE
        else:
            character = load_project(self.output)
            np.testing.assert_array_equal(character.mesh.V, before.mesh.V)
            np.testing.assert_array_equal(character.mesh.F, before.mesh.F)
            np.testing.assert_array_equal(character.mask, before.mask)
            assert any(np.array_equal(character.texture, rgba) for rgba in self.drawings.values()), \
                "the project's texture is none of the drawings rigged"
            project = json.loads(self.marker.read_text(encoding="utf-8"))
            for key in ("texture", "mask"):  # an asset is named by its content's hash: check it is whole
                name = project[key]
                assert _ASSET.fullmatch(name).group(2) == \
                    hashlib.sha256((self.output / name).read_bytes()).hexdigest()[:16], f"{name} is damaged"

    def time_the_write(self, i: int) -> float:
        """Run ``i`` to the end, watching: how long from its first new entry in the folder to the
        replacement of the marker file (the write's last step)."""
        known, stamp = _entries(self.folder), _stamp(self.marker)
        start = time.perf_counter()
        child = _start(self.command(i))
        began = ended = None
        while child.poll() is None:
            now = time.perf_counter() - start
            if began is None and _entries(self.folder) - known:
                began = now
            if ended is None and _stamp(self.marker) != stamp:
                ended = now
            time.sleep(_POLL)
        assert child.returncode == 0
        assert began is not None and ended is not None and began <= ended, (began, ended)
        return ended - began

    def kill_in_the_write(self, i: int, delay: float) -> int:
        """Start run ``i``, wait until it adds an entry to the folder, then ``delay`` s, and kill it."""
        known = _entries(self.folder)
        child = _start(self.command(i))
        while child.poll() is None and not _entries(self.folder) - known:
            time.sleep(_POLL)
        time.sleep(delay)
        child.send_signal(signal.SIGKILL)  # does nothing if it has finished already
        return child.wait()

    def kill_at(self, i: int, moment: float) -> int:
        child = _start(self.command(i))
        time.sleep(moment)
        child.send_signal(signal.SIGKILL)
        return child.wait()


@pytest.mark.parametrize("kind", ["gif", "png", "project"])
def test_a_killed_write_keeps_the_old_output_and_leaves_nothing_after_the_next_run(data, tmp_path, kind):
    case = Case(kind, data, tmp_path)
    took = _run(*case.command(0))  # the output every killed run must leave whole
    before = case.snapshot()
    write = case.time_the_write(KILLS + 1)
    case.check_intact(before)
    assert _leftovers(case.folder) == set()

    chance = random.Random(f"kill safety {kind}")
    killed = interrupted = 0
    for i in range(1, KILLS + 1):
        earlier = _leftovers(case.folder)
        if i % 2:
            code = case.kill_at(i, chance.uniform(0.4, 1.0) * took)
        else:
            code = case.kill_in_the_write(i, chance.uniform(0.0, 1.0) * write)
        assert code in (0, -signal.SIGKILL), f"run {i} failed on its own with exit code {code}"
        killed += code == -signal.SIGKILL
        case.check_intact(before)
        interrupted += bool(_leftovers(case.folder) - earlier)  # it had a temporary out when killed
    print(f"\n{kind}: a run takes {took:.2f} s, its write {write * 1000:.0f} ms; {killed} of {KILLS} runs "
          f"killed, {interrupted} of them mid-write", end=" ")
    assert killed >= MIN_KILLED, f"only {killed} of {KILLS} runs were killed; the rest finished first"
    assert interrupted >= 1, "no kill landed inside a write; the test tests nothing"

    _run(*case.command(0))
    case.check_intact(before)
    assert _leftovers(case.folder) == set()
