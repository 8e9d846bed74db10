"""Tests for toonmotion.io.atomic: atomic writes."""

import os
import subprocess
import sys

import numpy as np
import pytest

from toonmotion.io.atomic import write_bytes, write_text


def test_a_new_file_gets_the_usual_permissions(tmp_path):
    umask = os.umask(0o022)
    try:
        write_text(tmp_path / "a.json", "{}")
    finally:
        os.umask(umask)
    assert (tmp_path / "a.json").stat().st_mode & 0o777 == 0o644


def test_a_replaced_file_keeps_its_permissions(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("old")
    path.chmod(0o640)
    write_text(path, "new")
    assert path.read_text() == "new"
    assert path.stat().st_mode & 0o777 == 0o640


def test_a_failed_write_leaves_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "a.json"
    path.write_text("old")
    from pathlib import Path

    def broken(self, data):
        raise OSError("disk full")

    monkeypatch.setattr(Path, "write_bytes", broken)
    with pytest.raises(OSError, match="disk full"):
        write_text(path, "new")
    monkeypatch.undo()
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]


def _dead_pid():
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_the_next_write_sweeps_temporaries_of_dead_writers_and_keeps_live_ones(tmp_path):
    dead = tmp_path / f".out.gif.{_dead_pid()}.abc123.tmp"
    dead.write_bytes(b"half a gif")
    live = tmp_path / f".out.gif.{os.getppid()}.def456.tmp"  # a running process: another writer
    live.write_bytes(b"being written")
    other = tmp_path / f".other.gif.{_dead_pid()}.abc123.tmp"  # another target's: not this write's
    other.write_bytes(b"x")
    write_bytes(tmp_path / "out.gif", b"GIF89a")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["out.gif", live.name, other.name])


def test_a_project_save_removes_assets_a_killed_save_left(tmp_path):
    from toonmotion.io.project import load_project, save_project
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    drawing, skeleton = sample_character(scale=0.3)
    hero = rig_drawing(drawing, skeleton=skeleton)
    save_project(tmp_path / "P", hero)
    stray = tmp_path / "P" / "texture-0123456789abcdef.png"  # written by a save killed before its JSON
    stray.write_bytes(b"\x89PNG")
    mine = tmp_path / "P" / "notes.png"  # the user's own file stays
    mine.write_bytes(b"\x89PNG")
    save_project(tmp_path / "P", hero)
    assert not stray.exists() and mine.exists()
    np.testing.assert_array_equal(load_project(tmp_path / "P").mesh.V, hero.mesh.V)
