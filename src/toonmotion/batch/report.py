"""A batch's reports: ``report.json`` (counts, every task's status, failures' messages, timings)
and ``report.html`` (a static page: a strip of thumbnails per output, each failure's message).

Thumbnails are a few frames of each output's GIF (or another picture format Pillow reads),
saved as small PNGs in ``thumbs/`` beside the outputs. :func:`run_batch` makes each task's as the
task finishes (:func:`make_strip`), while the workers go on, so the report at the end only lists
them.
"""

from __future__ import annotations

import html
import json
from dataclasses import dataclass
from pathlib import Path

from toonmotion.io.atomic import atomic_path


@dataclass(frozen=True)
class TaskResult:
    """How one output task ended.

    Attributes
    ----------
    key : str
        The task's key (SHA-256 of its inputs and options).
    character, motion, output : str
        Its pair and output name ("" for a job's single unnamed output).
    status : {"done", "skipped", "failed"}
        Computed now, found finished and intact in the manifest, or failed.
    message : str
        Why it failed: one line.
    seconds : float
        Work on the worker (0 when skipped or failed).
    files : tuple of str
        The files it wrote (or had written), relative to the output folder.
    frames : int
    """

    key: str
    character: str
    motion: str
    output: str
    status: str
    message: str = ""
    seconds: float = 0.0
    files: tuple[str, ...] = ()
    frames: int = 0


@dataclass(frozen=True)
class BatchReport:
    """What :func:`run_batch` did: every task's result, the wall time, where it wrote."""

    job: Path
    folder: Path
    results: tuple[TaskResult, ...]
    seconds: float
    dashboard: str | None = None

    def count(self, status: str) -> int:
        """How many tasks ended as ``status``."""
        return sum(r.status == status for r in self.results)


THUMBS = "thumbs"
# Frames in a thumbnail strip, and a thumbnail's largest side in pixels.
STRIP_FRAMES = 4
THUMB_SIZE = 96
_PICTURES = (".gif", ".apng", ".webp")


def write_report(report: BatchReport) -> None:
    """Write ``report.json``, ``report.html`` and the thumbnails into the report's folder."""
    folder = report.folder
    folder.mkdir(parents=True, exist_ok=True)
    strips = {r.key: _strip(folder, r) for r in report.results if r.status != "failed"}
    data = {
        "job": str(report.job),
        "seconds": round(report.seconds, 3),
        "dashboard": report.dashboard,
        "done": report.count("done"),
        "skipped": report.count("skipped"),
        "failed": report.count("failed"),
        "tasks": [
            {"key": r.key, "character": r.character, "motion": r.motion, "output": r.output,
             "status": r.status, "message": r.message, "seconds": round(r.seconds, 3),
             "frames": r.frames, "files": list(r.files), "thumbnails": strips.get(r.key, [])}
            for r in report.results
        ],
    }
    with atomic_path(folder / "report.json") as tmp:
        tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    with atomic_path(folder / "report.html") as tmp:
        tmp.write_text(_page(report, strips), encoding="utf-8")


def _strip(folder: Path, result: TaskResult) -> list[str]:
    """The thumbnails of ``result``'s first picture file, made if missing; [] if it has none."""
    names = _strip_names(result.files)
    if names and all((folder / n).is_file() for n in names):
        return names
    return make_strip(folder, result.files)


def _strip_names(files: tuple[str, ...]) -> list[str]:
    picture = next((f for f in files if Path(f).suffix.lower() in _PICTURES), None)
    if picture is None:
        return []
    stem = Path(picture).name.replace(".", "_")
    return [f"{THUMBS}/{stem}-{i}.png" for i in range(STRIP_FRAMES)]


def make_strip(folder: Path, files: tuple[str, ...]) -> list[str]:
    """Make the thumbnails of the first picture among ``files`` (relative to ``folder``), replacing
    any earlier ones; their names, or [] when there is no picture or it cannot be read."""
    from PIL import Image, ImageSequence

    names = _strip_names(files)
    if not names:
        return []
    picture = next(f for f in files if Path(f).suffix.lower() in _PICTURES)
    try:
        with Image.open(folder / picture) as image:
            frames = [f.convert("RGBA") for f in ImageSequence.Iterator(image)]
    except OSError:
        for name in names:  # no stale strip of an earlier run stands in for it
            (folder / name).unlink(missing_ok=True)
        return []
    picks = [frames[round(i * (len(frames) - 1) / max(STRIP_FRAMES - 1, 1))] for i in range(STRIP_FRAMES)]
    for name, frame in zip(names, picks, strict=True):
        frame.thumbnail((THUMB_SIZE, THUMB_SIZE))
        with atomic_path(folder / name) as tmp:
            frame.save(tmp, format="PNG")
    return names


def _page(report: BatchReport, strips: dict[str, list[str]]) -> str:
    e = html.escape
    rows = []
    for r in report.results:
        title = f"{r.character} × {r.motion}" + (f" ({r.output})" if r.output else "")
        if r.status == "failed":
            body = f'<p class="failed">failed: {e(r.message)}</p>'
        else:
            pictures = "".join(f'<img src="{e(n)}" alt="frame">' for n in strips.get(r.key, []))
            links = " ".join(f'<a href="{e(f)}">{e(f)}</a>' for f in r.files)
            timing = f"{r.seconds:.1f} s" if r.status == "done" else "skipped: unchanged"
            body = f'<div class="strip">{pictures}</div><p>{r.frames} frames, {timing}: {links}</p>'
        rows.append(f'<section class="{r.status}"><h2>{e(title)}</h2>{body}</section>')
    summary = (f"{report.count('done')} done, {report.count('skipped')} skipped, "
               f"{report.count('failed')} failed in {report.seconds:.1f} s")
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>toonmotion batch: {e(report.job.name)}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; }}
section {{ border-bottom: 1px solid #ddd; padding: .4em 0; }}
h2 {{ font-size: 1em; margin: .2em 0; }}
.strip img {{ border: 1px solid #ccc; margin-right: 4px; background: #fff; }}
.failed {{ color: #a00; }}
</style></head>
<body><h1>toonmotion batch: {e(report.job.name)}</h1>
<p>{e(summary)}</p>
{chr(10).join(rows)}
</body></html>
"""
