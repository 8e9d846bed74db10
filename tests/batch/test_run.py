"""Running a job on a local Dask cluster: outputs, reruns, changes, bad inputs (issue 46)."""

import json

import pytest

from tests.batch.jobs import check_outputs, write_job
from toonmotion.batch import run_batch
from toonmotion.cli.app import main


@pytest.fixture(scope="module")
def cluster():
    from distributed import LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as running:
        yield running.scheduler_address


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    """The job run once through the CLI on its own local cluster of two workers."""
    folder = tmp_path_factory.mktemp("job")
    job = write_job(folder)
    with pytest.raises(SystemExit) as done:
        main(["batch", str(job), "--workers", "2"])
    assert done.value.code == 0
    return job


def _mtimes(folder):
    return {p.name: p.stat().st_mtime_ns for p in folder.iterdir() if p.suffix in (".gif", ".glb")}


def test_every_output_is_written_valid_and_recorded(finished):
    out = finished.parent / "job_outputs"
    check_outputs(out)
    report = json.loads((out / "report.json").read_text())
    assert (report["done"], report["skipped"], report["failed"]) == (4, 0, 0)
    manifest = json.loads((out / "manifest.json").read_text())
    assert len(manifest["tasks"]) == 4
    html = (out / "report.html").read_text()
    assert html.count('<img src="thumbs/') == 4 * 4
    assert all((out / t).is_file() for task in report["tasks"] for t in task["thumbnails"])


def test_a_rerun_recomputes_nothing(finished, cluster):
    out = finished.parent / "job_outputs"
    before = _mtimes(out)
    report = run_batch(finished, scheduler=cluster)
    assert (report.count("skipped"), report.count("done")) == (4, 0)
    assert _mtimes(out) == before


def test_a_changed_input_recomputes_only_its_tasks(finished, cluster, tmp_path):
    job = write_job(tmp_path)
    first = run_batch(job, scheduler=cluster)
    assert first.count("done") == 4
    keys = json.loads((tmp_path / "keys.json").read_text())
    keys["keys"][1]["frame"] = 3  # a shorter still: only the 'still' tasks change
    (tmp_path / "keys.json").write_text(json.dumps(keys))
    before = _mtimes(tmp_path / "job_outputs")
    again = run_batch(job, scheduler=cluster)
    redone = {(r.character, r.motion) for r in again.results if r.status == "done"}
    assert redone == {("char1", "still"), ("char4", "still")}
    assert again.count("skipped") == 2
    after = _mtimes(tmp_path / "job_outputs")
    assert {n for n in after if after[n] != before[n]} == {f"{c}-still.{e}" for c in ("char1", "char4")
                                                             for e in ("gif", "glb")}
    # a damaged output is redone too
    (tmp_path / "job_outputs" / "char1-walk.glb").write_bytes(b"broken")
    third = run_batch(job, scheduler=cluster)
    assert [(r.character, r.motion) for r in third.results if r.status == "done"] == [("char1", "walk")]
    # so is one damaged in place, at the same size (its modification time gives it away), and the
    # outputs of a manifest without sizes and times (its first version) are checked by their hashes
    gif = tmp_path / "job_outputs" / "char4-walk.gif"
    gif.write_bytes(bytes(gif.stat().st_size))
    manifest = json.loads((tmp_path / "job_outputs" / "manifest.json").read_text())
    for entry in manifest["tasks"].values():
        if entry["character"] == "char1":
            del entry["stamps"]
    (tmp_path / "job_outputs" / "manifest.json").write_text(json.dumps(manifest))
    fourth = run_batch(job, scheduler=cluster)
    assert [(r.character, r.motion) for r in fourth.results if r.status == "done"] == [("char4", "walk")]


def test_a_bad_input_fails_only_its_tasks_with_one_line(cluster, tmp_path):
    job = write_job(tmp_path)
    (tmp_path / "broken.png").write_bytes(b"\x89PNG\r\n\x1a\nnot really")
    (tmp_path / "alien.json").write_text(json.dumps({
        "format": "toonmotion.motion", "version": 1, "fps": 12,
        "joints": [{"name": "tentacle", "parent": None, "position": [0, 0]},
                   {"name": "sucker", "parent": "tentacle", "position": [10, 0]}],
        "frames": [[[0, 0], [10, 0]], [[0, 0], [0, 10]]]}))
    text = job.read_text()
    pairs = '[["char1", "still"], ["broken", "still"], ["char1", "alien"], ["char4", "walk"]]'
    job.write_text(f"pairs = {pairs}\n"
                   + text + '\n[[character]]\nname = "broken"\ndrawing = "broken.png"\n'
                   '\n[[motion]]\nname = "alien"\nmotion = "alien.json"\n')
    report = run_batch(job, scheduler=cluster)
    status = {(r.character, r.motion): r for r in report.results}
    assert [k for k, r in status.items() if r.status == "done"] == [("char1", "still"), ("char4", "walk")]
    broken, alien = status["broken", "still"], status["char1", "alien"]
    assert broken.status == alien.status == "failed"
    assert "broken.png" in broken.message and str(tmp_path) in broken.message and "\n" not in broken.message
    assert "toonmotion-batch-" not in broken.message  # the worker's temporary name is not shown
    assert "no bone of the target matches" in alien.message and "\n" not in alien.message
    saved = json.loads((tmp_path / "job_outputs" / "report.json").read_text())
    assert saved["failed"] == 2 and {t["message"] for t in saved["tasks"] if t["status"] == "failed"} == {
        broken.message, alien.message}
    assert "no bone of the target matches" in (tmp_path / "job_outputs" / "report.html").read_text()
    check_outputs(tmp_path / "job_outputs", names=("char1",), motions=("still",))
