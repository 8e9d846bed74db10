"""About toonmotion itself: ``doctor``, the versions to put in a bug report."""

from __future__ import annotations

import typer

from toonmotion import api
from toonmotion.cli.app import app


@app.command()
def doctor() -> None:
    """Print toonmotion's version and those of the libraries and tools it uses, for a bug report.

    Chromium and the glTF validator are needed only by the tests; a missing one is shown, not an
    error.
    """
    report = api.environment_report()
    width = max(len(item.name) for item in report)
    for item in report:
        where = f"  {item.where}" if item.where and item.name not in ("toonmotion", "python") else ""
        mark = "" if item.found else "  (missing)"
        typer.echo(f"{item.name:<{width}}  {item.version}{mark}{where}")
