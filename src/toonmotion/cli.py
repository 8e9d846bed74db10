"""The ``toonmotion`` command line: parse, call the library, report.

Errors the user can fix print one line, ``toonmotion: error: ...``, and exit with status 2.
"""

import dataclasses
import sys
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from toonmotion import __version__
from toonmotion.animate.inbetween import animate_frames, solve_keys
from toonmotion.animate.timeline import make_timeline, pose_at
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.deform.depth import find_overlaps, set_region_depth
from toonmotion.errors import SettingsError, ToonmotionError
from toonmotion.io.image import DEFAULT_MAX_PIXELS, load_image, load_mask, save_png
from toonmotion.io.pose_json import load_keyframes, load_pose, save_keyframes
from toonmotion.io.project import load_project, save_project
from toonmotion.io.skeleton_json import load_skeleton_file, save_skeleton_json
from toonmotion.io.video import animation_format, save_animation
from toonmotion.render.frame import check_overlays, fit_view, natural_size, render_frame
from toonmotion.render.overview import render_overview
from toonmotion.rig.character import RigSettings
from toonmotion.rig.pipeline import STAGES, rig_drawing
from toonmotion.sample_animation import sample_keyframes
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

        character = rig_drawing(texture, mask=figure, skeleton=bones, settings=settings, progress=report)
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
    keys: Annotated[
        Path | None, typer.Option("--keys", help="Also write built-in key-frames for it (.json).")
    ] = None,
):
    """Write toonmotion's bundled sample character (and its skeleton, key-frames) to try things on."""
    if skeleton is not None and skeleton.suffix.lower() not in (".json", ".yaml", ".yml"):
        raise SettingsError(
            f"give a skeleton file ending in .json or .yaml (so 'rig' can read it back), "
            f"not {skeleton.name}"
        )
    if keys is not None and keys.suffix.lower() != ".json":
        raise SettingsError(f"give a key-frames file ending in .json, not {keys.name}")
    rgba, bones = sample_character()
    save_png(output, rgba)
    written = [output]
    if skeleton is not None:
        size = (rgba.shape[1], rgba.shape[0])
        if skeleton.suffix.lower() in (".yaml", ".yml"):
            from toonmotion.io.char_cfg import save_char_cfg

            save_char_cfg(skeleton, bones, size)
        else:
            save_skeleton_json(skeleton, bones, size)
        written.append(skeleton)
    if keys is not None:
        save_keyframes(keys, bones, sample_keyframes(bones))
        written.append(keys)
    typer.echo("wrote " + ", ".join(str(p) for p in written))


_Project = Annotated[Path, typer.Argument(help="Project folder made by 'toonmotion rig'.")]
_Size = Annotated[
    str | None, typer.Option("--size", help="Output WxH pixels \\[default: the view at 1:1].")
]
_Overlay = Annotated[str, typer.Option("--overlay", help="Comma list of mesh, skeleton, rest.")]
_NoArea = Annotated[
    bool, typer.Option("--no-area", help="Do not preserve area when bones stretch.")
]
_StageOne = Annotated[
    bool, typer.Option("--stage-one", help="Needle model only, no joint-area solve.")
]
_Weights = Annotated[str, typer.Option("--weights", help="Stage-two weights w1,w2,w3.")]
_JointWidth = Annotated[
    float,
    typer.Option("--joint-width", help="Joint-area size, in limb half-thicknesses.", min=0),
]


@app.command()
def pose(
    project: _Project,
    pose_file: Annotated[
        Path,
        typer.Argument(metavar="POSE.json", help="Joint positions by name (a pose or skeleton file)."),
    ],
    output: Annotated[Path, typer.Option("-o", "--output", help="PNG file to write.")],
    size: _Size = None,
    background: Annotated[
        str, typer.Option("--background", help="transparent, white, black or #rrggbb.")
    ] = "transparent",
    overlay: _Overlay = "",
    no_area: _NoArea = False,
    stage_one_only: _StageOne = False,
    weights: _Weights = "1,1,1",
    joint_width: _JointWidth = 1.5,
):
    """Pose a rigged drawing: deform it to a sketched skeleton and render one frame."""
    _png_output(output)
    character = load_project(project)
    posed = load_pose(pose_file, character.skeleton)
    deformer = Deformer(character, _deform_settings(no_area, stage_one_only, weights, joint_width))
    result = deformer.deform(posed)
    view = fit_view(character, [result.U])
    frame = render_frame(
        character,
        result.U,
        pose=posed,
        size=_size(size),
        view=view,
        background=_colour(background),
        overlays=_overlays(overlay),
    )
    save_png(output, frame)
    typer.echo(
        f"posed {project.name}: stage two {result.iterations} "
        f"iterations, energy {result.energy_start:.4g} -> {result.energy:.4g} -> {output}"
    )
    _report_overlaps(character, result.U)


