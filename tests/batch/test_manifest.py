"""The batch manifest's journal: a task recorded per line as it finishes, merged at the end."""

import json

import pytest

from toonmotion.errors import BatchError
from toonmotion.io.batch_manifest import (
    ManifestEntry,
    journal_path,
    load_manifest,
    record_task,
    save_manifest,
)


def _entry(n):
    return ManifestEntry(character=f"c{n}", motion="walk", output="", frames=n,
                         files={f"c{n}-walk.gif": f"{n:064x}"})


def test_a_stopped_run_s_journal_is_read_and_its_cut_line_redone(tmp_path):
    path = tmp_path / "manifest.json"
    save_manifest(path, {f"{1:064x}": _entry(1)})  # an earlier run's
    for n in (2, 3):
        record_task(path, f"{n:064x}", _entry(n))
    size = journal_path(path).stat().st_size
    with open(journal_path(path), "a") as journal:  # the stop came mid-write
        journal.write(json.dumps({"key": f"{4:064x}", **_entry(4).model_dump()})[:40])
    tasks = load_manifest(path)
    assert sorted(e.frames for e in tasks.values()) == [1, 2, 3]  # task 4 is done again
    assert journal_path(path).stat().st_size > size
    save_manifest(path, tasks)
    assert not journal_path(path).exists()
    assert load_manifest(path) == tasks
    assert sorted(json.loads(path.read_text())["tasks"]) == [f"{n:064x}" for n in (1, 2, 3)]


def test_recording_a_task_costs_one_line_whatever_the_manifest_holds(tmp_path):
    path = tmp_path / "manifest.json"
    save_manifest(path, {f"{n:064x}": _entry(n) for n in range(1, 2001)})
    before = path.stat().st_size
    record_task(path, f"{5000:064x}", _entry(5000))
    assert path.stat().st_size == before  # the manifest is not rewritten
    assert len(journal_path(path).read_text().splitlines()) == 1
    assert len(load_manifest(path)) == 2001


def test_a_damaged_journal_line_before_the_last_is_refused_in_one_line(tmp_path):
    path = tmp_path / "manifest.json"
    record_task(path, f"{1:064x}", _entry(1))
    with open(journal_path(path), "a") as journal:
        journal.write('{"key": "not a key"}\n')
    record_task(path, f"{2:064x}", _entry(2))
    with pytest.raises(BatchError, match=r"line 2 is not a finished task's record") as refused:
        load_manifest(path)
    assert "\n" not in str(refused.value)
