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

from toonmotion.io.exchange.drawing_rig import drawing_rig
from toonmotion.io.exchange.spine_json import save_spine, spine_skeleton

sys.path.insert(0, str(Path(__file__).parent))
from export import animations, spine_error  # noqa: E402

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
    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "rig.json"
        for name, source, skinning, settings, character, animation in animations(
                args.drawings, args.clips, args.frames, ("one-bone", "weights")):
            worst = runtime_error(character, animation, settings, path)
            print(json.dumps({"drawing": name, "source": source, "skinning": skinning,
                              "frames": len(animation.meshes), "runtime": f"spine-core {version} (float32)",
                              "max_error_px": float(f"{worst:.3g}")}), flush=True)


def runtime_error(character, animation, settings, path):
    """Write the animation as Spine files at ``path``, pose them with the runtime at every frame, and
    return the largest distance from toonmotion's vertices, pixels."""
    rig = drawing_rig(character, animation, settings=settings)
    save_spine(path, rig, name="anim")
    order = spine_skeleton(rig, name="anim").order
    argv = ["node", str(POSE), str(path), str(path.with_suffix(".atlas")), "anim", repr(rig.fps),
            str(rig.frame_count)]
    posed = json.loads(subprocess.run(argv, capture_output=True, text=True, check=True, cwd=ROOT).stdout)
    return spine_error(posed, rig, order, animation)


if __name__ == "__main__":
    main()