@app.command()
def animate(
    project: _Project,
    keys_file: Annotated[
        Path, typer.Argument(metavar="KEYS.json", help="Key-frames: poses at frame numbers.")
    ],
    output: Annotated[
        Path,
        typer.Option(
            "-o", "--output", help="OUT.gif, OUT.mp4, or a folder (or frame_%04d.png pattern) for PNGs."
        ),
    ],
    fps: Annotated[
        float | None,
        typer.Option("--fps", help="Frames per second \\[default: the key file's, else 24].", min=0.001),
    ] = None,
    size: _Size = None,
    background: Annotated[
        str | None,
        typer.Option(
            "--background",
            help="transparent, white, black or #rrggbb \\[default: white; transparent for PNGs].",
        ),
    ] = None,
    overlay: _Overlay = "",
    ease: Annotated[
        str | None, typer.Option("--ease", help="linear, in-out, in or out \\[default: the key file's].")
    ] = None,
    solve_inbetweens: Annotated[
        bool,
        typer.Option("--solve-inbetweens", help="Run stage two on every frame, not only the keys."),
    ] = False,
    no_area: _NoArea = False,
    stage_one_only: _StageOne = False,
    weights: _Weights = "1,1,1",
    joint_width: _JointWidth = 1.5,
):
    """Animate a rigged drawing through key-frames, with in-betweens, to GIF, MP4 or PNGs."""
    kind = animation_format(output)
    character = load_project(project)
    timeline = load_keyframes(keys_file, character.skeleton, fps=fps)
    if ease is not None:
        timeline = make_timeline(character.skeleton, timeline.keys, fps=timeline.fps, ease=ease)
    colour = _colour(background or ("transparent" if kind == "png" else "white"))
    deformer = Deformer(character, _deform_settings(no_area, stage_one_only, weights, joint_width))
    keys = solve_keys(deformer, timeline)
    method = "solve" if solve_inbetweens else "interpolate"
    meshes = list(animate_frames(deformer, timeline, method=method, keys=keys))
    view = fit_view(character, [U for _, U in meshes])
    out_size = natural_size(view, size=_size(size))
    overlays = _overlays(overlay)
    skeleton = character.skeleton
    with _progress() as bar:
        task = bar.add_task("rendering", total=len(meshes))

        def frames():
            for frame, U in meshes:
                posed = pose_at(skeleton, timeline, frame) if overlays else None
                yield render_frame(
                    character, U, pose=posed, size=out_size, view=view, background=colour, overlays=overlays
                )
                bar.update(task, advance=1)

        count = save_animation(
            output, frames(), fps=timeline.fps, background=colour if colour is not None else (255, 255, 255)
        )
    typer.echo(
        f"animated {len(timeline.keys)} key-frames: {count} frames at {timeline.fps:g} fps, "
        f"{out_size[0]}x{out_size[1]} -> {output}"
    )
    for key, solved in zip(timeline.keys, keys, strict=True):
        _report_overlaps(character, solved.U, where=f"key-frame {key.frame}: ")


@app.command()
def depth(
    project: _Project,
    settings: Annotated[
        list[str] | None,
        typer.Argument(
            metavar="[BONE=N | @X,Y=N]...",
            help="Set a bone region's depth (higher is in front); @X,Y picks the region of "
            "the vertex nearest that point.",
        ),
    ] = None,
):
    """Show or set the depth layers of a project's bone regions (saved in the project)."""
    character = load_project(project)
    names = character.skeleton.bone_names
    layers = np.array(character.depth)
    for item in settings or []:
        target, _, value = item.rpartition("=")
        try:
            value = int(value)
        except ValueError:
            raise SettingsError(f"give a whole-number depth after '=' in {item!r}") from None
        if target.startswith("@"):
            x, y = _numbers(target[1:], 2, "@X,Y")
            vertex = int(np.argmin(np.hypot(*(character.mesh.V - (x, y)).T)))
            layers = set_region_depth(layers, character.binding, vertex, value)
        elif target in names:
            layers[names.index(target)] = value
        else:
            raise SettingsError(f"no bone is called {target!r}; the bones are: {', '.join(names)}")
    if settings:
        save_project(project, dataclasses.replace(character, depth=layers))
    for name, d in zip(names, layers, strict=True):
        typer.echo(f"{name:>20} {d}")


def _deform_settings(no_area, stage_one_only, weights, joint_width):
    return DeformSettings(
        preserve_area=not no_area,
        stage_two=not stage_one_only,
        weights=_numbers(weights, 3, "--weights"),
        joint_width=joint_width,
    )


def _report_overlaps(character, U, *, where=""):
    for o in find_overlaps(character.mesh, character.binding, character.skeleton, U, character.depth):
        if o.same_depth:
            typer.echo(
                f"{where}regions {o.bone_a} and {o.bone_b} overlap ({o.area:.0f} px²) at the same depth; "
                f"set their order with 'toonmotion depth'",
                err=True,
            )


def _png_output(output):
    if output.suffix.lower() != ".png":
        raise SettingsError(f"the frame is a PNG; give an output ending in .png, not {output.name}")


def _numbers(text, count, option):
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(np.isfinite(values)):
        raise SettingsError(f"{option} takes {count} comma-separated numbers, got {text!r}")
    return values


def _size(text):
    if text is None:
        return None
    w, _, h = text.lower().partition("x")
    try:
        size = int(w), int(h)
    except ValueError:
        size = (0, 0)
    if min(size) < 1 or max(size) > 16384:
        raise SettingsError(f"--size takes WxH in pixels, each 1 to 16384, e.g. 1024x1024; got {text!r}")
    return size


def _colour(text):
    named = {"transparent": None, "white": (255, 255, 255), "black": (0, 0, 0)}
    if text.lower() in named:
        return named[text.lower()]
    hexa = text.lstrip("#")
    if len(hexa) == 6:
        try:
            return tuple(int(hexa[i : i + 2], 16) for i in (0, 2, 4))
        except ValueError:
            pass
    raise SettingsError(f"--background takes transparent, white, black or #rrggbb, got {text!r}")


def _overlays(text):
    return check_overlays(o.strip() for o in text.split(",") if o.strip())


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
