"""Running a batch job on Dask: :func:`run_batch`, the call behind ``toonmotion batch``.

The client (this process) reads the job and every input (:mod:`toonmotion.batch.plan`), skips
the tasks the output folder's manifest shows finished and intact, and submits the rest: one
task per character that rigs it, one per motion that reads it, and one per output whose
inputs are those two futures (:mod:`toonmotion.batch.work`). Workers send the outputs back as
bytes; the client writes each file atomically and records it in the manifest as soon as its
task finishes (in the manifest's journal: :mod:`toonmotion.io.batch_manifest`), so a batch
stopped at any moment loses at most the tasks still running, and no half-written file is ever
left. A worker that dies mid-task has its tasks rerun elsewhere by
Dask's scheduler.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path, PurePosixPath
from typing import Any

from toonmotion.batch.plan import OutputTask, Plan, plan_job, sha256
from toonmotion.batch.report import BatchReport, TaskResult, make_strip, write_report
from toonmotion.batch.work import prepare_motion, render_output, rig_character
from toonmotion.errors import BatchError, ToonmotionError
from toonmotion.io.atomic import atomic_path
from toonmotion.io.batch_job import Job, load_job
from toonmotion.io.batch_manifest import (
    ManifestEntry,
    journal_path,
    load_manifest,
    record_task,
    save_manifest,
)
from toonmotion.progress import Progress

MANIFEST = "manifest.json"


def run_batch(
    job: str | os.PathLike[str] | Job,
    *,
    output: str | os.PathLike[str] | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: Progress | None = None,
    on_connect: Callable[[str | None], None] | None = None,
) -> BatchReport:
    """Run every task of a batch job on a Dask cluster; write outputs, manifest and reports.

    Parameters
    ----------
    job : str, Path or Job
        A ``JOB.toml`` (docs/batch.md) or a job already loaded with
        :func:`toonmotion.io.batch_job.load_job`.
    output : str or Path, optional
        The output folder; default ``JOB_outputs`` beside the job file.
    scheduler : str, optional
        A running Dask scheduler's address, ``tcp://HOST:PORT``; default a local cluster of
        worker processes started for this run.
    workers : int, optional
        The local cluster's worker processes (one thread each); default one per core.
    progress : callable, optional
        ``progress("tasks", finished, count)`` as tasks finish.
    on_connect : callable, optional
        ``on_connect(dashboard_link)`` once connected (None without a dashboard).

    Returns
    -------
    BatchReport
        Every task's result; ``report.json`` and ``report.html`` in the output folder say the same.

    Raises
    ------
    BatchError
        A malformed job, a missing input, a scheduler that cannot be reached. A task that fails
        (an unreadable drawing, a motion that does not fit a character) does not raise: it is
        recorded with its message and every other task completes.

    Examples
    --------
    >>> report = run_batch("JOB.toml", workers=2)  # doctest: +SKIP
    >>> report.count("done"), report.count("failed")  # doctest: +SKIP
    (8, 0)
    """
    start = time.perf_counter()
    if workers is not None and workers < 1:
        raise BatchError(f"--workers must be at least 1, got {workers}")
    if not isinstance(job, Job):
        job = load_job(job)
    folder = Path(output) if output is not None else job.path.parent / f"{job.path.stem}_outputs"
    plan = plan_job(job)
    manifest = load_manifest(folder / MANIFEST)
    results: dict[str, TaskResult] = {}
    pending = []
    for task in plan.tasks:
        entry = manifest.get(task.key)
        if entry is not None and _intact(folder, entry):
            results[task.key] = TaskResult(task.key, task.character, task.motion, task.output.name or "",
                                           "skipped", files=tuple(entry.files), frames=entry.frames)
        else:
            pending.append(task)
    count = len(plan.tasks)
    if progress is not None:
        progress("tasks", len(results), count)
    dashboard = None
    if pending:
        try:
            with _client(scheduler, workers) as client:
                dashboard = _dashboard(client)
                if on_connect is not None:
                    on_connect(dashboard)
                for result in _compute(client, plan, pending, folder, manifest):
                    results[result.key] = result
                    if progress is not None:
                        progress("tasks", len(results), count)
        finally:  # the journal of this run's finished tasks merged into the manifest, even if stopped
            if journal_path(folder / MANIFEST).exists():
                save_manifest(folder / MANIFEST, manifest)
    report = BatchReport(job=job.path, folder=folder, results=tuple(results[t.key] for t in plan.tasks),
                         seconds=time.perf_counter() - start, dashboard=dashboard)
    write_report(report)
    return report


def _intact(folder: Path, entry: ManifestEntry) -> bool:
    """Whether every file of ``entry`` is there as it was written: by its size and modification
    time when the manifest has them and they match, else by its SHA-256 (a million outputs would
    otherwise be read again on every rerun)."""
    for name, digest in entry.files.items():
        try:
            if _stamp(folder / name) == entry.stamps.get(name):
                continue
            if sha256((folder / name).read_bytes()) != digest:
                return False
        except OSError:
            return False
    return True


def _stamp(path: Path) -> tuple[int, int]:
    """A file's size and modification time, nanoseconds."""
    status = path.stat()
    return status.st_size, status.st_mtime_ns


