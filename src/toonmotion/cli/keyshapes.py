"""Key-shape commands (Bregler et al. capture): ``keyshapes``, ``capture-contours``,
``capture-video``, ``retarget-keyshapes``, ``retarget-line``."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from numpy.typing import ArrayLike, NDArray

from toonmotion import api
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.errors import SettingsError
from toonmotion.io.frames import load_frames
from toonmotion.io.image import load_image, save_png
from toonmotion.io.keyshape_json import (
    load_contours,
    load_keymotion,
    load_model,
    save_contours,
    save_keymotion,
    save_model,
    save_video_report,
)
from toonmotion.io.motion_json import save_motion
from toonmotion.io.pose_json import load_keyframes
from toonmotion.io.video import animation_format, save_animation
from toonmotion.render.shape_overlay import draw_shape

# Contours of any point count, resampled into correspondence (both capture commands take them).
Points = Annotated[int | None, typer.Option(
    "--points", min=3, max=100_000,
    help="Resample every contour (closed) to this many points by arc length.")]
Start = Annotated[str | None, typer.Option(
    "--start", help="With --points: each contour starts at its point nearest X,Y.")]


@app.command()
def keyshapes(
    keys_file: Annotated[Path, typer.Argument(
        metavar="KEYS.json|KEYS.csv|KEYS.svg",
        help="The key-shapes: a contours file (points in correspondence) or an SVG file.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="The key-shape model to write (.json).")],
    inbetweens: Annotated[int, typer.Option("--inbetweens", min=0, max=1000,
                                            help="ARAP in-betweens per pair of keys.")] = 5,
    tolerance: Annotated[float, typer.Option("--tolerance", min=0.001,
                                             help="Largest reconstruction error of any example, px.")] = 0.5,
    sheet: Annotated[Path | None, typer.Option(
        "--sheet", help="Also write a preview sheet of the keys and their in-betweens (.png).")] = None,
    points: Points = None,
    start: Start = None,
) -> None:
    """Build a key-shape model: in-betweens of every pair of keys, then PCA (the extended space).

    The keys are contours in correspondence (the same number of points, in the same order);
    see docs/keyshapes.md.
    """
    options.suffix(output, ".json", "an output", why="a key-shape model is JSON; ")
    if sheet is not None:
        options.suffix(sheet, ".png", "a sheet", why="the sheet is a PNG; ")
    keys, _, closed = load_contours(keys_file, points=points, start=_start(start, points))
    space = api.keyshape_space(keys, closed=closed, inbetweens=inbetweens, tolerance=tolerance)
    picture = api.keyshape_sheet(space) if sheet is not None else None
    save_model(output, space)
    if sheet is not None and picture is not None:
        save_png(sheet, picture)
    typer.echo(f"{len(keys)} keys of {keys.shape[1]} points: {len(space.eigen)} eigen-shapes, every example "
               f"within {space.error:.3g} px -> {output}" + (f" (sheet {sheet})" if sheet else ""))


@app.command("capture-contours")
def capture_contours(
    model: Annotated[Path, typer.Argument(metavar="MODEL.json", help="A key-shape model ('keyshapes').")],
    contours_file: Annotated[Path, typer.Argument(
        metavar="CONTOURS.json|CONTOURS.csv|CONTOURS.svg",
        help="The contours to capture, in correspondence with the keys.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="The captured motion to write (.json).")],
    keys_only: Annotated[bool, typer.Option(
        "--keys", help="Capture with the hand-picked keys, not the extended space.")] = False,
    lower: Annotated[float, typer.Option("--lower", help="With --keys: each weight's lower bound.")] = -0.5,
    upper: Annotated[float, typer.Option("--upper", help="With --keys: each weight's upper bound.")] = 1.5,
    support: Annotated[int | None, typer.Option(
        "--support", min=1, help="With --keys: at most this many non-zero weights.")] = None,
    points: Points = None,
    start: Start = None,
) -> None:
    """Capture contours: each frame's affine motion and key-shape weights (Bregler et al. 3.2)."""
    options.suffix(output, ".json", "an output", why="a key-shape motion is JSON; ")
    space = load_model(model)
    contours, fps, _ = load_contours(contours_file, points=points, start=_start(start, points))
    with options.progress("capturing") as report_progress:
        if keys_only:
            found = api.capture_contours(contours, space.keys, lower=lower, upper=upper, support=support,
                                         progress=report_progress)
        else:
            found = api.capture_contours(contours, space, progress=report_progress)
    save_keymotion(output, found, fps=fps, space="keys" if keys_only else "extended")
    typer.echo(f"captured {len(contours)} frames: rms error {found.error.mean():.3g} px (largest "
               f"{found.error.max():.3g}), {found.rounds.mean():.1f} rounds a frame -> {output}")


