"""Capture commands: ``track`` (joints through footage) and ``retarget`` (onto a rigged drawing)."""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from numpy.typing import NDArray

from toonmotion import api
from toonmotion.cli import options
from toonmotion.cli.animation import write
from toonmotion.cli.app import app
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import SettingsError
from toonmotion.io.frames import load_frames
from toonmotion.io.motion_json import load_motion, save_motion, save_motion_csv
from toonmotion.io.track_json import load_joints, save_joints
from toonmotion.io.video import animation_format, save_animation
from toonmotion.render.track_overlay import draw_tracking


@app.command()
def track(
    source: Annotated[Path, typer.Argument(
        metavar="INPUT", help="A video, an animated GIF, or a folder (or pattern) of frames.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Motion file to write (.json).")],
    joints: Annotated[Path | None, typer.Option(
        "--joints", help="Joint rectangles to track (.json) \\[default: suggested from frame 1].")] = None,
    overlay: Annotated[Path | None, typer.Option(
        "--overlay", help="Also draw the tracked joints on the footage: OUT.mp4, OUT.gif or a folder."
    )] = None,
    csv: Annotated[Path | None, typer.Option("--csv", help="Also write the motion as CSV.")] = None,
    search: Annotated[float | None, typer.Option(
        "--search", help="Search radius in pixels \\[default: from each rectangle].")] = None,
    background: Annotated[str | None, typer.Option(
        "--background", help="Flat background colour #rrggbb: joints are suggested on the figure that "
        "differs from it, and held to it \\[default: the border's colour if flat, else estimated from "
        "the sequence, and joints are free].")] = None,
    free: Annotated[bool, typer.Option(
        "--free", help="Do not hold joints to the figure on a flat background.")] = False,
    frame_by_frame: Annotated[bool, typer.Option(
        "--frame-by-frame", help="Keep each frame's own choice of where the joints are: do not choose "
        "their paths again over the whole clip (hidden spans are still filled in).")] = False,
    both_ways: Annotated[bool, typer.Option(
        "--both-ways", help="Also track backwards from the last frame, and choose each joint's path "
        "between the two ways: fewer joints lost for a stretch, in about twice the time.")] = False,
    steady_light: Annotated[bool, typer.Option(
        "--steady-light", help="Take the frames as they are: do not map each frame's brightness and "
        "contrast back to those of the frame tracking starts from (for exposure changes and "
        "flicker).")] = False,
    full_resolution: Annotated[bool, typer.Option(
        "--full-resolution", help="Track footage larger than 1000 px at its own size: by default it "
        "is halved until it fits, two to three times as fast.")] = False,
    fps: Annotated[float | None, typer.Option(
        "--fps", help="Frame rate \\[default: the video's, else 24].")] = None,
    resume: Annotated[Path | None, typer.Option(
        "--resume", help="Correct this earlier tracking (with --at and --set).")] = None,
    at: Annotated[int | None, typer.Option("--at", help="Frame where --set places joints.")] = None,
    corrections: Annotated[list[str] | None, typer.Option(
        "--set", help="NAME=X,Y: a joint's true position at --at (repeat); tracking resumes there.")] = None,
) -> None:
    """Track a character's joints through footage (thesis ch. 4) into a motion file."""
    options.suffix(output, ".json", "a motion file")
    if csv is not None:
        options.suffix(csv, ".csv", "a CSV file")
    if (resume is None) != (at is None) or (resume is None) != (not corrections):
        raise SettingsError(
            "--resume, --at and --set go together: the earlier motion, the frame and the joints"
        )
    if resume is not None and joints is None:
        raise SettingsError("--resume needs the --joints file the tracking used (for the rectangle sizes)")
    if overlay is not None:
        animation_format(overlay)
    if both_ways and frame_by_frame:
        raise SettingsError("--both-ways and --frame-by-frame do not go together: the paths are chosen "
                            "between the two ways over the whole clip")
    flat = None if background is None else _drawn_on(background)  # checked even when unused
    frames, video_fps = load_frames(source)
    rate = fps if fps is not None else video_fps or 24.0  # a given fps is checked by the motion
    start = 0
    if joints is not None:
        skeleton, sizes, start = load_joints(joints)
        given = True
    else:
        given = False
        skeleton, sizes = api.suggest_joints(frames, colour=flat)
        joints = output.with_name(output.stem + ".joints.json")
        save_joints(joints, skeleton, sizes)
        options.warn(f"suggested {len(skeleton)} joints from frame 0 on {_figure_said(frames[0], flat)} "
                      f"-> {joints} (edit it, pass --joints)")
    settings = api.TrackSettings(search=search, figure=not free, best_path=not frame_by_frame,
                                 both_ways=both_ways, relight=not steady_light)
    if full_resolution:
        settings = replace(settings, working_side=None)
    with options.progress("tracking") as report:
        captured = api.track_footage(
            frames,
            joints=(skeleton, sizes),
            start=start,
            fps=rate,
            settings=settings,
            background=flat,
            earlier=None if resume is None else load_motion(resume),
            corrections=dict(options.named_point(c, "--set") for c in corrections or ()),
            at=at,
            progress=report,
        )
    motion = captured.motion
    save_motion(output, motion)
    if given:  # what may have gone wrong from the start (after the run: a refusal is one line)
        for warning in api.setup_warnings(frames, skeleton, sizes, start=start, colour=flat):
            options.warn(warning)
    if csv is not None:
        save_motion_csv(csv, motion)
    if overlay is not None:
        save_animation(
            overlay, _tracking_pictures(frames, captured, sizes), fps=rate, background=(255, 255, 255)
        )
    held = int(captured.held.sum())
    repeats = f"{held} frames repeat the frame before (drawn on twos or threes); " if held else ""
    poorly = f"{captured.poor_fraction:.0%} of joint-frames matched poorly (hidden or changed)"
    typer.echo(
        f"tracked {len(skeleton)} joints through {motion.frame_count} frames (from frame {captured.first}); "
        f"{repeats}{poorly} -> {output}"
    )
    poor = captured.poorly_matched()
    if poor:
        said = ", ".join(f"{joint.name} in {joint.fraction:.0%} of frames (longest from frame {joint.start}, "
                         f"{joint.length} frame{'s' if joint.length > 1 else ''})" for joint in poor)
        typer.echo(f"matched poorly most: {said}; where one is lost, put it right with "
                   f"--joints {joints} --resume {output} --at FRAME --set NAME=X,Y -o FIXED.json")


