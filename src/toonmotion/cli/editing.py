"""Editing commands: ``depth``, ``correct``, ``undo``, ``redo``, ``edits``, ``tune``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from toonmotion import api
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.deform.deformer import DeformSettings
from toonmotion.deform.tuning import CurveEdit, DragEdit
from toonmotion.deform.tuning import describe as describe_tuning
from toonmotion.errors import SettingsError
from toonmotion.io.image import save_png
from toonmotion.io.tuned_pose import load_tuned_pose, save_tuned_pose, with_edits, without_last_edit
from toonmotion.render.frame import natural_size
from toonmotion.rig.edits import describe as describe_edit


@app.command()
def depth(
    project: options.Project,
    settings: Annotated[list[str] | None, typer.Argument(
        metavar="[BONE=N | @X,Y=N]...",
        help="Set a bone region's depth (higher is in front); @X,Y picks the region of the vertex "
        "nearest that point.")] = None,
) -> None:
    """Show or set the depth layers of a project's bone regions (saved as edits; see 'undo')."""
    character = api.load_project(project)
    names = character.skeleton.bone_names
    for item in settings or []:
        character = api.set_depth(character, **_depth_target(item, names))
    if not settings:
        for name, d in zip(names, character.depth, strict=True):
            typer.echo(f"{name:>20} {d}")
        return
    api.save_project(project, character)
    for edit in character.edits[-len(settings) :]:
        typer.echo(f"set {describe_edit(edit)}")


# Curve points may be negative ("-100,-100"): they are arguments, not unknown options.
@app.command(context_settings={"ignore_unknown_options": True})
def correct(
    project: options.Project,
    bone: Annotated[str, typer.Argument(help="The bone (named after its child joint) to attach to.")],
    curve: Annotated[list[str], typer.Argument(
        metavar="X,Y X,Y X,Y...", help="A closed curve round the vertices, drawing pixels.")],
) -> None:
    """Correct the decomposition: attach every vertex inside a closed curve to one bone."""
    character = api.load_project(project)
    points = np.array([options.point(p, "a curve point X,Y") for p in curve])
    before = character.binding.bone
    character = api.correct_regions(character, bone, points)
    api.save_project(project, character)
    moved = int(np.count_nonzero(character.binding.bone != before))
    typer.echo(
        f"attached {moved} vertices to {bone} (edit {len(character.edits)}; 'toonmotion undo' takes it back)"
    )


Steps = Annotated[int, typer.Option("--steps", help="How many edits.")]


@app.command("undo")
def undo_edits(project: options.Project, steps: Steps = 1) -> None:
    """Take back a project's last corrections or depth settings."""
    before = api.load_project(project)
    character = api.undo_edits(before, steps)
    taken = before.edits[len(character.edits):]
    api.save_project(project, character)
    for edit in taken[::-1]:
        typer.echo(f"undid: {describe_edit(edit)}")


@app.command("redo")
def redo_edits(project: options.Project, steps: Steps = 1) -> None:
    """Make again edits taken back by 'undo' (until a new edit is made)."""
    before = api.load_project(project)
    character = api.redo_edits(before, steps)
    again = before.undone[: len(before.undone) - len(character.undone)]
    api.save_project(project, character)
    for edit in again:
        typer.echo(f"redid: {describe_edit(edit)}")


@app.command()
def edits(project: options.Project) -> None:
    """List a project's edits, oldest first, and any that can be redone."""
    character = api.load_project(project)
    if not character.edits and not character.undone:
        typer.echo("no edits")
    for n, edit in enumerate(character.edits, start=1):
        typer.echo(f"{n:>3}  {describe_edit(edit)}")
    for edit in character.undone:
        typer.echo(f"redo {describe_edit(edit)}")