@app.command("retarget-keyshapes")
def retarget_keyshapes(
    motion_file: Annotated[Path, typer.Argument(
        metavar="MOTION.json",
        help="Key-shape motion captured with the hand-picked keys ('capture-contours').")],
    model: Annotated[Path, typer.Argument(
        metavar="MODEL.json", help="The key-shape model it was captured with.")],
    output: Annotated[Path, typer.Option(
        "-o", "--output", help="Contours or a motion to write (.json); with --drawing, the animation "
                               "(OUT.gif, OUT.mp4 or a folder).")],
    onto: Annotated[Path | None, typer.Option(
        "--onto", help="Output key-shapes, one per input key (a contours file): writes contours.")] = None,
    drawing: Annotated[Path | None, typer.Option(
        "--drawing", help="With --onto: the output character's picture, drawn in its first key-shape's "
                          "pixels; the picture inside that outline moves with it, frame by frame.")] = None,
    background: Annotated[str | None, typer.Option(
        "--background", help="With --drawing: a background colour #rrggbb \\[default: transparent; "
                             "white in an MP4].")] = None,
    project: Annotated[Path | None, typer.Option(
        "--project", help="A rigged character, with --poses: writes its motion.")] = None,
    poses: Annotated[Path | None, typer.Option(
        "--poses", help="Key-frames of the project's skeleton, one key per input key, in order.")
    ] = None,
    pin: Annotated[str | None, typer.Option(
        "--pin", help="With --project: hold a joint at a place, e.g. left_foot=140,280.")] = None,
    pin_frames: Annotated[str | None, typer.Option(
        "--pin-frames", help="With --pin: the frames it holds on, e.g. 0,12,24 \\[default: every frame].")
    ] = None,
) -> None:
    """Replay captured key-shape motion on another character's key-shapes or key poses.

    With --onto and --drawing the output character's picture is animated directly. With
    --project and --poses the result is a motion: render it with 'toonmotion animate PROJECT
    OUT.json -o OUT.gif'.
    """
    if drawing is None:
        options.suffix(output, ".json", "an output", why="contours and motions are JSON; ")
    else:
        animation_format(output)
    flat = None if background is None else options.colour(background)
    if (onto is None) == (project is None or poses is None):
        raise SettingsError("give either --onto OUTKEYS.json, or --project PROJECT and --poses KEYS.json")
    if pin is not None and project is None:
        raise SettingsError("--pin goes with --project: it holds one of the character's joints")
    if drawing is not None and onto is None:
        raise SettingsError("--drawing goes with --onto: the picture is drawn in the first output key-shape")
    captured, fps, space = load_keymotion(motion_file)
    if space != "keys":
        raise SettingsError(f"{motion_file.name} was captured in the extended space: capture it with the "
                            "hand-picked keys ('capture-contours' with its keys option) to retarget it")
    keys = load_model(model).keys
    if onto is not None:
        outputs, _, closed = load_contours(onto)
        picture = None if drawing is None else load_image(drawing)
        shapes = api.retarget_keyshapes(captured, keys, outputs)
        if picture is None:
            save_contours(output, shapes, fps=fps, closed=closed)
        else:
            frames = api.animate_drawing(picture, outputs[0], shapes, closed=closed, background=flat)
            save_animation(output, frames, fps=fps, background=flat or (255, 255, 255))
        typer.echo(f"retargeted {len(shapes)} frames onto {len(outputs)} key-shapes -> {output}")
        return
    assert project is not None and poses is not None  # checked above
    character = api.load_project(project)
    timeline = load_keyframes(poses, character.skeleton)
    outline = character.mesh.V[character.mesh.boundary[0]]  # the drawing's extent, at rest
    held: tuple[str, dict[int, ArrayLike]] | None = None
    if pin is not None:
        joint, place = options.named_point(pin, "--pin")
        held_on = (list(range(len(captured.affine))) if pin_frames is None
                   else _frame_list(pin_frames, "--pin-frames"))
        held = (joint, dict.fromkeys(held_on, place))
    elif pin_frames is not None:
        raise SettingsError("--pin-frames goes with --pin: say which joint is held where")
    motion = api.retarget_keyposes(captured, keys, character.skeleton, timeline, fps=fps, reference=outline,
                                   pin=held)
    save_motion(output, motion)
    typer.echo(f"retargeted {motion.frame_count} frames onto {project.name}'s {len(timeline.keys)} key poses "
               f"-> {output}")


