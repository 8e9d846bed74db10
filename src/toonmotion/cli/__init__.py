"""The ``toonmotion`` command line: parse, call the library (:mod:`toonmotion.api`), report.

One module per command group registers its commands on the shared Typer ``app``:
:mod:`~toonmotion.cli.rigging` (rig, show, sample, remesh), :mod:`~toonmotion.cli.animation`
(pose, animate, filter), :mod:`~toonmotion.cli.editing` (depth, correct, undo, redo, edits, tune)
and :mod:`~toonmotion.cli.capture` (track, retarget). Errors the user can fix print one line,
``toonmotion: error: ...``, and exit with status 2 (:func:`~toonmotion.cli.app.main`).
"""

from toonmotion.cli import animation, capture, editing, rigging
from toonmotion.cli.app import app, main

__all__ = ["animation", "app", "capture", "editing", "main", "rigging"]
