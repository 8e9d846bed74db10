"""Batch jobs on Dask: many (character, motion, output) tasks from one ``JOB.toml``.

:mod:`~toonmotion.batch.plan` turns a job into tasks with keys (what the client reads and
sends), :mod:`~toonmotion.batch.work` is what the workers run, :mod:`~toonmotion.batch.run`
submits, collects and writes (:func:`run_batch`), :mod:`~toonmotion.batch.report` writes
``report.json`` and ``report.html``. See docs/batch.md.
"""

from toonmotion.batch.report import BatchReport, TaskResult
from toonmotion.batch.run import run_batch

__all__ = ["BatchReport", "TaskResult", "run_batch"]