@app.command("capture-video")
def capture_video(
    source: Annotated[Path, typer.Argument(
        metavar="INPUT", help="A video, an animated GIF, or a folder (or pattern) of frames.")],
    output: Annotated[Path, typer.Option(
        "-o", "--output", help="The captured shape of every frame to write (a contours file, .json).")],
    keys_file: Annotated[Path | None, typer.Option(
        "--keys", help="The layer's outline at each key frame, in correspondence (a contours or SVG file; "
                       "one outline: affine motion only).")] = None,
    key_frames: Annotated[str | None, typer.Option(
        "--key-frames", help="The frames the --keys outlines are drawn on, from 0, e.g. 0,8,16 "
                             r"\[default: 0, for one outline].")] = None,
    pick: Annotated[str | None, typer.Option(
        "--pick", help="Instead of --keys: X,Y on the layer in frame --at; its colour region is the layer "
                       "(affine motion only).")] = None,
    at: Annotated[int, typer.Option("--at", min=0, help="With --pick: the frame picked in.")] = 0,
    tolerance: Annotated[int, typer.Option(
        "--tolerance", min=1, max=255,
        help="With --pick: the colour step, per channel, allowed between neighbouring pixels of the "
             "layer; the layer's colours stay within three steps of the one picked.")] = 24,
    motion_file: Annotated[Path | None, typer.Option(
        "--motion", help="Also write the key-shape motion of the captured shapes, with the --keys outlines "
                         "as keys (for 'retarget-keyshapes').")] = None,
    report: Annotated[Path | None, typer.Option(
        "--report", help="Also write each frame's iterations, residual, affine and weights (.csv).")] = None,
    overlay: Annotated[Path | None, typer.Option(
        "--overlay", help="Also draw the captured shape on the footage: OUT.mp4, OUT.gif or a folder."
    )] = None,
    eigen: Annotated[int, typer.Option("--eigen", min=0, max=100, help="Eigen-images kept, at most.")] = 10,
    inbetweens: Annotated[int, typer.Option(
        "--inbetweens", min=0, max=100, help="ARAP in-betweens per pair of keys.")] = 5,
    largest: Annotated[float, typer.Option(
        "--largest", min=16, help="A layer wider or taller than this (px) is captured on frames shrunk by a "
                                  "whole factor, for speed.")] = 200.0,
    fps: Annotated[float | None, typer.Option(
        "--fps", help="Frame rate \\[default: the video's, else 24].")] = None,
    points: Points = None,
    start: Start = None,
) -> None:
    """Capture a cartoon layer straight from footage: affine motion and key-images (Bregler et
    al. 3.3), tracked from the first key frame both ways. See docs/keyshapes.md.
    """
    options.suffix(output, ".json", "an output", why="captured shapes are a contours file (JSON); ")
    if motion_file is not None:
        options.suffix(motion_file, ".json", "a motion", why="a key-shape motion is JSON; ")
    if report is not None:
        options.suffix(report, ".csv", "a report", why="the report is CSV; ")
    if overlay is not None:
        animation_format(overlay)
    if (keys_file is None) == (pick is None):
        raise SettingsError("give the layer: either --keys OUTLINES.json (and --key-frames) or --pick X,Y")
    if pick is not None and (key_frames is not None or motion_file is not None):
        raise SettingsError("--pick gives one outline, on frame --at: --key-frames and --motion go with "
                            "--keys")
    spot = None if pick is None else options.point(pick, "--pick")
    frames, video_fps = load_frames(source)
    rate = fps if fps is not None else video_fps or 24.0
    if spot is not None:
        if at >= len(frames):
            raise SettingsError(f"--at {at} is outside the footage's {len(frames)} frames")
        picked = api.pick_layer(frames[at], spot, tolerance=tolerance, points=points or 100)
        keys, closed, frames_at = picked[None], True, [at]
    else:
        assert keys_file is not None  # checked above
        keys, _, closed = load_contours(keys_file, points=points, start=_start(start, points))
        frames_at = [0] if key_frames is None and len(keys) == 1 else _key_frames(key_frames, len(keys))
    with options.progress("capturing") as report_progress:
        found = api.capture_video(frames, keys, key_frames=frames_at, closed=closed, inbetweens=inbetweens,
                                  eigen=eigen, largest=largest, progress=report_progress)
    save_contours(output, found.shapes, fps=rate, closed=closed)
    if motion_file is not None:
        save_keymotion(motion_file, api.capture_contours(found.shapes, keys), fps=rate, space="keys")
    if report is not None:
        save_video_report(report, found)
    if overlay is not None:
        pictures = (_opaque(draw_shape(frame, shape, closed=closed))
                    for frame, shape in zip(frames, found.shapes, strict=True))
        save_animation(overlay, pictures, fps=rate, background=(255, 255, 255))
    typer.echo(f"captured {len(found.shapes)} frames with {len(keys)} key frame(s) and "
               f"{found.weights.shape[1]} eigen-images: {found.iterations.mean():.1f} iterations a frame, "
               f"residual {found.residual.mean():.3g} -> {output}")