@contextmanager
def _client(scheduler: str | None, workers: int | None) -> Iterator[Any]:
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as error:
            raise BatchError(f"cannot reach the Dask scheduler at {scheduler}: {error}") from None
        with client:
            yield client
        return
    # The workers' own logs stay quiet: a task's failure is reported by the client, in one line
    # (the workers log it with its traceback at ERROR), and so is an unexpected error.
    with _forked_workers():  # and a worker restarted after a crash
        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.CRITICAL)
        with cluster, Client(cluster) as client:
            yield client


@contextmanager
def _forked_workers() -> Iterator[None]:
    """On Linux, the local cluster's worker processes are forked from this one (which has already
    imported the library) instead of spawned, unless Dask's configuration names another method.

    A spawned worker starts a new interpreter and imports Dask and the library again: 5 s before
    its first task here, against 0.8 s forked (docs/batch.md, overhead). Fork was Python's own
    default on Linux until 3.14; elsewhere (macOS, Windows) the workers are spawned.
    """
    import dask

    key = "distributed.worker.multiprocessing-method"
    if sys.platform.startswith("linux") and dask.config.get(key, "spawn") == "spawn":
        with dask.config.set({key: "fork"}):
            yield
    else:
        yield


def _dashboard(client: Any) -> str | None:
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # a scheduler that does not say: no link
        return None
    return str(client.dashboard_link) if "dashboard" in services else None


def _compute(client: Any, plan: Plan, pending: list[OutputTask], folder: Path,
             manifest: dict[str, ManifestEntry]) -> Iterator[TaskResult]:
    from distributed import as_completed

    characters = {t.character for t in pending}
    motions = {t.motion for t in pending}
    rigged = {c: client.submit(rig_character, plan.characters[c],
                               key=f"rig-{c}-{plan.characters[c].key[:16]}")
              for c in sorted(characters)}
    read = {m: client.submit(prepare_motion, plan.motions[m], key=f"motion-{m}-{plan.motions[m].key[:16]}")
            for m in sorted(motions)}
    futures = {}
    for task in pending:
        future = client.submit(render_output, rigged[task.character], read[task.motion], task,
                               key=f"render-{task.character}-{task.motion}-{task.key[:16]}")
        futures[future.key] = (future, task)
    del rigged, read  # held by the tasks that need them; released with the last of those
    for future in as_completed([f for f, _ in futures.values()]):
        _, task = futures.pop(future.key)
        name = task.output.name or ""
        if future.status != "finished":
            error = future.exception()
            message = str(error) if isinstance(error, ToonmotionError) else \
                f"internal error ({type(error).__name__}: {error})"
            yield TaskResult(task.key, task.character, task.motion, name, "failed", " ".join(message.split()))
            continue
        rendered = future.result()
        del future
        files, stamps = {}, {}
        for file, data in rendered.files.items():
            relative = PurePosixPath(file)
            if relative.is_absolute() or ".." in relative.parts:
                raise BatchError(f"a worker returned a file outside the output folder: {file}")
            with atomic_path(folder / relative) as tmp:
                tmp.write_bytes(data)
            files[file] = sha256(data)
            stamps[file] = _stamp(folder / relative)
        manifest[task.key] = ManifestEntry(character=task.character, motion=task.motion, output=name,
                                           frames=rendered.frames, files=files, stamps=stamps)
        record_task(folder / MANIFEST, task.key, manifest[task.key])
        make_strip(folder, tuple(files))  # while the workers go on
        yield TaskResult(task.key, task.character, task.motion, name, "done", seconds=rendered.seconds,
                         files=tuple(files), frames=rendered.frames)
