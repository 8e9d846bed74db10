"""The ``batch`` command: many characters x motions x outputs from one job file, on Dask."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from toonmotion.batch import run_batch
from toonmotion.cli import options
from toonmotion.cli.app import app


@app.command()
def batch(
    job: Annotated[Path, typer.Argument(metavar="JOB.toml", help="The job: characters, motions, outputs.")],
    scheduler: Annotated[str | None, typer.Option(
        "--scheduler", help="A running Dask scheduler, tcp://HOST:PORT \\[default: a local cluster].",
    )] = None,
    workers: Annotated[int | None, typer.Option(
        "--workers", help="Local worker processes \\[default: one per core].", min=1)] = None,
    output: Annotated[Path | None, typer.Option(
        "-o", "--output", help="Output folder \\[default: JOB_outputs beside the job file].")] = None,
) -> None:
    """Animate every character of a job with every motion (or its pairs), on a Dask cluster.

    Each character is rigged once. Outputs, a manifest, report.json and report.html go into
    the output folder; a rerun skips what is finished and unchanged. A task that fails is
    reported with its message and the others complete. See docs/batch.md.
    """
    def connected(link: str | None) -> None:
        if link:
            options.warn(f"dashboard: {link}")

    with options.progress("batch") as report:
        done = run_batch(job, output=output, scheduler=scheduler, workers=workers, progress=report,
                         on_connect=connected)
    typer.echo(f"batch {job.name}: {done.count('done')} done, {done.count('skipped')} skipped, "
               f"{done.count('failed')} failed in {done.seconds:.1f} s -> {done.folder / 'report.html'}")
    for result in done.results:
        if result.status == "failed":
            options.warn(f"failed {result.character} x {result.motion}"
                         + (f" ({result.output})" if result.output else "") + f": {result.message}")
    if done.count("failed"):
        raise typer.Exit(1)
