"""3D proxy commands (Jain et al. 2012): ``lift`` (markers + a mocap prior -> a proxy file),
``proxy-export`` (to .glb or .bvh), ``proxy-preview`` (a video of the proxy over the drawing) and
``project-mocap`` (a mocap clip seen from a view -> a 2D motion for ``retarget``)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import numpy as np
import typer

from toonmotion import api
from toonmotion.animate.motion import Motion
from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.cli.scene3d import project_animation
from toonmotion.errors import SettingsError
from toonmotion.io.bvh import load_bvh, save_bvh
from toonmotion.io.exchange.proxy_gltf import save_proxy_glb
from toonmotion.io.frames import lay_on, load_frames
from toonmotion.io.markers_json import load_markers
from toonmotion.io.motion_json import is_motion_file, load_motion, save_motion
from toonmotion.io.proxy_json import load_proxy, save_proxy
from toonmotion.io.video import animation_format, save_animation
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton_bvh import skeleton_clip

EXPORTS = (".glb", ".bvh")


@app.command("lift")
def lift_command(
    prior: Annotated[Path, typer.Option("--prior",
                                        help="Motion-capture clip (.bvh) that moves like the drawing.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Proxy file to write (.json).")],
    source: Annotated[Path | None, typer.Argument(
        metavar="[MARKERS]", help="A markers file (.json or .csv: named markers per frame) or a motion file "
        "(from 'track' or an animation); or give --project and --keys.")] = None,
    joint_map: Annotated[str | None, typer.Option(
        "--map", help="Markers named otherwise than the clip's joints: MARKER=JOINT[,MARKER=JOINT...]."
    )] = None,
    segment: Annotated[str | None, typer.Option(
        "--segment", help="The clip's frames to use, START:STOP (a slice) \\[default: all].")] = None,
    view: Annotated[str | None, typer.Option(
        "--view", help="The artist's view AZIMUTH,ELEVATION in degrees (0,0: from the front of a figure "
        "facing +Z; 90,0: from its left) \\[default: searched].")] = None,
    focal: Annotated[float | None, typer.Option(
        "--focal", help="Focal length in pixels \\[default: the image's diagonal].")] = None,
    still_camera: Annotated[bool, typer.Option(
        "--still-camera", help="One camera for the whole shot (a drawing without camera moves): steadier "
        "than a camera per frame where the prior fits the drawing badly.")] = False,
    up: Annotated[str, typer.Option(
        "--up", help="Where the world's up points in the picture, degrees clockwise from the picture's up "
        "(0: a level picture: the camera does not roll, the proxy and a scene's gravity stand as drawn); "
        "'free' fits the camera's roll per frame, as the paper does.")] = "0",
    hold_elevation: Annotated[bool, typer.Option(
        "--hold-elevation", help="The camera keeps the view's elevation (it pans, it does not tilt): the "
        "world's vertical stays the picture's, for a figure unlike its prior (four legs on a human clip)."
    )] = False,
    ground: Annotated[str, typer.Option(
        "--ground", help="Where the ground (Y = 0) is: 'prior', the clip's floor, or 'feet', the drawn "
        "markers' lowest path (for a figure unlike its prior, which the clip's floor leaves in the air)."
    )] = "prior",
    size: Annotated[str | None, typer.Option(
        "--size", help="Image WxH pixels \\[default: the frames', else the markers' extent].")] = None,
    frames: Annotated[Path | None, typer.Option(
        "--frames", help="The drawn frames (video, GIF, folder or pattern), for the collision volumes."
    )] = None,
    widths: Annotated[list[str] | None, typer.Option(
        "--width", help="FRAME:MARKER=W1,W2: the limb ending at MARKER is W1 px wide at its parent end and "
        "W2 at MARKER's on FRAME (where limbs overlap; repeat).")] = None,
    units: Annotated[str | None, typer.Option(
        "--units", help="The clip's unit: m, cm, mm, inch, cmu, or metres per unit \\[default: guessed from "
        "the figure's height].")] = None,
    fps: Annotated[float | None, typer.Option(
        "--fps", help="Frame rate of a CSV markers file \\[default: 12].")] = None,
    extra: Annotated[list[Path] | None, typer.Option(
        "--extra", help="Another clip (.bvh) for the skeleton's pose space (repeat).")] = None,
    glb: Annotated[Path | None, typer.Option("--glb",
                                             help="Also export the proxy as glTF binary (.glb).")] = None,
    bvh: Annotated[Path | None, typer.Option("--bvh", help="Also export the skeleton as BVH (.bvh).")] = None,
    project: Annotated[Path | None, typer.Option(
        "--project", help="Instead of MARKERS and --frames: a rigged character, whose animation through "
        "--keys is lifted (its joints in its frames, and its frames for the volumes), as 'scene --project' "
        "composites it.")] = None,
    keys: Annotated[Path | None, typer.Option(
        "--keys", help="With --project: the key-frames or motion it is animated with.")] = None,
    preview: Annotated[Path | None, typer.Option(
        "--preview", help="Also write a preview: the proxy over the drawing beside a side view (.mp4, .gif "
        "or a folder).")] = None,
) -> None:
    """Lift drawn markers into 3D with a mocap prior (Jain et al. 2012): camera, points, volumes, skeleton."""
    options.suffix(output, ".json", "a proxy file")
    if glb is not None:
        options.suffix(glb, ".glb", "a glTF binary file")
    if bvh is not None:
        options.suffix(bvh, ".bvh", "a BVH file")
    if preview is not None:
        animation_format(preview)
    if (source is None) == (project is None) or (project is None) != (keys is None):
        raise SettingsError("give the drawn markers (MARKERS) or a project and its keys (--project, --keys)")
    if project is not None and (frames is not None or fps is not None):
        raise SettingsError("--project gives its own frames and frame rate: leave out --frames and --fps")
    overrides = _widths(widths)
    if overrides and frames is None and project is None:
        raise SettingsError("--width sets a limb's width on the drawn frames: give them with --frames")
    clip = load_bvh(prior)
    given = dict(joint_map=_pairs(joint_map, "--map"), segment=_segment(segment),
                 view=None if view is None else options.numbers(view, 2, "--view"),
                 focal=focal, still_camera=still_camera, up=_up(up), hold_elevation=hold_elevation,
                 ground=ground, widths=overrides, units=_units(units),
                 extra=[load_bvh(p) for p in extra or ()])
    pictures = None
    if project is not None and keys is not None:
        character, animation = project_animation(project, keys)
        with options.progress("lifting") as report:
            proxy, found = api.lift_animation(character, animation, clip, size=options.size(size),
                                              progress=report, **given)
        if preview is not None:
            pictures = lay_on(api.animation_frames(character, animation, proxy)[0])
    else:
        markers = read_markers(source, fps)  # type: ignore[arg-type]
        if frames is not None:
            pictures = lay_on(load_frames(frames, alpha=True)[0])  # transparent PNGs on white
        with options.progress("lifting") as report:
            proxy, found = api.lift_proxy(markers, clip, size=options.size(size), frames=pictures,
                                          progress=report, **given)  # type: ignore[arg-type]
    save_proxy(output, proxy)
    written = [str(output)]
    if glb is not None:
        save_proxy_glb(glb, proxy)
        written.append(str(glb))
    if bvh is not None:
        save_bvh(bvh, skeleton_clip(proxy))
        written.append(str(bvh))
    if preview is not None:
        _write_preview(preview, proxy, pictures)
        written.append(str(preview))
    how = "searched" if found.view_found else "given"
    typer.echo(
        f"lifted {len(proxy.names)} markers over {proxy.frame_count} frames: view {found.azimuth:.1f},"
        f"{found.elevation:.1f} ({how}), camera fit {found.camera_px:.2f} px, points on the drawing within "
        f"{found.reproj_px:.2g} px{'' if proxy.radii is not None else ', no volumes (no --frames)'} -> "
        + ", ".join(written)
    )
    for warning in api.lift_warnings(proxy, found):
        options.warn(warning)
    if found.left_out:
        options.warn(f"left out {', '.join(found.left_out)}: no joint of the prior matches "
                     f"{'them' if len(found.left_out) > 1 else 'it'} (map with --map)")
    if found.capped is not None and found.capped.any():
        t, k = np.argwhere(found.capped)[0]
        options.warn(f"{int(found.capped.sum())} limb widths found no outline within the limb's length "
                     "(first: "
                     f"frame {t}, the limb to {proxy.names[proxy.limbs[k, 1]]}); give them with --width")


@app.command("proxy-export")
def proxy_export(
    source: Annotated[Path, typer.Argument(metavar="PROXY.json", help="A proxy file made by 'lift'.")],
    output: Annotated[Path, typer.Option(
        "-o", "--output", help="OUT.glb (the whole proxy, glTF binary) or OUT.bvh (the skeleton).")],
) -> None:
    """Export a 3D proxy to glTF binary (.glb) or its skeleton to BVH (.bvh); metres, +Y up."""
    options.suffix(output, EXPORTS, "an export")
    proxy = load_proxy(source)
    if output.suffix.lower() == ".glb":
        save_proxy_glb(output, proxy)
    else:
        save_bvh(output, skeleton_clip(proxy))
    typer.echo(f"exported {len(proxy.names)} markers over {proxy.frame_count} frames -> {output}")


@app.command("proxy-preview")
def proxy_preview(
    source: Annotated[Path, typer.Argument(metavar="PROXY.json", help="A proxy file made by 'lift'.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="OUT.mp4, OUT.gif or a folder of PNGs.")],
    frames: Annotated[Path | None, typer.Option(
        "--frames", help="The drawn frames to draw over \\[default: white].")] = None,
) -> None:
    """Draw a 3D proxy from its camera over the drawing, beside a side view, as a video."""
    animation_format(output)
    proxy = load_proxy(source)
    pictures = None if frames is None else lay_on(load_frames(frames, alpha=True)[0])
    count = _write_preview(output, proxy, pictures)
    typer.echo(f"previewed {count} frames -> {output}")


@app.command("project-mocap")
def project_mocap_command(
    clip: Annotated[Path, typer.Argument(metavar="CLIP.bvh", help="A motion-capture clip (.bvh).")],
    view: Annotated[str, typer.Option(
        "--view", help="The view AZIMUTH,ELEVATION in degrees, as lift's (0,0: from the front of a figure "
        "facing +Z; 90,0: from its left).")],
    output: Annotated[Path, typer.Option(
        "-o", "--output", help="Motion file to write (.json), for 'retarget'.")],
    joint_map: Annotated[str | None, typer.Option(
        "--map", help="Joints named after the drawing's: NAME=JOINT[,NAME=JOINT...] gives the clip's JOINT "
        "the name NAME (e.g. front_left_foot=LeftHand) \\[default: standard names: hips, spine, neck, "
        "head, left_shoulder, left_elbow, left_hand, ..., right_foot].")] = None,
    segment: Annotated[str | None, typer.Option(
        "--segment", help="The clip's frames to use, START:STOP (a slice) \\[default: all].")] = None,
    fps: Annotated[float | None, typer.Option(
        "--fps", help="Frame rate of the motion \\[default: the clip's].")] = None,
    size: Annotated[str | None, typer.Option(
        "--size", help="Picture WxH pixels the whole motion is fitted into, 10% clear on each side "
        "\\[default: 640x480].")] = None,
) -> None:
    """See a motion-capture clip from a view as a drawn 2D motion, for 'retarget' onto a drawing."""
    options.suffix(output, ".json", "a motion file")
    angles = options.numbers(view, 2, "--view")
    picture = options.size(size) or (640, 480)
    mapping = _pairs(joint_map, "--map")
    motion = api.project_mocap(load_bvh(clip), view=(angles[0], angles[1]), joint_map=mapping,
                               segment=_segment(segment), fps=fps, size=picture)
    save_motion(output, motion)
    typer.echo(
        f"projected {len(motion.skeleton)} joints of {clip.name} seen from {angles[0]:g},{angles[1]:g}: "
        f"{motion.frame_count} frames at {motion.fps:g} fps in {picture[0]}x{picture[1]} -> {output}"
    )


def read_markers(path: Path, fps: float | None) -> Markers | Motion:
    """A markers file, or a motion file (its joints become markers)."""
    if path.suffix.lower() == ".json" and is_motion_file(path):
        if fps is not None:
            raise SettingsError("--fps is for CSV markers files; a motion file has its own frame rate")
        return load_motion(path)
    return load_markers(path, fps=fps)


def _write_preview(path: Path, proxy: Proxy, pictures: np.ndarray | None) -> int:
    with options.progress("preview") as report:
        pictures_out = api.preview_proxy(proxy, pictures)
        report("preview", len(pictures_out), len(pictures_out))

        def rgba():
            for p in pictures_out:
                yield np.concatenate([p, np.full(p.shape[:2] + (1,), 255, np.uint8)], axis=2)

        return save_animation(path, rgba(), fps=proxy.fps)


def _pairs(text: str | None, option: str) -> dict[str, str]:
    out = {}
    for item in (text or "").split(","):
        if not item.strip():
            continue
        key, sep, value = item.partition("=")
        if not sep or not key.strip() or not value.strip():
            raise SettingsError(f"{option} takes NAME=NAME pairs separated by commas, got {item!r}")
        out[key.strip()] = value.strip()
    return out


def _up(text: str) -> float | None:
    if text.strip().lower() == "free":
        return None
    try:
        angle = float(text)
    except ValueError:
        angle = float("nan")
    if not np.isfinite(angle):
        raise SettingsError(f"--up takes an angle in degrees or 'free', got {text!r}")
    return angle


def _segment(text: str | None) -> tuple[int, int | None]:
    if text is None:
        return 0, None
    start, sep, stop = text.partition(":")
    try:
        if not sep:
            raise ValueError
        return int(start or 0), (int(stop) if stop.strip() else None)
    except ValueError:
        raise SettingsError(f"--segment takes START:STOP frame numbers, got {text!r}") from None


def _units(text: str | None) -> float | str | None:
    if text is None:
        return None
    try:
        return float(text)
    except ValueError:
        return text.strip()


def _widths(items: list[str] | None) -> dict[tuple[int, str], tuple[float, float]]:
    """``--width FRAME:MARKER=W1,W2`` as ``(frame, marker) -> (w1, w2)``."""
    out = {}
    for item in items or ():
        where, sep, values = item.partition("=")
        frame, sep2, name = where.partition(":")
        if not (sep and sep2 and name.strip()):
            raise SettingsError(f"--width takes FRAME:MARKER=W1,W2, got {item!r}")
        try:
            t = int(frame)
        except ValueError:
            raise SettingsError(f"--width takes a whole frame number before ':', got {frame!r}") from None
        w1, w2 = options.numbers(values, 2, "--width")
        if not min(w1, w2) >= 0:
            raise SettingsError(f"--width {item}: the limb to {name.strip()} needs two widths >= 0 in pixels")
        out[t, name.strip()] = (w1, w2)
    return out
