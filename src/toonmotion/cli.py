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
from toonmotion.animate.cartoon_filter import FilterSettings, filter_bones, filter_trajectories
from toonmotion.animate.inbetween import animate_frames, motion_frames, solve_keys
from toonmotion.animate.motion import Motion, motion_for, motion_from_timeline
from toonmotion.animate.pose_filter import exaggerate_pose
from toonmotion.animate.timeline import Keyframe, make_timeline
from toonmotion.capture.foreground import border_colour, estimate_background, foreground_masks
from toonmotion.capture.retarget import retarget
from toonmotion.capture.setup import check_setup, suggest_setup
from toonmotion.capture.tracker import Tracking, TrackSettings, TrackSetup, retrack
from toonmotion.capture.tracker import track as track_joints
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.deform.depth import find_overlaps
from toonmotion.deform.tuning import CurveEdit, DragEdit, apply_tuning
from toonmotion.deform.tuning import describe as describe_tuning
from toonmotion.errors import EditError, SettingsError, ToonmotionError
from toonmotion.io.frames import load_frames
from toonmotion.io.image import DEFAULT_MAX_PIXELS, load_image, load_mask, save_png
from toonmotion.io.motion_json import is_motion_file, load_motion, save_motion, save_motion_csv
from toonmotion.io.pose_json import (
    load_keyframes,
    load_pose,
    load_pose_edits,
    save_keyframes,
    save_pose,
)
from toonmotion.io.project import load_project, save_project
from toonmotion.io.skeleton_json import load_skeleton_file, save_skeleton_json
from toonmotion.io.track_json import load_joints, save_joints
from toonmotion.io.video import animation_format, save_animation
from toonmotion.render.frame import check_overlays, fit_view, natural_size, render_frame
from toonmotion.render.overview import render_overview
from toonmotion.render.track_overlay import draw_tracking
from toonmotion.rig.binding import Correction
from toonmotion.rig.character import RigSettings
from toonmotion.rig.edits import DepthEdit, apply_edit, redo, undo
from toonmotion.rig.edits import describe as describe_edit
from toonmotion.rig.pipeline import STAGES, remesh, rig_drawing
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


_Strength = Annotated[
    float, typer.Option("--strength", help="Filter strength A (0 leaves the motion as it is).")
]
_Sigma = Annotated[float, typer.Option("--sigma", help="Filter width in frames.")]
_Shift = Annotated[float, typer.Option("--shift", help="Filter time shift in frames (> 0 delays it).")]


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
    accel: Annotated[
        str | None,
        typer.Option("--accel", help="Cartoon filter: acceleration DX,DY at the root, pixels."),
    ] = None,
    fixed: Annotated[
        str | None, typer.Option("--fixed", help="Joints that stay put under --accel: J[,J...].")
    ] = None,
    root: Annotated[
        str | None, typer.Option("--root", help="Joint --accel acts on \\[default: the skeleton's root].")
    ] = None,
    no_area: _NoArea = False,
    stage_one_only: _StageOne = False,
    weights: _Weights = "1,1,1",
    joint_width: _JointWidth = 1.5,
):
    """Pose a rigged drawing: deform it to a sketched skeleton and render one frame.

    Fine-tuning edits in the pose file (see 'toonmotion tune') are applied. --accel and
    --fixed exaggerate the pose with the single-frame cartoon filter first.
    """
    _png_output(output)
    if (accel is None) != (fixed is None):
        raise SettingsError(
            "--accel and --fixed go together: give the acceleration and the joints that stay put"
        )
    character = load_project(project)
    posed = load_pose(pose_file, character.skeleton)
    edits = load_pose_edits(pose_file)
    if accel is not None:
        posed = exaggerate_pose(character.skeleton, posed, _numbers(accel, 2, "--accel"),
                                _names(fixed), root=root)
    deformer = Deformer(character, _deform_settings(no_area, stage_one_only, weights, joint_width))
    result = apply_tuning(deformer, posed, deformer.deform(posed), edits)
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
        f"iterations, energy {result.energy_start:.4g} -> {result.energy:.4g}"
        + (f", {len(edits)} edit{'s' if len(edits) > 1 else ''}" if edits else "")
        + f" -> {output}"
    )
    _report_view(view, character)
    _report_overlaps(character, result.U)


