"""A batch's manifest, ``manifest.json`` in its output folder: what each finished task wrote.

Each task key (the SHA-256 of the task's inputs and options, :mod:`toonmotion.batch.plan`) maps
to the files it wrote, each with its SHA-256, so a rerun can skip a task whose files are all
there and intact. Written atomically after every finished task.

>>> import tempfile
>>> path = Path(tempfile.mkdtemp()) / "manifest.json"
>>> entry = ManifestEntry(character="hero", motion="walk", output="", frames=12,
...                       files={"hero-walk.gif": "0" * 64})
>>> save_manifest(path, {"ab" * 32: entry})
>>> load_manifest(path)["ab" * 32].files
{'hero-walk.gif': '0000000000000000000000000000000000000000000000000000000000000000'}
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated

from pydantic import Field, StrictStr

from toonmotion.errors import BatchError
from toonmotion.io.atomic import atomic_path
from toonmotion.io.schema import Int, JsonFormat, Model, read_versioned

FORMAT = "toonmotion-batch-manifest"
VERSION = 1

Sha256 = Annotated[StrictStr, Field(pattern=r"^[0-9a-f]{64}$")]


class ManifestEntry(Model):
    """One finished task: its pair, output name, frame count and files with their SHA-256."""

    character: StrictStr
    motion: StrictStr
    output: StrictStr
    frames: Int
    files: dict[StrictStr, Sha256]


class ManifestFile(Model):
    format: StrictStr
    version: Int
    tasks: dict[Sha256, ManifestEntry]


MANIFEST = JsonFormat(models={FORMAT: ManifestFile}, version=VERSION, error=BatchError,
                      title="batch manifest", label="a batch manifest", what="batch manifest ")


def load_manifest(path: str | Path) -> dict[str, ManifestEntry]:
    """The tasks recorded in a manifest; an empty dict when there is none yet."""
    path = Path(path)
    if not path.exists():
        return {}
    return dict(read_versioned(path, MANIFEST).tasks)


def save_manifest(path: str | Path, tasks: dict[str, ManifestEntry]) -> None:
    """Write a manifest atomically."""
    data = {"format": FORMAT, "version": VERSION,
            "tasks": {key: entry.model_dump() for key, entry in sorted(tasks.items())}}
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