def _figure_said(frame, flat):
    """Which figure the joints were suggested on, for the user."""
    if flat is not None:
        return f"the figure drawn on {_hex(flat)}"
    border = api.border_colour(frame)
    if border is None:
        return "what differs from a background taken over the whole clip"
    return f"the figure that differs from the border's colour {_hex(border)} (--background sets another)"


def _hex(colour):
    return "#" + "".join(f"{v:02x}" for v in colour)


def _drawn_on(text: str) -> tuple[int, int, int]:
    """track's ``--background``: the colour the footage is drawn on (not ``transparent``)."""
    try:
        colour = options.colour(text)
    except SettingsError:
        colour = None
    if colour is None:
        raise SettingsError(
            f"track's --background is the colour the footage is drawn on (white, black or #rrggbb), "
            f"got {text!r}"
        )
    return colour


@app.command("retarget")
@options.deform_options
def retarget_command(
    motion_file: Annotated[Path, typer.Argument(metavar="MOTION.json", help="A captured motion.")],
    project: options.Project,
    output: options.AnimationOutput,
    size: options.Size = None,
    background: options.AnimationBackground = None,
    overlay: options.Overlay = "",
    joint_map: Annotated[str | None, typer.Option(
        "--map", help="Target joints named differently: TARGET=SOURCE[,TARGET=SOURCE...].")] = None,
    exaggerate: Annotated[float | None, typer.Option(
        "--exaggerate", help="Cartoon filter strength A on the retargeted motion.")] = None,
    sigma: options.Sigma = 3.0,
    shift: options.Shift = 0.0,
    deform: DeformSettings = options.DEFAULT_DEFORM,
) -> None:
    """Replay a captured motion on a rigged drawing (thesis 4.5); the result is kept in the project."""
    kind = animation_format(output)
    picture_size = options.size(size)  # checked before the frames are worked out
    character = api.load_project(project)
    captured = load_motion(motion_file)
    motion = api.retarget(captured, character.skeleton, joint_map=_joint_map(joint_map))
    motion = api.exaggerate(motion, options.filter_settings(exaggerate, sigma, shift))
    animation = api.animate_character(
        character, motion,
        settings=deform
    )
    count, _ = write(
        output, character, animation, kind=kind, size=picture_size, background=background, overlay=overlay
    )
    kept = Path(project) / "motions" / f"{motion_file.stem}.json"
    save_motion(kept, motion)
    typer.echo(
        f"retargeted {captured.frame_count} frames onto {project.name}: {count} frames at "
        f"{motion.fps:g} fps -> {output} (motion kept in {kept})"
    )


def _joint_map(text: str | None) -> dict[str, str]:
    mapping = {}
    for item in (text or "").split(","):
        if item.strip():
            target, sep, source = item.partition("=")
            if not sep or not target.strip() or not source.strip():
                raise SettingsError(f"--map takes TARGET=SOURCE pairs separated by commas, got {item!r}")
            mapping[target.strip()] = source.strip()
    return mapping


def _tracking_pictures(
    frames: NDArray[np.uint8], captured: api.Capture, sizes: NDArray[np.float64]
) -> Iterator[NDArray[np.uint8]]:
    """The footage with the tracked rectangles and bones drawn on, opaque RGBA."""
    motion = captured.motion
    for t in range(motion.frame_count):
        confidence = None if motion.confidence is None else motion.confidence[t]
        rgb = draw_tracking(
            frames[captured.first + t],
            motion.positions[t],
            sizes,
            motion.skeleton.parents,
            angles=captured.angles[t],
            confidence=confidence,
        )
        yield np.concatenate([rgb, np.full(rgb.shape[:2] + (1,), 255, dtype=np.uint8)], axis=2)
