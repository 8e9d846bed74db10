"""Rigging commands: ``rig``, ``show``, ``sample``, ``remesh``."""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Annotated

import typer

from toonmotion import api
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.errors import SettingsError
from toonmotion.io.char_cfg import save_char_cfg
from toonmotion.io.image import save_png
from toonmotion.io.pose_json import save_keyframes
from toonmotion.io.skeleton_json import save_skeleton_json
from toonmotion.render.overview import render_overview
from toonmotion.rig.character import RigSettings
from toonmotion.rig.edits import describe as describe_edit
from toonmotion.rig.pipeline import coarse_mesh_warning, remesh
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_character


@app.command()
def rig(
    image: Annotated[Path, typer.Argument(help="The drawing: PNG, JPEG, BMP or any image Pillow reads.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Project folder to write.")],
    mask: Annotated[Path | None, typer.Option(
        "--mask", help="Mask image (white or opaque = figure).")] = None,
    skeleton: Annotated[Path | None, typer.Option(
        "--skeleton", help="Skeleton: an Animated Drawings char_cfg.yaml or a .json.")] = None,
    spacing: Annotated[float | None, typer.Option(
        "--spacing", help="Mesh spacing in pixels.", min=1.0)] = None,
    vertices: Annotated[int | None, typer.Option(
        "--vertices", help="Target mesh vertex count \\[default: 1500].", min=3)] = None,
    refine_joints: Annotated[bool, typer.Option(
        "--refine-joints", help="Denser mesh around joints.")] = False,
    tolerance: Annotated[float | None, typer.Option(
        "--tolerance", help="Outline simplification in pixels \\[default: auto].", min=0)] = None,
    largest_only: Annotated[bool, typer.Option(
        "--largest-only", help="Keep only the largest part of the figure.")] = False,
    background: Annotated[str, typer.Option(
        "--background", help="Background model without alpha or mask: auto, flat, paper.")] = "auto",
    decomposition: Annotated[str, typer.Option(
        "--decomposition", help="Which bone each part follows: geodesic (nearest through the drawing: curls "
        "and thin curved limbs stay whole; the default) or straight (the thesis's rule).")] = "geodesic",
    max_pixels: Annotated[int | None, typer.Option(
        "--max-pixels", help="Refuse larger images \\[default: the image_pixels limit].", min=1)] = None,
) -> None:
    """Rig a drawing: silhouette, mesh, curve skeleton, skeleton and decomposition."""
    if spacing is not None and vertices is not None:
        raise SettingsError("give either --spacing or --vertices, not both")
    settings = RigSettings(spacing=spacing, vertices=vertices, tolerance=tolerance,
                           refine_joints=refine_joints, largest_only=largest_only,
                           segmentation=background, decomposition=decomposition)
    with options.progress("rigging") as report:
        character = api.rig_image(
            image, mask=mask, skeleton=skeleton, settings=settings, max_pixels=max_pixels, progress=report
        )
        report("saving", 1, 1)
        api.save_project(output, character)
    mesh = character.mesh
    typer.echo(
        f"rigged {image.name}: {len(mesh.V)} vertices, {len(mesh.F)} triangles, "
        f"{len(character.skeleton)} joints -> {output}"
    )
    _warn_if_coarse(character)


@app.command()
def show(
    project: options.Project,
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file to write.")],
    height: Annotated[int, typer.Option("--height", help="Panel height in pixels.", min=64)] = 720,
) -> None:
    """Draw a project's rig: mesh, curve skeleton, skeleton and decomposition."""
    options.suffix(output, ".png", "an output", why="the overview is a PNG; ")
    save_png(output, render_overview(api.load_project(project), height=height))
    typer.echo(f"wrote {output}")


@app.command()
def sample(
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file for the drawing.")],
    skeleton: Annotated[Path | None, typer.Option(
        "--skeleton", help="Also write its skeleton (.json or .yaml).")] = None,
    keys: Annotated[Path | None, typer.Option(
        "--keys", help="Also write built-in key-frames for it (.json).")] = None,
) -> None:
    """Write toonmotion's bundled sample character (and its skeleton, key-frames) to try things on."""
    if skeleton is not None and skeleton.suffix.lower() not in (".json", ".yaml", ".yml"):
        raise SettingsError(
            f"give a skeleton file ending in .json or .yaml (so 'rig' can read it back), not {skeleton.name}"
        )
    if keys is not None:
        options.suffix(keys, ".json", "a key-frames file")
    rgba, bones = sample_character()
    save_png(output, rgba)
    written = [output]
    if skeleton is not None:
        size = (rgba.shape[1], rgba.shape[0])
        if skeleton.suffix.lower() in (".yaml", ".yml"):
            save_char_cfg(skeleton, bones, size)
        else:
            save_skeleton_json(skeleton, bones, size)
        written.append(skeleton)
    if keys is not None:
        save_keyframes(keys, bones, sample_keyframes(bones))
        written.append(keys)
    typer.echo("wrote " + ", ".join(str(p) for p in written))


@app.command("remesh")
def remesh_project(
    project: options.Project,
    spacing: Annotated[float | None, typer.Option("--spacing", help="Mesh spacing in pixels.")] = None,
    vertices: Annotated[int | None, typer.Option("--vertices", help="Target mesh vertex count.")] = None,
    refine_joints: Annotated[bool | None, typer.Option(
        "--refine-joints/--no-refine-joints", help="Denser mesh around joints.")] = None,
) -> None:
    """Mesh a project again (finer or coarser), keeping its skeleton and replaying its edits."""
    if spacing is None and vertices is None and refine_joints is None:
        raise SettingsError("give --spacing, --vertices or --refine-joints to say how to mesh again")
    if spacing is not None and vertices is not None:
        raise SettingsError("give either --spacing or --vertices, not both")
    character = api.load_project(project)
    old = character.settings
    density = spacing is not None or vertices is not None
    settings = dataclasses.replace(
        old,
        spacing=spacing if density else old.spacing,
        vertices=vertices if density else old.vertices,
        refine_joints=old.refine_joints if refine_joints is None else refine_joints,
    )
    character, skipped = remesh(character, settings)
    api.save_project(project, character)
    count = len(character.edits)
    typer.echo(
        f"remeshed {project.name}: {len(character.mesh.V)} vertices, {len(character.mesh.F)} triangles; "
        f"{count} edit{'' if count == 1 else 's'} replayed"
    )
    for edit, reason in skipped:
        options.warn(f"dropped an edit that no longer applies ({describe_edit(edit)}): {reason}")
    _warn_if_coarse(character)


def _warn_if_coarse(character: api.Character) -> None:
    warning = coarse_mesh_warning(character)
    if warning:
        options.warn(warning)