@app.command()
@options.deform_options
def tune(
    project: options.Project,
    pose_file: Annotated[Path, typer.Argument(
        metavar="POSE.json|KEYS.json", help="A pose file, or key-frames with --key.")],
    key: Annotated[int | None, typer.Option("--key", help="Frame number of the key to tune.")] = None,
    curve: Annotated[str | None, typer.Option(
        "--curve", help="Pull the outline onto a sketched curve: 'X,Y X,Y ...', drawing pixels.")] = None,
    drag: Annotated[list[str] | None, typer.Option(
        "--drag", help="Drag the vertex at X,Y to X2,Y2: 'X,Y:X2,Y2' (repeat for several).")] = None,
    undo_last: Annotated[bool, typer.Option("--undo", help="Take back the last edit.")] = False,
    preview: Annotated[Path | None, typer.Option(
        "-o", "--output", help="Also render the tuned pose to this PNG.")] = None,
    deform: DeformSettings = options.DEFAULT_DEFORM,
) -> None:
    """Fine-tune a deformed pose: sketch curves and point drags, saved in the pose or key file.

    With no edit given, lists the edits.

    Each new edit is tried on the project before it is saved, so a file never holds one that does not apply.
    """
    if preview is not None:
        options.suffix(preview, ".png", "an output", why="the frame is a PNG; ")
    if (curve is not None) + bool(drag) + undo_last > 1:
        raise SettingsError("give one of --curve, --drag or --undo at a time")
    character = api.load_project(project)
    tuned = load_tuned_pose(pose_file, character.skeleton, key=key)
    taken = None
    if curve is not None:
        points = np.array([options.point(p, "--curve point X,Y") for p in curve.split()])
        tuned = with_edits(tuned, (*tuned.edits, CurveEdit(points=points)))
    elif drag:
        start, end = zip(*(_drag(d) for d in drag), strict=True)
        tuned = with_edits(tuned, (*tuned.edits, DragEdit(start=np.array(start), end=np.array(end))))
    elif undo_last:
        tuned, taken = without_last_edit(tuned)
    # The edit is tried on the pose as 'pose' and 'animate' deform it given the same options.
    frame = api.pose_character(character, tuned.pose, edits=tuned.edits, settings=deform)
    # Drawn before anything is saved: an edit whose frame cannot be drawn is refused.
    picture = api.render_pose(character, frame) if preview is not None else None
    natural_size(api.pose_view(character, frame))
    if curve is not None or drag or undo_last:
        save_tuned_pose(tuned, character.skeleton)
        typer.echo(
            f"undid: {describe_tuning(taken)}"
            if taken is not None
            else f"added edit {len(tuned.edits)}: {describe_tuning(tuned.edits[-1])} -> {pose_file}"
        )
    elif not tuned.edits:
        typer.echo("no edits")
    else:
        for n, edit in enumerate(tuned.edits, start=1):
            typer.echo(f"{n:>3}  {describe_tuning(edit)}")
    if preview is not None:
        save_png(preview, picture)
        typer.echo(f"wrote {preview}")
        x0, y0, x1, _ = api.pose_view(character, frame)
        if (x0 + 0.5, y0 + 0.5) != (0.0, 0.0) and x1 - x0 > 0:
            options.warn(
                f"the picture's pixel (0, 0) is drawing pixel ({x0 + 0.5:.1f}, {y0 + 0.5:.1f}); "
                "edits and poses use drawing pixels"
            )


def _depth_target(item: str, names: list[str] | tuple[str, ...]) -> dict[str, Any]:
    """``BONE=N`` or ``@X,Y=N`` as :func:`toonmotion.api.set_depth`'s arguments."""
    target, _, value = item.rpartition("=")
    try:
        depth = int(value)
    except ValueError:
        raise SettingsError(f"give a whole-number depth after '=' in {item!r}") from None
    if target.startswith("@"):
        return {"value": depth, "at": options.point(target[1:], "@X,Y")}
    if target in names:
        return {"value": depth, "bone": target}
    raise SettingsError(f"no bone is called {target!r}; the bones are: {', '.join(names)}")


def _drag(text: str) -> tuple[tuple[float, float], tuple[float, float]]:
    a, sep, b = text.partition(":")
    if not sep:
        raise SettingsError(f"--drag takes X,Y:X2,Y2 (from, to), got {text!r}")
    return options.point(a, "--drag X,Y"), options.point(b, "--drag X2,Y2")
