"""Spine exports posed by Spine's own runtime (spine-core 4.2, float32) against toonmotion's frames;
JSON lines. An optional check outside ``make test`` and ``make bench``.

    npm install --no-save @esotericsoftware/spine-core@~4.2   # yourself: Spine Runtimes License
    python benchmarks/spine_runtime.py [--drawings DIR ...] [--clips CLIP.bvh ...] [--frames N]

Animations are made as in ``benchmarks/export.py`` (the bundled sample's key-frames and, for every
drawing, each clip retargeted onto it), written with ``toonmotion export --format spine``'s
writer, then loaded and posed at every frame by ``benchmarks/spine_pose.mjs`` through the
runtime's ``SkeletonJson``, ``Animation.apply`` and ``computeWorldVertices``.

Keys: drawing, source, skinning, frames, runtime, max_error_px (every frame and vertex, drawing
pixels; toonmotion's own play-back in double precision is in benchmarks/export.py).
"""

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from toonmotion import api
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.io.drawing_folder import rig_drawing_folder
from toonmotion.io.exchange.drawing_rig import drawing_rig, to_pixels
from toonmotion.io.exchange.spine_json import save_spine, spine_skeleton
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_rig

sys.path.insert(0, str(Path(__file__).parent))
from export import SHARED, clip_motion  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
POSE = Path(__file__).with_name("spine_pose.mjs")


def runtime_version():
    """The installed spine-core's version; exits with a message when it is not installed."""
    package = ROOT / "node_modules" / "@esotericsoftware" / "spine-core" / "package.json"
    if not package.is_file():
        sys.exit("spine-core is not installed: npm install --no-save @esotericsoftware/spine-core@~4.2 "
                 "(under the Spine Runtimes License)")
    return json.loads(package.read_text())["version"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drawings", nargs="*", type=Path, default=None)
    parser.add_argument("--clips", nargs="*", type=Path, default=None)
    parser.add_argument("--frames", type=int, default=48)
    args = parser.parse_args()
    version = runtime_version()
    drawings = args.drawings
    if drawings is None:
        found = (SHARED / "drawings").iterdir()
        drawings = [None, *sorted(p for p in found if (p / "texture.png").is_file())]
    clips = args.clips if args.clips is not None else sorted((SHARED / "mocap").glob("*.bvh"))
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "rig.json"
        for drawing in drawings:
            character = sample_rig() if drawing is None else rig_drawing_folder(drawing)
            for skinning in ("one-bone", "weights"):
                settings = DeformSettings(skinning=skinning)
                deformer = Deformer(character, settings)
                sources = [("keys", sample_keyframes(character.skeleton))] if drawing is None else []
                sources += [(clip.stem, api.retarget(clip_motion(clip, args.frames), character.skeleton))
                            for clip in clips]
                for source, played in sources:
                    animation = api.animate_character(deformer, played)
                    worst = runtime_error(character, animation, settings, path)
                    name = "sample" if drawing is None else drawing.name
                    print(json.dumps({"drawing": name, "source": source, "skinning": skinning,
                                      "frames": len(animation.meshes),
                                      "runtime": f"spine-core {version} (float32)",
                                      "max_error_px": float(f"{worst:.3g}")}), flush=True)


def runtime_error(character, animation, settings, path):
    """Write the animation as Spine files at ``path``, pose them with the runtime at every frame, and
    return the largest distance from toonmotion's vertices, pixels."""
    rig = drawing_rig(character, animation, settings=settings)
    save_spine(path, rig, name="anim")
    order = spine_skeleton(rig, name="anim").order
    argv = ["node", str(POSE), str(path), str(path.with_suffix(".atlas")), "anim", repr(rig.fps),
            str(rig.frame_count)]
    frames = np.array(json.loads(subprocess.run(argv, capture_output=True, text=True, check=True,
                                                cwd=ROOT).stdout))
    worst = 0.0
    for t, (_, U) in enumerate(animation.meshes):
        pixels = np.empty_like(U)
        pixels[order] = to_pixels(frames[t].reshape(-1, 2), rig)
        worst = max(worst, float(np.abs(pixels - U).max()))
    return worst

if __name__ == "__main__":
    main()
