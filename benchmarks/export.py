"""Exports of animated drawings: time, size and how exactly the rigs replay toonmotion's frames;
JSON lines.

    python benchmarks/export.py [--drawings DIR ...] [--clips CLIP.bvh ...] [--frames N]
                                [--skinning one-bone|weights ...] [--formats glb spine sheet]

Each drawing folder (texture.png, mask.png, char_cfg.yaml; default: the bundled sample and every
drawing in ../shared/data/drawings) is rigged, and each motion-capture clip (default: every clip
in ../shared/data/mocap) is projected from the front, fitted to the drawing's skeleton by
``retarget`` and animated (its first ``--frames`` frames at 12 fps). The bundled sample also plays
its built-in key-frames. Every animation is exported as glb, spine and a sprite sheet (or the
``--formats`` given).

Keys, one line per drawing, source, skinning and format:
  drawing, source, skinning, format, frames, vertices
  export_s        writing the export (rigs: building the skin and the offsets; pictures:
                  rendering the frames too)
  bytes           every file written, together
  error           instead of the figures, when the export is refused (a sprite sheet that does
                  not fit the default 4096-pixel maximum)
  max_error_px    rigs only: the file played back by toonmotion.testing.export_playback (glTF's
                  node, skin and morph evaluation; Spine's bone and weighted-vertex math), read
                  from the file alone, against toonmotion's own vertices, over every frame and
                  vertex (goals: glTF 1e-4, Spine 1e-3)
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toonmotion import api  # noqa: E402
from toonmotion.animate.motion import Motion  # noqa: E402
from toonmotion.capture.bvh_kinematics import forward_kinematics  # noqa: E402
from toonmotion.capture.mocap import (  # noqa: E402
    STANDARD_JOINTS,
    fit_to_frame,
    pick_joints,
    project_orthographic,
    standard_skeleton_parents,
)
from toonmotion.deform.deformer import Deformer, DeformSettings  # noqa: E402
from toonmotion.errors import ExportError  # noqa: E402
from toonmotion.io.bvh import load_bvh  # noqa: E402
from toonmotion.io.drawing_folder import rig_drawing_folder  # noqa: E402
from toonmotion.io.exchange.drawing_rig import drawing_rig, to_pixels  # noqa: E402
from toonmotion.io.exchange.spine_json import spine_skeleton  # noqa: E402
from toonmotion.rig.skeleton import Skeleton  # noqa: E402
from toonmotion.sample_animation import sample_keyframes  # noqa: E402
from toonmotion.samples import sample_rig  # noqa: E402
from toonmotion.testing.export_playback import GlbScene, glb_mesh, spine_mesh  # noqa: E402

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
FPS = 12.0


def clip_motion(path, frames):
    """A BVH clip seen from the front as a motion of the standard joints, at about 12 fps."""
    clip = load_bvh(path)
    step = max(1, round(clip.fps / FPS))
    X = forward_kinematics(clip)[1::step][:frames]  # CMU clips open with a T-pose frame
    picks = pick_joints(clip.names, clip.parents)
    points = fit_to_frame(project_orthographic(X[:, [picks[n] for n in STANDARD_JOINTS]]), (480, 480))
    parents = standard_skeleton_parents()
    skeleton = Skeleton.from_joints([(n, parents[n], tuple(points[0, i]))
                                     for i, n in enumerate(STANDARD_JOINTS)])
    order = [STANDARD_JOINTS.index(n) for n in skeleton.names]
    return Motion(skeleton=skeleton, positions=points[:, order], fps=clip.fps / step)


def measure(character, name, source, animation, settings, skinning, folder, formats):
    """One JSON line per format for ``animation``."""
    common = dict(drawing=name, source=source, skinning=skinning, frames=len(animation.meshes),
                  vertices=len(character.mesh.V))
    for kind in formats:
        path = folder / f"{name}_{source}_{skinning}_{kind}.{'glb' if kind == 'glb' else 'json'}"
        start = time.perf_counter()
        try:
            done = api.export_animation(path, character, animation, format=kind, settings=settings)
        except ExportError as error:  # a sheet too big for the default maximum size, say
            print(json.dumps(dict(common, format=kind, error=str(error))), flush=True)
            continue
        seconds = time.perf_counter() - start
        line = dict(common, format=kind, export_s=round(seconds, 3),
                    bytes=sum(p.stat().st_size for p in done.files))
        if kind == "glb":
            rig = drawing_rig(character, animation, settings=settings, unit=100.0)
            scene = GlbScene(path)
            line["max_error_px"] = max(float(np.abs(to_pixels(glb_mesh(scene, t)[:, :2], rig) - U).max())
                                       for t, U in animation.meshes)
        elif kind == "spine":
            rig = drawing_rig(character, animation, settings=settings)
            order = spine_skeleton(rig, name=path.stem).order
            doc = json.loads(path.read_text())
            posed = [spine_mesh(doc, path.stem, t / doc["skeleton"]["fps"]) for t, _ in animation.meshes]
            line["max_error_px"] = spine_error(posed, rig, order, animation)
        if "max_error_px" in line:
            line["max_error_px"] = float(f"{line['max_error_px']:.3g}")
        print(json.dumps(line), flush=True)


def animations(drawings, clips, frames, skinnings):
    """Yield ``(drawing name, source, skinning, settings, character, animation)`` for every drawing
    folder (None: the bundled sample, which also plays its key-frames), skinning and clip."""
    if drawings is None:
        found = (SHARED / "drawings").iterdir()
        drawings = [None, *sorted(p for p in found if (p / "texture.png").is_file())]
    clips = clips if clips is not None else sorted((SHARED / "mocap").glob("*.bvh"))
    for drawing in drawings:
        character = sample_rig() if drawing is None else rig_drawing_folder(drawing)
        name = "sample" if drawing is None else drawing.name
        for skinning in skinnings:
            settings = DeformSettings(skinning=skinning)
            deformer = Deformer(character, settings)
            sources = [("keys", sample_keyframes(character.skeleton))] if drawing is None else []
            sources += [(clip.stem, api.retarget(clip_motion(clip, frames), character.skeleton))
                        for clip in clips]
            for source, played in sources:
                yield name, source, skinning, settings, character, api.animate_character(deformer, played)


def spine_error(posed, rig, order, animation):
    """The largest distance, drawing pixels, between Spine mesh vertices ``posed`` (per frame, in
    the file's vertex ``order``) and the animation's own."""
    worst = 0.0
    for t, (_, U) in enumerate(animation.meshes):
        pixels = np.empty_like(U)
        pixels[order] = to_pixels(np.reshape(posed[t], (-1, 2)), rig)
        worst = max(worst, float(np.abs(pixels - U).max()))
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drawings", nargs="*", type=Path, default=None)
    parser.add_argument("--clips", nargs="*", type=Path, default=None)
    parser.add_argument("--frames", type=int, default=48)
    parser.add_argument("--skinning", nargs="+", default=["one-bone", "weights"])
    parser.add_argument("--formats", nargs="+", default=["glb", "spine", "sheet"],
                        choices=["glb", "spine", "sheet"])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(scratch)
        for name, source, skinning, settings, character, animation in animations(
                args.drawings, args.clips, args.frames, args.skinning):
            measure(character, name, source, animation, settings, skinning, folder, args.formats)
            for old in folder.iterdir():
                old.unlink()

if __name__ == "__main__":
    main()
