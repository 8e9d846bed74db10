"""The ``scene`` command: simulated 3D elements around a 3D proxy, composited into the drawing in
depth order (Jain et al. 2012, section 3.5)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from PIL import Image

from toonmotion import api
from toonmotion.animate.motion import Motion
from toonmotion.animate.timeline import Timeline
from toonmotion.api.scene3d import ANTIALIAS
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.errors import SettingsError
from toonmotion.io.frames import load_frames
from toonmotion.io.image import save_png
from toonmotion.io.motion_json import is_motion_file, load_motion
from toonmotion.io.pose_json import load_keyframes
from toonmotion.io.proxy_json import load_proxy
from toonmotion.io.video import animation_format, save_animation
from toonmotion.render.zbuffer import MAX_ANTIALIAS
from toonmotion.scene.build import DEFAULT_LIMB_RADIUS, check_scene
from toonmotion.scene.elements import MAX_SIZE, Balloon, Balls, Cape, Element, Rain, Scarf, Skirt

_MOST = f"{MAX_SIZE:g} times the figure's height"


@app.command("scene")
def scene_command(
    source: Annotated[Path, typer.Argument(metavar="PROXY.json", help="A proxy file made by 'lift'.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="OUT.mp4, OUT.gif or a folder of PNGs.")],
    frames: Annotated[Path | None, typer.Option(
        "--frames", help="The drawn frames the proxy was lifted from (video, GIF, folder or pattern; "
        "transparent PNGs from 'animate' keep their figure).")] = None,
    project: Annotated[Path | None, typer.Option(
        "--project", help="Instead of --frames: the rigged character whose animation (--keys) the proxy was "
        "lifted from; each pixel's depth then follows the bone it moves with.")] = None,
    keys: Annotated[Path | None, typer.Option(
        "--keys", help="With --project: the key-frames or motion it was animated with.")] = None,
    balloon: Annotated[list[str] | None, typer.Option(
        "--balloon", help="A balloon on a string held at MARKER (repeat for more).")] = None,
    balls: Annotated[list[str] | None, typer.Option(
        "--balls", help="Balls on the ground in the path of MARKER[,MARKER...] (feet, say), to be kicked."
    )] = None,
    scarf: Annotated[list[str] | None, typer.Option(
        "--scarf", help="A scarf tied at MARKER (a wrist, say; repeat for more).")] = None,
    skirt: Annotated[list[str] | None, typer.Option(
        "--skirt", help="A skirt of cloth hanging in a ring around MARKER (the hips, say).")] = None,
    cape: Annotated[list[str] | None, typer.Option(
        "--cape", help="A cape of cloth hanging from LEFT,RIGHT (the figure's own left and right "
        "shoulders) down its back.")] = None,
    rain: Annotated[int, typer.Option(
        "--rain", min=0, help="Rain: this many drops falling over the figure at a time, bouncing off it. "
        "Drops, balls, the links of strings and the points of cloth count towards the limit scene_bodies."
    )] = 0,
    ball_count: Annotated[int, typer.Option("--ball-count", min=1, help="Balls per --balls marker.")] = 3,
    ball_radius: Annotated[float | None, typer.Option(
        "--ball-radius", help=f"Metres, at most {_MOST} \\[default: 5% of the figure's height].")] = None,
    balloon_radius: Annotated[float | None, typer.Option(
        "--balloon-radius", help=f"Metres, at most {_MOST} \\[default: 7% of the figure's height].")] = None,
    string_length: Annotated[float | None, typer.Option(
        "--string-length", help=f"Metres, at most {_MOST} \\[default: 30% of the figure's height].")] = None,
    shading: Annotated[str, typer.Option("--shading", help="toon, smooth or flat.")] = "toon",
    antialias: Annotated[int, typer.Option(
        "--antialias", min=1, max=MAX_ANTIALIAS, help="Rays per pixel side for the elements' edges: 1 is "
        f"hard edges, N blends N x N rays a pixel (1 to {MAX_ANTIALIAS}; time grows about as N x N)."
    )] = ANTIALIAS,
    passes: Annotated[Path | None, typer.Option(
        "--passes", help="Also write the elements' passes per frame into this folder, for compositing "
        "elsewhere: beauty_NNNN.png (RGBA), depth_NNNN.png (16-bit millimetres, 0: nothing) and "
        "occlusion_NNNN.png.")] = None,
    background: Annotated[str, typer.Option(
        "--background", help="white, black or #rrggbb under transparent frames.")] = "white",
) -> None:
    """Put simulated 3D elements (balloons, balls) around a 3D proxy and composite them into the drawing."""
    animation_format(output)
    under = options.colour(background)
    if under is None:
        raise SettingsError("--background takes white, black or #rrggbb here: the output is opaque")
    elements: list[Element] = [Balloon(m.strip(), radius=balloon_radius, string_length=string_length)
                               for m in balloon or ()]
    for text in balls or ():
        elements += [Balls(m, count=ball_count, radius=ball_radius) for m in options.names(text)]
    elements += [Scarf(m.strip()) for m in scarf or ()] + [Skirt(m.strip()) for m in skirt or ()]
    elements += [Cape(*_pair(text)) for text in cape or ()]
    elements += [Rain(count=rain)] if rain else []
    if (frames is None) == (project is None) or (project is None) != (keys is None):
        raise SettingsError("give the drawn frames (--frames) or a project and its keys (--project, --keys)")
    if not elements:
        options.warn("no elements given (--balloon, --balls, --scarf, --skirt, --cape, --rain): the drawing "
                     "is written as it is")
    proxy = load_proxy(source)
    check_scene(proxy, elements)  # markers, bodies and sizes, before the frames are read
    if proxy.radii is None and elements:
        options.warn("the proxy has no collision volumes (it was lifted without --frames): its limbs' radii "
                     f"are taken as {DEFAULT_LIMB_RADIUS:.1%} of the figure's height")
    limbs = None
    with options.progress("scene") as report:
        if frames is not None:
            pictures, _ = load_frames(frames, alpha=True)
        elif project is not None and keys is not None:
            character, animation = project_animation(project, keys)
            pictures, limbs = api.animation_frames(character, animation, proxy)
        motion = api.simulate_scene(proxy, elements, progress=report)
        made = api.composite_scene(proxy, pictures, motion, shading=shading, background=under, limbs=limbs,
                                   progress=report, antialias=antialias)
        written = save_animation(output, _opaque(made), fps=proxy.fps)
        if passes is not None:
            _write_passes(passes, api.scene_passes(proxy, motion, shading=shading, antialias=antialias))
    deepest = f", deepest contact {motion.deepest * 1000:.1f} mm" if len(motion.balls[0]) else ""
    counts = [(sum(isinstance(e, kind) for e in elements), one, many) for kind, one, many in (
        (Balloon, "balloon", "balloons"), (Scarf, "scarf", "scarves"), (Skirt, "skirt", "skirts"),
        (Cape, "cape", "capes"))]
    counts += [(motion.balls.shape[1], "ball", "balls"), (rain, "drop", "drops")]
    parts = [f"{n} {one if n == 1 else many}" for n, one, many in counts if n]
    listed = " and ".join([", ".join(parts[:-1]), parts[-1]] if len(parts) > 1 else parts) or "nothing"
    typer.echo(f"simulated {listed} over {written} frames ({motion.substeps} steps each{deepest}) -> "
               f"{output}")
    for warning in api.scene_warnings(motion):
        options.warn(warning)


def _opaque(frames):
    for f in frames:
        yield np.concatenate([f, np.full(f.shape[:2] + (1,), 255, np.uint8)], axis=2)


def project_animation(project: Path, keys: Path) -> tuple[api.Character, api.Animation]:
    """The project's character and its animation through ``keys`` (key-frames or a motion)."""
    character = api.load_project(project)
    source: Motion | Timeline
    if is_motion_file(keys):
        source = load_motion(keys)
    else:
        source = load_keyframes(keys, character.skeleton)
    return character, api.animate_character(character, source)


def _write_passes(folder: Path, passes) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    for t, (beauty, depth, occlusion) in enumerate(passes):
        save_png(folder / f"beauty_{t:04d}.png", beauty)
        save_png(folder / f"depth_{t:04d}.png", Image.fromarray(depth))
        save_png(folder / f"occlusion_{t:04d}.png", occlusion)


def _pair(text: str) -> tuple[str, str]:
    """``LEFT,RIGHT`` for ``--cape``."""
    found = options.names(text)
    if len(found) != 2:
        raise SettingsError(f"--cape takes two markers, LEFT,RIGHT (the figure's own shoulders), "
                            f"got {text!r}")
    return found[0], found[1]
