"""Posing and animation commands: ``pose``, ``sketch``, ``animate``, ``filter``."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from toonmotion import api
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.animate.motion import Motion
from toonmotion.animate.timeline import Timeline, make_timeline
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import SettingsError
from toonmotion.io.image import save_png
from toonmotion.io.motion_json import is_motion_file, load_motion, save_motion
from toonmotion.io.pose_json import load_keyframes, load_pose, load_pose_edits, save_pose
from toonmotion.io.sketch_json import load_sketch
from toonmotion.io.video import TRANSPARENT_FORMATS, animation_format, rate_note
from toonmotion.rig.character import Character


@app.command()
@options.deform_options
def pose(
    project: options.Project,
    pose_file: Annotated[Path, typer.Argument(
        metavar="POSE.json", help="Joint positions by name (a pose or skeleton file).")],
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file to write.")],
    size: options.Size = None,
    background: Annotated[str, typer.Option(
        "--background", help="transparent, white, black or #rrggbb.")] = "transparent",
    overlay: options.Overlay = "",
    deform: DeformSettings = options.DEFAULT_DEFORM,
    accel: Annotated[str | None, typer.Option(
        "--accel", help="Cartoon filter: acceleration DX,DY at the root, pixels.")] = None,
    fixed: Annotated[str | None, typer.Option(
        "--fixed", help="Joints that stay put under --accel: J[,J...].")] = None,
    root: Annotated[str | None, typer.Option(
        "--root", help="Joint --accel acts on \\[default: the skeleton's root].")] = None,
) -> None:
    """Pose a rigged drawing: deform it to a sketched skeleton and render one frame.

    Fine-tuning edits in the pose file (see 'toonmotion tune') are applied.

    --accel and --fixed exaggerate the pose with the single-frame cartoon filter first.
    """
    options.suffix(output, ".png", "an output", why="the frame is a PNG; ")
    picture_size = options.size(size)  # checked before the pose is worked out
    if (accel is None) != (fixed is None):
        raise SettingsError(
            "--accel and --fixed go together: give the acceleration and the joints that stay put"
        )
    character = api.load_project(project)
    edits = load_pose_edits(pose_file)
    frame = api.pose_character(
        character, load_pose(pose_file, character.skeleton), edits=edits,
        accel=None if accel is None else options.point(accel, "--accel"),
        fixed=options.names(fixed) if fixed is not None else (), root=root,
        settings=deform)
    picture = api.render_pose(character, frame, size=picture_size,
                              background=options.colour(background), overlays=options.overlays(overlay))
    save_png(output, picture)
    result = frame.deformation
    typer.echo(
        f"posed {project.name}: stage two {result.iterations} "
        f"iterations, energy {result.energy_start:.4g} -> {result.energy:.4g}"
        + (f", {len(edits)} edit{'s' if len(edits) > 1 else ''}" if edits else "")
        + f" -> {output}"
    )
    report_overlaps(character, [(0, result.U)])


@app.command()
def sketch(
    project: options.Project,
    sketch_file: Annotated[Path, typer.Argument(
        metavar="SKETCH.json", help="Strokes in drawing pixels: a toonmotion sketch file.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Pose file to write (.json).")],
    start: Annotated[Path | None, typer.Option(
        "--from", help=r"The pose the sketch edits (a pose file) \[default: the rest pose].")] = None,
) -> None:
    """Read a sketched skeleton: match its strokes to the bones and write the pose.

    A stroke is a bone, a chain of bones (its corners are joints) or part of a stick figure,
    drawn over the drawing or beside it. Pose the drawing with 'toonmotion pose PROJECT
    POSE.json', or key it in a key-frames file.
    """
    options.suffix(output, ".json", "an output", why="a pose file is JSON; ")
    character = api.load_project(project)
    pose = None if start is None else load_pose(start, character.skeleton)
    found = api.sketch_pose(character, load_sketch(sketch_file), pose=pose)
    save_pose(output, character.skeleton, found.pose)
    typer.echo(f"sketched {', '.join(found.bones)}"
               + (" (drawn beside the figure: scaled to it)" if found.elsewhere else "") + f" -> {output}")


@app.command()
@options.deform_options
def animate(
    project: options.Project,
    keys_file: options.KeysFile,
    output: options.AnimationOutput,
    fps: options.Fps = None,
    size: options.Size = None,
    background: options.AnimationBackground = None,
    overlay: options.Overlay = "",
    ease: options.Ease = None,
    exaggerate: options.Exaggerate = None,
    sigma: options.Sigma = 3.0,
    shift: options.Shift = 0.0,
    save_motion_to: Annotated[Path | None, typer.Option(
        "--save-motion", help="Also write the joint positions of every frame, in the drawing's pixels "
        "(.json: a motion that replays on the character).")] = None,
    save_frame_motion_to: Annotated[Path | None, typer.Option(
        "--save-frame-motion", help="Also write the joint positions in the written frames' pixels (.json: "
        "what tracking the frames finds; what 'lift' needs beside them).")] = None,
    solve_inbetweens: options.SolveInbetweens = False,
    deform: DeformSettings = options.DEFAULT_DEFORM,
) -> None:
    """Animate a rigged drawing through key-frames or a motion, to GIF, MP4 or PNGs.

    --exaggerate runs the cartoon filter over every bone's angle and length and the root's path.
    """
    kind = animation_format(output)
    picture_size = options.size(size)  # checked before the frames are worked out
    for path in (save_motion_to, save_frame_motion_to):
        if path is not None:
            options.suffix(path, ".json", "a motion file")
    exaggeration = options.filter_settings(exaggerate, sigma, shift)
    character, animation, what = make_animation(project, keys_file, settings=deform, fps=fps, ease=ease,
                                                exaggeration=exaggeration, solve_inbetweens=solve_inbetweens)
    count, out_size = write(
        output, character, animation, kind=kind, size=picture_size, background=background, overlay=overlay
    )
    if save_motion_to is not None:
        save_motion(save_motion_to, animation.motion)
    if save_frame_motion_to is not None:
        save_motion(save_frame_motion_to, api.motion_in_frames(character, animation, size=picture_size))
    typer.echo(
        f"animated {what}"
        + (f", exaggerated (A={exaggerate:g})" if exaggeration else "")
        + f": {count} frames at {animation.motion.fps:g} fps, {out_size[0]}x{out_size[1]} -> {output}"
        + (f" (motion -> {save_motion_to})" if save_motion_to is not None else "")
        + (f" (motion in the frames -> {save_frame_motion_to})" if save_frame_motion_to is not None else "")
    )
    note = rate_note(kind, animation.motion.fps)
    if note:
        options.warn(note)
    solved = zip(animation.keys, animation.solved, strict=True)
    report_overlaps(character, [(key.frame, result.U) for key, result in solved], keys=True)


@app.command("filter")
def filter_motion(
    motion_file: Annotated[Path, typer.Argument(metavar="MOTION.json", help="A motion: a pose per frame.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Motion file to write (.json).")],
    strength: options.Strength,
    sigma: options.Sigma = 3.0,
    shift: options.Shift = 0.0,
    joints: Annotated[str | None, typer.Option(
        "--joints", help="Filter only these joints' paths (J[,J...]), carrying what hangs below them "
        "\\[default: the root's path and every bone's angle and length].")] = None,
) -> None:
    """Exaggerate a motion with the cartoon animation filter: anticipation, follow-through."""
    options.suffix(output, ".json", "a motion file")
    motion = load_motion(motion_file)
    filtered = api.filter_motion(
        motion, strength, sigma=sigma, shift=shift, joints=None if joints is None else options.names(joints)
    )
    save_motion(output, filtered)
    moved = np.hypot(*(filtered.positions - motion.positions).reshape(-1, 2).T).max()
    typer.echo(
        f"filtered {motion.frame_count} frames (A={strength:g}, sigma={sigma:g}, shift={shift:g}): "
        f"joints moved up to {moved:.1f} px -> {output}"
    )


def make_animation(project: Path, keys_file: Path, *, settings: DeformSettings, fps: float | None,
                   ease: str | None, exaggeration: FilterSettings | None, solve_inbetweens: bool
                   ) -> tuple[Character, api.Animation, str]:
    """The project's character, its animation through key-frames or a motion file, and what that
    file held (for the summary line): what ``animate`` and ``export`` share."""
    character = api.load_project(project)
    source: Motion | Timeline
    if is_motion_file(keys_file):
        if ease is not None:
            raise SettingsError("--ease applies to key-frames; a motion has a pose for every frame")
        motion = load_motion(keys_file)
        source, what = motion, f"a motion of {motion.frame_count} frames"
    else:
        timeline = load_keyframes(keys_file, character.skeleton, fps=fps)
        if ease is not None:
            timeline = make_timeline(character.skeleton, timeline.keys, fps=timeline.fps, ease=ease)
        source, what = timeline, f"{len(timeline.keys)} key-frames"
    animation = api.animate_character(character, source, settings=settings, exaggeration=exaggeration,
                                      fps=fps, method="solve" if solve_inbetweens else "interpolate")
    return character, animation, what


def write(output: Path, character: Character, animation: api.Animation, *, kind: str,
          size: tuple[int, int] | None, background: str | None, overlay: str) -> tuple[int, tuple[int, int]]:
    """Render and save an animation with the shared output options; ``(frames, (w, h))``."""
    colour = options.colour(background or ("transparent" if kind in TRANSPARENT_FORMATS else "white"))
    with options.progress("rendering") as report:
        return api.write_animation(output, character, animation, size=size,
                                   background=colour, overlays=options.overlays(overlay), progress=report)


def report_overlaps(
    character: Character, results: Iterable[tuple[int, np.ndarray]], *, keys: bool = False
) -> None:
    """Warn once for each pair of regions at the same depth that overlap (in which key-frames)."""
    for o in api.same_depth_overlaps(character, results):
        where = (
            f" in key-frame{'s' if len(o.frames) > 1 else ''} {', '.join(map(str, o.frames))}" if keys else ""
        )
        options.warn(
            f"regions {o.bone_a} and {o.bone_b} overlap ({o.area:.0f} px²) at the same depth{where}; "
            f"set their order with 'toonmotion depth'"
        )