def _opaque(rgb: NDArray[np.uint8]) -> NDArray[np.uint8]:
    return np.dstack([rgb, np.full(rgb.shape[:2], 255, np.uint8)])


def _frame_list(text: str, option: str) -> list[int]:
    try:
        return [int(f) for f in text.split(",")]
    except ValueError:
        raise SettingsError(f"{option} takes frame numbers separated by commas, got {text!r}") from None


def _key_frames(text: str | None, count: int) -> list[int]:
    if text is None:
        raise SettingsError(f"--key-frames: say which frames the {count} outlines are drawn on, e.g. 0,8,16")
    frames = _frame_list(text, "--key-frames")
    if len(frames) != count:
        raise SettingsError(f"--key-frames names {len(frames)} frames for {count} outlines: one frame each")
    return frames


def _start(text: str | None, points: int | None) -> tuple[float, float] | None:
    if text is not None and points is None:
        raise SettingsError("--start goes with --points: it says where the resampled contours begin")
    return None if text is None else options.point(text, "--start")


@app.command("retarget-line")
def retarget_line(
    lines_file: Annotated[Path, typer.Argument(
        metavar="LINES.json|LINES.csv|LINES.svg",
        help="The line of action of every frame: open lines (an SVG file's paths, in order).")],
    project: Annotated[Path, typer.Option("--project", help="The rigged character to bend.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="The motion to write (.json).")],
    keys_file: Annotated[Path | None, typer.Option(
        "--keys", help="Key lines, in correspondence with the lines (a contours or SVG file).")] = None,
    key_frames: Annotated[str | None, typer.Option(
        "--key-frames", help="Or: the lines of these frames (numbered from 0) are the keys, e.g. 0,8,20.")
    ] = None,
    chain: Annotated[str | None, typer.Option(
        "--chain", help="Joints along the line, parent to child, e.g. hip,torso,neck,head "
                        "\\[default: from the root to the joint farthest from it].")] = None,
    direction: Annotated[str, typer.Option(
        "--direction", help="Which end the lines start at: auto, root-first or tip-first.")] = "auto",
    pin: Annotated[str | None, typer.Option(
        "--pin", help="Hold a joint at a place on every frame, e.g. left_foot=140,280.")] = None,
    lower: Annotated[float, typer.Option("--lower", help="Each key line's weight lower bound.")] = -0.5,
    upper: Annotated[float, typer.Option("--upper", help="Each key line's weight upper bound.")] = 1.5,
    support: Annotated[int | None, typer.Option(
        "--support", min=1, help="At most this many non-zero weights.")] = None,
    points: Annotated[int | None, typer.Option(
        "--points", min=3, max=100_000,
        help="Resample every line (open: first point to last) to this many points by arc length.")] = None,
) -> None:
    """Capture a line of action and bend a character's chain of joints along it (Bregler et al. 4).

    Each frame's line is captured with the key lines; the chain's joints then sit along the
    model's line, bones keeping their lengths, the rest of the body hanging rigidly from the chain
    (docs/keyshapes.md). Render the motion with 'toonmotion animate PROJECT OUT.json -o OUT.gif'.
    """
    options.suffix(output, ".json", "an output", why="a motion is JSON; ")
    if (keys_file is None) == (key_frames is None):
        raise SettingsError("give the key lines: either --keys KEYLINES.json or --key-frames 0,8,20")
    held = None if pin is None else options.named_point(pin, "--pin")
    lines, fps, _ = load_contours(lines_file, points=points, closed=False)
    if keys_file is not None:
        keys, _, _ = load_contours(keys_file, points=points, closed=False)
    else:
        assert key_frames is not None  # checked above
        keys = lines[_frames(key_frames, len(lines))]
    character = api.load_project(project)
    motion = api.retarget_line_of_action(
        lines, keys, character.skeleton, chain=chain, direction=direction, fps=fps, lower=lower, upper=upper,
        support=support, pin=None if held is None else (held[0], dict.fromkeys(range(len(lines)), held[1])))
    save_motion(output, motion)
    typer.echo(f"retargeted {motion.frame_count} frames of the line of action ({len(keys)} key lines) onto "
               f"{project.name}'s {'chain ' + chain if chain else 'default chain'} -> {output}")


def _frames(text: str, count: int) -> list[int]:
    try:
        frames = [int(f) for f in text.split(",")]
    except ValueError:
        frames = []
    if not frames or min(frames) < 0 or max(frames) >= count:
        raise SettingsError(f"--key-frames takes frame numbers from 0 to {count - 1} separated by commas, "
                            f"got {text!r}")
    return frames