@app.command()
def animate(
    project: _Project,
    keys_file: Annotated[
        Path,
        typer.Argument(
            metavar="KEYS.json", help="Key-frames (poses at frame numbers) or a motion (a pose per frame)."
        ),
    ],
    output: Annotated[
        Path,
        typer.Option(
            "-o", "--output", help="OUT.gif, OUT.mp4, or a folder (or frame_%04d.png pattern) for PNGs."
        ),
    ],
    fps: Annotated[
        float | None,
        typer.Option("--fps", help="Frames per second \\[default: the file's, else 24]."),
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
    exaggerate: Annotated[
        float | None,
        typer.Option("--exaggerate", help="Cartoon filter strength A: anticipation and follow-through."),
    ] = None,
    sigma: _Sigma = 3.0,
    shift: _Shift = 0.0,
    save_motion_to: Annotated[
        Path | None,
        typer.Option("--save-motion", help="Also write the joint positions of every frame (.json)."),
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
    """Animate a rigged drawing through key-frames or a motion, to GIF, MP4 or PNGs.

    --exaggerate runs the cartoon filter over every bone's angle and length and the root's path.
    """
    kind = animation_format(output)
    if save_motion_to is not None and save_motion_to.suffix.lower() != ".json":
        raise SettingsError(f"give a motion file ending in .json, not {save_motion_to.name}")
    character = load_project(project)
    skeleton = character.skeleton
    colour = _colour(background or ("transparent" if kind == "png" else "white"))
    settings = FilterSettings(strength=exaggerate, sigma=sigma, shift=shift) if exaggerate else None
    deformer = Deformer(character, _deform_settings(no_area, stage_one_only, weights, joint_width))
    keys, solved = (), []
    if is_motion_file(keys_file):
        if ease is not None:
            raise SettingsError("--ease applies to key-frames; a motion has a pose for every frame")
        loaded = load_motion(keys_file)
        positions = motion_for(skeleton, loaded, where=str(keys_file))
        motion = _exaggerated(Motion(skeleton=skeleton, positions=positions,
                                     fps=loaded.fps if fps is None else fps), settings)
        meshes = list(motion_frames(deformer, motion.positions))
        what = f"a motion of {len(positions)} frames"
    else:
        timeline = load_keyframes(keys_file, skeleton, fps=fps)
        if ease is not None:
            timeline = make_timeline(skeleton, timeline.keys, fps=timeline.fps, ease=ease)
        motion = _exaggerated(motion_from_timeline(skeleton, timeline), settings)
        poses = motion.positions if settings else None
        keys, solved = timeline.keys, solve_keys(deformer, timeline)
        method = "solve" if solve_inbetweens else "interpolate"
        meshes = list(animate_frames(deformer, timeline, method=method, keys=solved, poses=poses))
        what = f"{len(timeline.keys)} key-frames"
    count, out_size = _write_frames(character, meshes, motion, output, size=_size(size), colour=colour,
                                    overlays=_overlays(overlay))
    if save_motion_to is not None:
        save_motion(save_motion_to, motion)
    typer.echo(
        f"animated {what}"
        + (f", exaggerated (A={exaggerate:g})" if settings else "")
        + f": {count} frames at {motion.fps:g} fps, {out_size[0]}x{out_size[1]} -> {output}"
        + (f" (motion -> {save_motion_to})" if save_motion_to is not None else "")
    )
    for key, result in zip(keys, solved, strict=True):
        _report_overlaps(character, result.U, where=f"key-frame {key.frame}: ")


@app.command("filter")
def filter_motion(
    motion_file: Annotated[Path, typer.Argument(metavar="MOTION.json", help="A motion: a pose per frame.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Motion file to write (.json).")],
    strength: _Strength,
    sigma: _Sigma = 3.0,
    shift: _Shift = 0.0,
    joints: Annotated[
        str | None,
        typer.Option(
            "--joints",
            help="Filter only these joints' paths (J[,J...]), carrying what hangs below them "
            "\\[default: the root's path and every bone's angle and length].",
        ),
    ] = None,
):
    """Exaggerate a motion with the cartoon animation filter: anticipation, follow-through."""
    if output.suffix.lower() != ".json":
        raise SettingsError(f"give a motion file ending in .json, not {output.name}")
    settings = FilterSettings(strength=strength, sigma=sigma, shift=shift)
    motion = load_motion(motion_file)
    skeleton = motion.skeleton
    if joints is None:
        positions = filter_bones(skeleton, motion.positions, settings)
    else:
        positions = filter_trajectories(skeleton, motion.positions, settings, joints=_names(joints))
    save_motion(output, Motion(skeleton=skeleton, positions=positions, fps=motion.fps))
    moved = np.hypot(*(positions - motion.positions).reshape(-1, 2).T).max()
    typer.echo(
        f"filtered {motion.frame_count} frames (A={strength:g}, sigma={sigma:g}, shift={shift:g}): "
        f"joints moved up to {moved:.1f} px -> {output}"
    )


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
    """Show or set the depth layers of a project's bone regions (saved as edits; see 'undo')."""
    character = load_project(project)
    names = character.skeleton.bone_names
    for item in settings or []:
        target, _, value = item.rpartition("=")
        try:
            value = int(value)
        except ValueError:
            raise SettingsError(f"give a whole-number depth after '=' in {item!r}") from None
        if target.startswith("@"):
            edit = DepthEdit(value=value, at=_numbers(target[1:], 2, "@X,Y"))
        elif target in names:
            edit = DepthEdit(value=value, bone=target)
        else:
            raise SettingsError(f"no bone is called {target!r}; the bones are: {', '.join(names)}")
        character = apply_edit(character, edit)
    if settings:
        save_project(project, character)
    for name, d in zip(names, character.depth, strict=True):
        typer.echo(f"{name:>20} {d}")


@app.command()
def correct(
    project: _Project,
    bone: Annotated[str, typer.Argument(help="The bone (named after its child joint) to attach to.")],
    curve: Annotated[
        list[str],
        typer.Argument(metavar="X,Y X,Y X,Y...", help="A closed curve round the vertices, drawing pixels."),
    ],
):
    """Correct the decomposition: attach every vertex inside a closed curve to one bone."""
    character = load_project(project)
    points = np.array([_numbers(p, 2, "a curve point X,Y") for p in curve])
    before = character.binding.bone
    character = apply_edit(character, Correction(curve=points, bone=bone))
    save_project(project, character)
    moved = int(np.count_nonzero(character.binding.bone != before))
    typer.echo(
        f"attached {moved} vertices to {bone} (edit {len(character.edits)}; 'toonmotion undo' takes it back)"
    )


_Steps = Annotated[int, typer.Option("--steps", help="How many edits.")]


@app.command("undo")
def undo_edits(project: _Project, steps: _Steps = 1):
    """Take back a project's last corrections or depth settings."""
    character, taken = undo(load_project(project), steps)
    save_project(project, character)
    for edit in taken[::-1]:
        typer.echo(f"undid: {describe_edit(edit)}")


@app.command("redo")
def redo_edits(project: _Project, steps: _Steps = 1):
    """Make again edits taken back by 'undo' (until a new edit is made)."""
    character, again = redo(load_project(project), steps)
    save_project(project, character)
    for edit in again:
        typer.echo(f"redid: {describe_edit(edit)}")


@app.command()
def edits(project: _Project):
    """List a project's edits, oldest first, and any that can be redone."""
    character = load_project(project)
    if not character.edits and not character.undone:
        typer.echo("no edits")
    for n, edit in enumerate(character.edits, start=1):
        typer.echo(f"{n:>3}  {describe_edit(edit)}")
    for edit in character.undone:
        typer.echo(f"redo {describe_edit(edit)}")


@app.command("remesh")
def remesh_project(
    project: _Project,
    spacing: Annotated[float | None, typer.Option("--spacing", help="Mesh spacing in pixels.")] = None,
    vertices: Annotated[int | None, typer.Option("--vertices", help="Target mesh vertex count.")] = None,
    refine_joints: Annotated[
        bool | None, typer.Option("--refine-joints/--no-refine-joints", help="Denser mesh around joints.")
    ] = None,
):
    """Mesh a project again (finer or coarser), keeping its skeleton and replaying its edits."""
    if spacing is None and vertices is None and refine_joints is None:
        raise SettingsError("give --spacing, --vertices or --refine-joints to say how to mesh again")
    if spacing is not None and vertices is not None:
        raise SettingsError("give either --spacing or --vertices, not both")
    character = load_project(project)
    old = character.settings
    settings = dataclasses.replace(
        old,
        spacing=spacing if spacing is not None or vertices is not None else old.spacing,
        vertices=vertices if spacing is not None or vertices is not None else old.vertices,
        refine_joints=old.refine_joints if refine_joints is None else refine_joints,
    )
    character, skipped = remesh(character, settings)
    save_project(project, character)
    typer.echo(
        f"remeshed {project.name}: {len(character.mesh.V)} vertices, {len(character.mesh.F)} triangles; "
        f"{len(character.edits)} edit{'' if len(character.edits) == 1 else 's'} replayed"
    )
    for edit, reason in skipped:
        typer.echo(f"dropped an edit that no longer applies ({describe_edit(edit)}): {reason}", err=True)


@app.command()
def tune(
    project: _Project,
    pose_file: Annotated[
        Path, typer.Argument(metavar="POSE.json|KEYS.json", help="A pose file, or key-frames with --key.")
    ],
    key: Annotated[int | None, typer.Option("--key", help="Frame number of the key to tune.")] = None,
    curve: Annotated[
        str | None,
        typer.Option(
            "--curve", help="Pull the outline onto a sketched curve: 'X,Y X,Y ...', drawing pixels."
        ),
    ] = None,
    drag: Annotated[
        list[str] | None,
        typer.Option("--drag", help="Drag the vertex at X,Y to X2,Y2: 'X,Y:X2,Y2' (repeat for several)."),
    ] = None,
    undo_last: Annotated[bool, typer.Option("--undo", help="Take back the last edit.")] = False,
    preview: Annotated[
        Path | None, typer.Option("-o", "--output", help="Also render the tuned pose to this PNG.")
    ] = None,
    joint_width: _JointWidth = 1.5,
):
    """Fine-tune a deformed pose: sketch curves and point drags, saved in the pose or key file.

    With no edit given, lists the edits. Each new edit is tried on the project before it is
    saved, so a file never holds an edit that does not apply.
    """
    if preview is not None:
        _png_output(preview)
    actions = (curve is not None) + bool(drag) + undo_last
    if actions > 1:
        raise SettingsError("give one of --curve, --drag or --undo at a time")
    character = load_project(project)
    skeleton = character.skeleton
    timeline, index = None, None
    if key is None:
        posed, edits = load_pose(pose_file, skeleton), load_pose_edits(pose_file)
    else:
        timeline = load_keyframes(pose_file, skeleton)
        frames = [k.frame for k in timeline.keys]
        if key not in frames:
            raise SettingsError(f"{pose_file} has no key at frame {key}; its keys are at {frames}")
        index = frames.index(key)
        posed, edits = timeline.keys[index].pose, timeline.keys[index].edits
    if curve is not None:
        edits = (*edits, CurveEdit(points=[_numbers(p, 2, "--curve point X,Y") for p in curve.split()]))
    elif drag:
        start, end = zip(*(_drag(d) for d in drag), strict=True)
        edits = (*edits, DragEdit(start=start, end=end))
    elif undo_last:
        if not edits:
            raise EditError(f"{pose_file} has no edits to undo")
        taken, edits = edits[-1], edits[:-1]
    deformer = Deformer(character, _deform_settings(False, False, "1,1,1", joint_width))
    result = apply_tuning(deformer, posed, deformer.deform(posed), edits)
    if actions:
        if timeline is None:
            save_pose(pose_file, skeleton, posed, edits)
        else:
            keys = list(timeline.keys)
            keys[index] = Keyframe(keys[index].frame, posed, edits)
            save_keyframes(pose_file, skeleton, dataclasses.replace(timeline, keys=tuple(keys)))
        typer.echo(f"undid: {describe_tuning(taken)}" if undo_last
                   else f"added edit {len(edits)}: {describe_tuning(edits[-1])} -> {pose_file}")
    elif not edits:
        typer.echo("no edits")
    else:
        for n, edit in enumerate(edits, start=1):
            typer.echo(f"{n:>3}  {describe_tuning(edit)}")
    if preview is not None:
        view = fit_view(character, [result.U])
        save_png(preview, render_frame(character, result.U, view=view, background=None))
        typer.echo(f"wrote {preview}")
        _report_view(view, character)


@app.command()
def track(
    source: Annotated[
        Path,
        typer.Argument(metavar="INPUT", help="A video, an animated GIF, or a folder (or pattern) of frames."),
    ],
    output: Annotated[Path, typer.Option("-o", "--output", help="Motion file to write (.json).")],
    joints: Annotated[
        Path | None,
        typer.Option(
            "--joints", help="Joint rectangles to track (.json) \\[default: suggested from frame 1]."
        ),
    ] = None,
    overlay: Annotated[
        Path | None,
        typer.Option(
            "--overlay", help="Also draw the tracked joints on the footage: OUT.mp4, OUT.gif or a folder."
        ),
    ] = None,
    csv: Annotated[Path | None, typer.Option("--csv", help="Also write the motion as CSV.")] = None,
    search: Annotated[
        float | None,
        typer.Option("--search", help="Search radius in pixels \\[default: from each rectangle]."),
    ] = None,
    background: Annotated[
        str | None,
        typer.Option("--background", help="Flat background colour #rrggbb for suggesting joints \\[default: "
                     "the border's colour if flat, else estimated from the sequence]."),
    ] = None,
    fps: Annotated[
        float | None, typer.Option("--fps", help="Frame rate \\[default: the video's, else 24].")
    ] = None,
    resume: Annotated[
        Path | None, typer.Option("--resume", help="Correct this earlier tracking (with --at and --set).")
    ] = None,
    at: Annotated[int | None, typer.Option("--at", help="Frame where --set places joints.")] = None,
    corrections: Annotated[
        list[str] | None,
        typer.Option(
            "--set", help="NAME=X,Y: a joint's true position at --at (repeat); tracking resumes there."
        ),
    ] = None,
):
    """Track a character's joints through footage (thesis ch. 4) into a motion file."""
    if output.suffix.lower() != ".json":
        raise SettingsError(f"give a motion file ending in .json, not {output.name}")
    if csv is not None and csv.suffix.lower() != ".csv":
        raise SettingsError(f"give a CSV file ending in .csv, not {csv.name}")
    if (resume is None) != (at is None) or (resume is None) != (not corrections):
        raise SettingsError(
            "--resume, --at and --set go together: the earlier motion, the frame and the joints"
        )
    if overlay is not None:
        animation_format(overlay)
    frames, video_fps = load_frames(source)
    rate = fps or video_fps or 24.0
    h, w = frames.shape[1:3]
    if joints is not None:
        skeleton, sizes, start = load_joints(joints)
    elif resume is not None:
        raise SettingsError("--resume needs the --joints file the tracking used (for the rectangle sizes)")
    else:
        colour = border_colour(frames[0]) if background is None else _colour(background)
        back = None if colour is not None else estimate_background(frames)
        mask = foreground_masks(frames[:1], background=back, colour=colour)[0]
        skeleton, sizes = suggest_setup(mask)
        start = 0
        suggested = output.with_name(output.stem + ".joints.json")
        save_joints(suggested, skeleton, sizes)
        typer.echo(f"suggested {len(skeleton)} joints from frame 0 -> {suggested} (edit it, pass --joints)",
                   err=True)
    if not 0 <= start < len(frames):
        raise SettingsError(f"the joints are given at frame {start} but the footage has {len(frames)} frames")
    check_setup(skeleton, sizes, (w, h))
    setup = TrackSetup(skeleton=skeleton, sizes=sizes)
    settings = TrackSettings(search=search)
    with _progress() as bar:
        task = bar.add_task("tracking", total=len(frames))

        def report(frame, count):
            bar.update(task, completed=frame, total=count)

        if resume is None:
            result = track_joints(frames, setup, settings=settings, start=start, progress=report)
        else:
            earlier = _tracking_from(load_motion(resume), skeleton, len(frames), start)
            fixes = dict(_named_point(c) for c in corrections)
            result = retrack(earlier, frames, setup, at, fixes, settings=settings, progress=report)
    tracked = np.flatnonzero(result.tracked)
    first, last = int(tracked[0]), int(tracked[-1]) + 1
    motion = Motion(skeleton=skeleton, positions=result.positions[first:last], fps=rate,
                    confidence=result.confidence[first:last])
    save_motion(output, motion)
    if csv is not None:
        save_motion_csv(csv, motion)
    if overlay is not None:
        pictures = (_opaque(draw_tracking(frames[first + t], motion.positions[t], sizes, skeleton.parents,
                                          angles=result.angles[first + t], confidence=motion.confidence[t]))
                    for t in range(motion.frame_count))
        save_animation(overlay, pictures, fps=rate, background=(255, 255, 255))
    unsure = float((motion.confidence < 0.5).mean())
    typer.echo(
        f"tracked {len(skeleton)} joints through {motion.frame_count} frames (from frame {first}); "
        f"{unsure:.0%} of joint-frames matched poorly (hidden or changed) -> {output}"
    )


@app.command("retarget")
def retarget_command(
    motion_file: Annotated[Path, typer.Argument(metavar="MOTION.json", help="A captured motion.")],
    project: _Project,
    output: Annotated[
        Path, typer.Option("-o", "--output", help="OUT.gif, OUT.mp4, or a folder (or pattern) for PNGs.")
    ],
    joint_map: Annotated[
        str | None,
        typer.Option("--map", help="Target joints named differently: TARGET=SOURCE[,TARGET=SOURCE...]."),
    ] = None,
    size: _Size = None,
    background: Annotated[
        str | None,
        typer.Option("--background", help="transparent, white, black or #rrggbb \\[default: white; "
                     "transparent for PNGs]."),
    ] = None,
    overlay: _Overlay = "",
    exaggerate: Annotated[
        float | None, typer.Option("--exaggerate", help="Cartoon filter strength A on the retargeted motion.")
    ] = None,
    sigma: _Sigma = 3.0,
    shift: _Shift = 0.0,
    no_area: _NoArea = False,
    stage_one_only: _StageOne = False,
    weights: _Weights = "1,1,1",
    joint_width: _JointWidth = 1.5,
):
    """Replay a captured motion on a rigged drawing (thesis 4.5); the result is kept in the project."""
    kind = animation_format(output)
    character = load_project(project)
    skeleton = character.skeleton
    mapping = {}
    for item in (joint_map or "").split(","):
        if item.strip():
            target, sep, source = item.partition("=")
            if not sep or not target.strip() or not source.strip():
                raise SettingsError(f"--map takes TARGET=SOURCE pairs separated by commas, got {item!r}")
            mapping[target.strip()] = source.strip()
    captured = load_motion(motion_file)
    motion = retarget(captured, skeleton, joint_map=mapping)
    if exaggerate:
        motion = _exaggerated(motion, FilterSettings(strength=exaggerate, sigma=sigma, shift=shift))
    deformer = Deformer(character, _deform_settings(no_area, stage_one_only, weights, joint_width))
    meshes = list(motion_frames(deformer, motion.positions))
    colour = _colour(background or ("transparent" if kind == "png" else "white"))
    count, _ = _write_frames(character, meshes, motion, output, size=_size(size), colour=colour,
                             overlays=_overlays(overlay))
    kept = Path(project) / "motions" / f"{motion_file.stem}.json"
    save_motion(kept, motion)
    typer.echo(f"retargeted {captured.frame_count} frames onto {project.name}: {count} frames at "
               f"{motion.fps:g} fps -> {output} (motion kept in {kept})")


def _exaggerated(motion, settings):
    """``motion`` through the cartoon filter (every bone and the root's path), or as it is."""
    if settings is None:
        return motion
    positions = filter_bones(motion.skeleton, motion.positions, settings)
    return Motion(skeleton=motion.skeleton, positions=positions, fps=motion.fps)


def _write_frames(character, meshes, motion, output, *, size, colour, overlays):
    """Render ``(frame, U)`` meshes in one view fitting them all and save them; ``(count, size)``."""
    view = fit_view(character, [U for _, U in meshes])
    out_size = natural_size(view, size=size)
    with _progress() as bar:
        task = bar.add_task("rendering", total=len(meshes))

        def frames():
            for frame, U in meshes:
                posed = motion.pose(frame) if overlays else None
                yield render_frame(
                    character, U, pose=posed, size=out_size, view=view, background=colour, overlays=overlays
                )
                bar.update(task, advance=1)

        count = save_animation(
            output, frames(), fps=motion.fps, background=colour if colour is not None else (255, 255, 255)
        )
    return count, out_size


def _tracking_from(motion, skeleton, count, start):
    """An earlier tracking, read back from its motion file, laid out on ``count`` frames."""
    positions = motion_for(skeleton, motion, where="the --resume motion")
    k = len(skeleton)
    if start + len(positions) > count:
        raise SettingsError(f"the --resume motion has {len(positions)} frames from frame {start}, more than "
                            f"the footage's {count}")
    full = np.zeros((count, k, 2))
    confidence = np.zeros((count, k))
    tracked = np.zeros(count, dtype=bool)
    full[start:start + len(positions)] = positions
    tracked[start:start + len(positions)] = True
    if motion.confidence is not None:
        confidence[start:start + len(positions)] = motion.confidence[:, [motion.skeleton.names.index(n)
                                                                          for n in skeleton.names]]
    return Tracking(positions=full, angles=np.zeros((count, k)), confidence=confidence, tracked=tracked)


def _opaque(rgb):
    return np.concatenate([rgb, np.full(rgb.shape[:2] + (1,), 255, dtype=np.uint8)], axis=2)


def _named_point(text):
    name, sep, point = text.partition("=")
    if not sep or not name.strip():
        raise SettingsError(f"--set takes NAME=X,Y, got {text!r}")
    return name.strip(), _numbers(point, 2, f"--set {name.strip()}=X,Y")


def _deform_settings(no_area, stage_one_only, weights, joint_width):
    return DeformSettings(
        preserve_area=not no_area,
        stage_two=not stage_one_only,
        weights=_numbers(weights, 3, "--weights"),
        joint_width=joint_width,
    )


def _report_view(view, character):
    """Say how picture pixels map to drawing pixels when the picture grew past the drawing."""
    x0, y0 = view[0] + 0.5, view[1] + 0.5
    if (x0, y0) != (0.0, 0.0) and view[2] - view[0] > 0:
        typer.echo(f"the picture's pixel (0, 0) is drawing pixel ({x0:.1f}, {y0:.1f}); edits and poses "
                   "use drawing pixels", err=True)


def _names(text):
    names = tuple(n.strip() for n in text.split(",") if n.strip())
    if not names:
        raise SettingsError(f"give one or more joint names separated by commas, got {text!r}")
    return names


def _drag(text):
    a, sep, b = text.partition(":")
    if not sep:
        raise SettingsError(f"--drag takes X,Y:X2,Y2 (from, to), got {text!r}")
    return _numbers(a, 2, "--drag X,Y"), _numbers(b, 2, "--drag X2,Y2")


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
