"""The ``export`` command: an animation into glTF, Spine, a sprite sheet or transparent video."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from toonmotion import api
from toonmotion.cli import options
from toonmotion.cli.animation import make_animation
from toonmotion.cli.app import app
from toonmotion.deform.deformer import DeformSettings


@app.command()
@options.deform_options
def export(
    project: options.Project,
    keys_file: options.KeysFile,
    output: Annotated[Path, typer.Option(
        "-o", "--output", help="File to write: .glb, .json (with --format), .apng/.png, .webp, .webm, "
        ".gif, .mp4, or a folder for PNG frames.")],
    format: Annotated[str | None, typer.Option(
        "--format", help="glb, spine, sheet, apng, webp, webm, gif, mp4 or png \\[default: from the "
        "output's name; .json needs spine or sheet].")] = None,
    fps: options.Fps = None,
    ease: options.Ease = None,
    exaggerate: options.Exaggerate = None,
    sigma: options.Sigma = 3.0,
    shift: options.Shift = 0.0,
    solve_inbetweens: options.SolveInbetweens = False,
    size: options.Size = None,
    background: Annotated[str | None, typer.Option(
        "--background", help="Pictures: transparent, white, black or #rrggbb \\[default: transparent; GIF "
        "and MP4 over white].")] = None,
    padding: Annotated[int, typer.Option("--padding", help="Sprite sheet: pixels between frames.")] = 2,
    no_trim: Annotated[bool, typer.Option(
        "--no-trim", help="Sprite sheet: keep whole frames instead of cropping to what is drawn.")] = False,
    max_size: Annotated[int, typer.Option(
        "--max-size", help="Sprite sheet: the largest width or height, pixels.")] = 4096,
    deform: DeformSettings = options.DEFAULT_DEFORM,
) -> None:
    """Export an animation for other tools: a skinned glTF or Spine rig, a sprite sheet, or frames.

    .glb (glTF 2.0: Blender, game engines, three.js) and Spine JSON replay the animation on the
    drawing itself: bones carry the needle model, per-frame offsets carry stage two, and the
    frames match toonmotion's. A sprite sheet is one PNG and a JSON atlas in TexturePacker's
    hash layout (Phaser, PixiJS, Godot). APNG, WebP and WebM keep soft transparent edges.
    """
    kind = api.export_format(output, format)
    exaggeration = options.filter_settings(exaggerate, sigma, shift)
    character, animation, what = make_animation(project, keys_file, settings=deform, fps=fps, ease=ease,
                                                exaggeration=exaggeration, solve_inbetweens=solve_inbetweens)
    colour = None if background is None else options.colour(background)
    with options.progress("exporting") as report:
        done = api.export_animation(output, character, animation, format=kind, settings=deform,
                                    size=options.size(size), background=colour, padding=padding,
                                    trim=not no_trim, max_size=max_size, progress=report)
    typer.echo(
        f"exported {what} as {kind}: {done.frames} frames at {animation.motion.fps:g} fps"
        + (f", {done.size[0]}x{done.size[1]}" if done.size is not None else "")
        + f" -> {', '.join(str(p) for p in done.files)}"
    )
