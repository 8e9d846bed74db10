"""A batch's manifest, ``manifest.json`` in its output folder: what each finished task wrote.

Each task key (the SHA-256 of the task's inputs and options, :mod:`toonmotion.batch.plan`) maps
to the files it wrote, each with its SHA-256, so a rerun can skip a task whose files are all
there and intact.

While a batch runs, each finished task is appended to a journal beside it,
``manifest.json.journal``, one JSON line flushed to disk (:func:`record_task`): constant work per
task, where rewriting the whole manifest after each would grow with the tasks done (a million
tasks' manifest is some 300 MB). At the end the two are merged into ``manifest.json``, written
atomically, and the journal removed (:func:`save_manifest`). A batch stopped mid-run leaves the
journal, which the next run reads; a line cut short by the stop is ignored and its task redone.

>>> import tempfile
>>> path = Path(tempfile.mkdtemp()) / "manifest.json"
>>> entry = ManifestEntry(character="hero", motion="walk", output="", frames=12,
...                       files={"hero-walk.gif": "0" * 64})
>>> record_task(path, "ab" * 32, entry)
>>> load_manifest(path)["ab" * 32].files
{'hero-walk.gif': '0000000000000000000000000000000000000000000000000000000000000000'}
>>> save_manifest(path, load_manifest(path)); journal_path(path).exists(), len(load_manifest(path))
(False, 1)
"""

from __future__ import annotations

import json
import os
import re
from pathlib import Path
from typing import Annotated

from pydantic import Field, StrictInt, StrictStr, ValidationError

from toonmotion.errors import BatchError
from toonmotion.io.atomic import atomic_path
from toonmotion.io.schema import Int, JsonFormat, Model, read_versioned

FORMAT = "toonmotion-batch-manifest"
VERSION = 1

Sha256 = Annotated[StrictStr, Field(pattern=r"^[0-9a-f]{64}$")]
Natural = Annotated[StrictInt, Field(ge=0)]  # bytes, nanoseconds: beyond 32 bits


class ManifestEntry(Model):
    """One finished task: its pair, output name, frame count and files with their SHA-256, and each
    file's size and modification time (nanoseconds) when it was written, so that a rerun need not
    read a file that was not touched since to know it is intact."""

    character: StrictStr
    motion: StrictStr
    output: StrictStr
    frames: Int
    files: dict[StrictStr, Sha256]
    stamps: dict[StrictStr, tuple[Natural, Natural]] = Field(default_factory=dict)


class ManifestFile(Model):
    format: StrictStr
    version: Int
    tasks: dict[Sha256, ManifestEntry]


MANIFEST = JsonFormat(models={FORMAT: ManifestFile}, version=VERSION, error=BatchError,
                      title="batch manifest", label="a batch manifest", what="batch manifest ")


def journal_path(path: str | Path) -> Path:
    """The journal beside a manifest: ``manifest.json.journal``."""
    path = Path(path)
    return path.with_name(path.name + ".journal")


def load_manifest(path: str | Path) -> dict[str, ManifestEntry]:
    """The tasks recorded in a manifest and its journal; an empty dict when there is none yet."""
    path = Path(path)
    tasks = dict(read_versioned(path, MANIFEST).tasks) if path.exists() else {}
    journal = journal_path(path)
    if journal.exists():
        lines = journal.read_text(encoding="utf-8").splitlines()
        for n, line in enumerate(lines):
            try:
                data = json.loads(line)
                key = data.pop("key")
                if not (isinstance(key, str) and _SHA256.fullmatch(key)):
                    raise ValueError("not a task key")
                entry = ManifestEntry.model_validate(data)
            except (ValueError, KeyError, TypeError, AttributeError, ValidationError):
                if n == len(lines) - 1:  # cut short by a stop mid-write: that task is redone
                    break
                raise BatchError(f"{journal}: line {n + 1} is not a finished task's record; delete the "
                                 "journal to redo the tasks it lists") from None
            tasks[key] = entry
    return tasks


def record_task(path: str | Path, key: str, entry: ManifestEntry) -> None:
    """Append a finished task to the manifest's journal: one line, flushed and synced to disk."""
    line = json.dumps({"key": key, **entry.model_dump()}, separators=(",", ":"))
    with open(journal_path(path), "a", encoding="utf-8") as journal:
        journal.write(line + "\n")
        journal.flush()
        os.fsync(journal.fileno())


def save_manifest(path: str | Path, tasks: dict[str, ManifestEntry]) -> None:
    """Write a manifest atomically, then remove its journal (whose tasks ``tasks`` must hold)."""
    data = {"format": FORMAT, "version": VERSION,
            "tasks": {key: entry.model_dump() for key, entry in sorted(tasks.items())}}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    journal_path(path).unlink(missing_ok=True)


_SHA256 = re.compile(r"[0-9a-f]{64}")
