"""The ``toonmotion`` command line: parse, call the library, report.

Errors the user can fix print one line, ``toonmotion: error: ...``, and exit with status 2.
"""

import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from toonmotion import __version__
from toonmotion.errors import SettingsError, ToonmotionError
from toonmotion.io.image import DEFAULT_MAX_PIXELS, load_image, load_mask, save_png
from toonmotion.io.project import load_project, save_project
from toonmotion.io.skeleton_json import load_skeleton_file, save_skeleton_json
from toonmotion.render.overview import render_overview
from toonmotion.rig.character import RigSettings
from toonmotion.rig.pipeline import STAGES, rig_drawing
from toonmotion.samples import sample_character

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="toonmotion: 2D character animation from one drawing.",
)
_err = Console(stderr=True)


def _version(value: bool):
    if value:
        typer.echo(f"toonmotion {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version.")
    ] = False,
):
    """toonmotion: 2D character animation from one drawing."""


@app.command()
def rig(
    image: Annotated[Path, typer.Argument(help="The drawing: PNG, JPEG, BMP or any image Pillow reads.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Project folder to write.")],
    mask: Annotated[
        Path | None, typer.Option("--mask", help="Mask image (white or opaque = figure).")
    ] = None,
    skeleton: Annotated[
        Path | None,
        typer.Option("--skeleton", help="Skeleton: an Animated Drawings char_cfg.yaml or a .json."),
    ] = None,
    spacing: Annotated[
        float | None, typer.Option("--spacing", help="Mesh spacing in pixels.", min=1.0)
    ] = None,
    vertices: Annotated[
        int | None,
        typer.Option("--vertices", help="Target mesh vertex count \\[default: 1500].", min=3),
    ] = None,
    refine_joints: Annotated[
        bool, typer.Option("--refine-joints", help="Denser mesh around joints.")
    ] = False,
    tolerance: Annotated[
        float | None,
        typer.Option("--tolerance", help="Outline simplification in pixels \\[default: auto].", min=0),
    ] = None,
    largest_only: Annotated[
        bool, typer.Option("--largest-only", help="Keep only the largest part of the figure.")
    ] = False,
    background: Annotated[
        str,
        typer.Option("--background", help="Background model without alpha or mask: auto, flat, paper."),
    ] = "auto",
    max_pixels: Annotated[
        int, typer.Option("--max-pixels", help="Refuse larger images.", min=1)
    ] = DEFAULT_MAX_PIXELS,
):
    """Rig a drawing: silhouette, mesh, curve skeleton, skeleton and decomposition."""
    if spacing is not None and vertices is not None:
        raise SettingsError("give either --spacing or --vertices, not both")
    texture = load_image(image, max_pixels=max_pixels)
    size = (texture.shape[1], texture.shape[0])
    figure = load_mask(mask, size=size, max_pixels=max_pixels) if mask else None
    bones = load_skeleton_file(skeleton, image_size=size) if skeleton else None
    settings = RigSettings(
        spacing=spacing,
        vertices=vertices,
        tolerance=tolerance,
        refine_joints=refine_joints,
        largest_only=largest_only,
        segmentation=background,
    )
    with _progress() as bar:
        task = bar.add_task("rigging", total=len(STAGES))

        def report(stage, index, count):
            bar.update(task, completed=index, description=stage)

        character = rig_drawing(
            texture, mask=figure, skeleton=bones, settings=settings, progress=report
        )
        bar.update(task, completed=len(STAGES), description="saving")
        save_project(output, character)
    mesh = character.mesh
    typer.echo(
        f"rigged {image.name}: {len(mesh.V)} vertices, {len(mesh.F)} triangles, "
        f"{len(character.skeleton)} joints -> {output}"
    )


@app.command()
def show(
    project: Annotated[Path, typer.Argument(help="Project folder made by 'toonmotion rig'.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file to write.")],
    height: Annotated[int, typer.Option("--height", help="Panel height in pixels.", min=64)] = 720,
):
    """Draw a project's rig: mesh, curve skeleton, skeleton and decomposition."""
    if output.suffix.lower() != ".png":
        raise SettingsError(f"the overview is a PNG; give an output ending in .png, not {output.name}")
    character = load_project(project)
    save_png(output, render_overview(character, height=height))
    typer.echo(f"wrote {output}")


@app.command()
def sample(
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file for the drawing.")],
    skeleton: Annotated[
        Path | None, typer.Option("--skeleton", help="Also write its skeleton (.json or .yaml).")
    ] = None,
):
    """Write toonmotion's bundled sample character (and its skeleton) to try things on."""
    if skeleton is not None and skeleton.suffix.lower() not in (".json", ".yaml", ".yml"):
        raise SettingsError(
            f"give a skeleton file ending in .json or .yaml (so 'rig' can read it back), "
            f"not {skeleton.name}"
        )
    rgba, bones = sample_character()
    save_png(output, rgba)
    if skeleton is not None:
        size = (rgba.shape[1], rgba.shape[0])
        if skeleton.suffix.lower() in (".yaml", ".yml"):
            from toonmotion.io.char_cfg import save_char_cfg

            save_char_cfg(skeleton, bones, size)
        else:
            save_skeleton_json(skeleton, bones, size)
    typer.echo(f"wrote {output}" + (f" and {skeleton}" if skeleton else ""))


def _progress():
    return Progress(
        TextColumn("{task.description:<15}"),
        BarColumn(),
        TimeElapsedColumn(),
        console=_err,
        transient=True,
        disable=not _err.is_terminal,
    )


def main(argv=None):
    """Entry point: run the CLI, turning user errors into one line and exit status 2."""
    try:
        app(args=argv, prog_name="toonmotion", standalone_mode=True)
    except ToonmotionError as error:
        print(f"toonmotion: error: {error}", file=sys.stderr)
        sys.exit(2)
    except OSError as error:  # an output path that cannot be written, a full disk, ...
        print(f"toonmotion: error: {error}", file=sys.stderr)
        sys.exit(2)


if __name__ == "__main__":
    main()
