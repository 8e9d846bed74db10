"""The ``toonmotion`` command line: parse, call the library (:mod:`toonmotion.api`), report.

One module per command group registers its commands on the shared Typer ``app``:
:mod:`~toonmotion.cli.rigging` (rig, show, sample, remesh), :mod:`~toonmotion.cli.animation`
(pose, animate, filter), :mod:`~toonmotion.cli.editing` (depth, correct, undo, redo, edits, tune)
and :mod:`~toonmotion.cli.capture` (track, retarget), :mod:`~toonmotion.cli.keyshapes`
(keyshapes, capture-contours), :mod:`~toonmotion.cli.proxy3d` (lift, proxy-export,
proxy-preview, project-mocap), :mod:`~toonmotion.cli.scene3d` (scene), :mod:`~toonmotion.cli.export`
(export), :mod:`~toonmotion.cli.editor` (edit) and :mod:`~toonmotion.cli.about` (doctor).
Errors the user can fix print one line, ``toonmotion: error: ...``, and exit with status 2
(:func:`~toonmotion.cli.app.main`).
"""

# The order the groups register their commands in is the order --help lists them: the workflow's.
from toonmotion.cli import rigging  # isort: split

from toonmotion.cli import animation  # isort: split

from toonmotion.cli import editing  # isort: split

from toonmotion.cli import capture  # isort: split

from toonmotion.cli import keyshapes  # isort: split

from toonmotion.cli import proxy3d  # isort: split

from toonmotion.cli import scene3d  # isort: split

from toonmotion.cli import export  # isort: split

from toonmotion.cli import batch  # isort: split

from toonmotion.cli import editor  # isort: split

from toonmotion.cli import about  # isort: split

from toonmotion.cli.app import app, main

__all__ = ["about", "animation", "app", "batch", "capture", "editing", "editor", "export", "keyshapes",
           "main", "proxy3d", "rigging", "scene3d"]
