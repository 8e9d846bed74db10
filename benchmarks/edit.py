"""Speed of the cartoon filter and the editing tools; JSON lines.

    python benchmarks/edit.py [DRAWING_DIR ...]

Each drawing (default: every drawing in ../shared/data/drawings, with its char_cfg.yaml
skeleton) is rigged to about 1,500 vertices. Runs on one core. There is no peer to compare
with: these are interactive operations, and the goal is that each answers well within a
frame of an editor (about 30 ms).

Keys, one line per drawing:
  drawing, vertices
  filter_240_ms        filter_bones over a 240-frame motion (10 s at 24 fps) of the drawing's skeleton
  exaggerate_pose_ms   the single-frame filter (both feet fixed) plus deforming the result
  curve_edit_ms        one sketch-curve edit on a bent pose (a 9-vertex outline arc pushed 4 px out)
  drag_ms              one point drag of 3 px on the head
  undo_ms              undoing the last of three project edits (re-decomposition and replay)
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toonmotion.animate.cartoon_filter import FilterSettings, filter_bones  # noqa: E402
from toonmotion.animate.pose_filter import exaggerate_pose  # noqa: E402
from toonmotion.deform.deformer import Deformer  # noqa: E402
from toonmotion.deform.fine_tune import drag_points, tune_with_curve  # noqa: E402
from toonmotion.io.drawing_folder import rig_drawing_folder  # noqa: E402
from toonmotion.rig.binding import Correction  # noqa: E402
from toonmotion.rig.edits import DepthEdit, apply_edit, undo  # noqa: E402
from toonmotion.rig.pose import Pose, rest_pose, rotate_about  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
REPEATS = 7


def _median_ms(run, repeats=REPEATS):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(1000 * (time.perf_counter() - start))
    return round(statistics.median(times), 3)


def _motion(skeleton, frames=240):
    """Elbows and knees swinging, the root bobbing: a busy motion to filter."""
    out = []
    for f in range(frames):
        t = 2 * np.pi * f / 48
        P = rotate_about(skeleton, skeleton.positions, "right_elbow", 0.8 * np.sin(t))
        P = rotate_about(skeleton, P, "left_knee", 0.5 * np.sin(t + 1))
        out.append(P + (0.0, 10 * np.sin(2 * t)))
    return np.stack(out)


def _pushed_arc(mesh, U, length=9, offset=4.0):
    """The first outline arc of ``length`` vertices pushed ``offset`` px along its outward normal."""
    loop = mesh.boundary[0]
    arc = U[loop[len(loop) // 3: len(loop) // 3 + length]]
    tangent = np.gradient(arc, axis=0)
    normal = np.stack([tangent[:, 1], -tangent[:, 0]], axis=1)
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    return arc + offset * normal  # the outer loop is counter-clockwise on screen: this is outward


def bench(folder):
    character = rig_drawing_folder(folder)
    skeleton = character.skeleton
    deformer = Deformer(character)
    motion = _motion(skeleton)
    settings = FilterSettings(strength=1.5)
    height = float(np.ptp(character.mesh.V[:, 1]))

    def crouch():
        feet = ["right_foot", "left_foot"]
        posed = exaggerate_pose(skeleton, rest_pose(skeleton), (0, -0.1 * height), feet)
        deformer.deform(posed)

    bent = Pose(rotate_about(skeleton, skeleton.positions, "right_elbow", 0.6))
    U = deformer.deform(bent).U
    curve = _pushed_arc(character.mesh, U)
    head = skeleton.positions[skeleton.index("neck")]
    grab = U[np.argmin(np.hypot(*(U - head).T))]

    edited = apply_edit(character, DepthEdit(value=1, bone="right_elbow"))
    hand = skeleton.positions[skeleton.index("right_hand")]
    box = hand + np.array([[-20, -20], [20, -20], [20, 20], [-20, 20]])
    edited = apply_edit(edited, Correction(curve=box, bone="right_hand"))
    edited = apply_edit(edited, DepthEdit(value=2, at=tuple(head)))
    return {
        "drawing": folder.name,
        "vertices": len(character.mesh.V),
        "filter_240_ms": _median_ms(lambda: filter_bones(skeleton, motion, settings)),
        "exaggerate_pose_ms": _median_ms(crouch),
        "curve_edit_ms": _median_ms(lambda: tune_with_curve(deformer, bent, U, curve)),
        "drag_ms": _median_ms(lambda: drag_points(deformer, U, [grab], [grab + (2.0, -2.2)])),
        "undo_ms": _median_ms(lambda: undo(edited), repeats=3),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path)
    args = parser.parse_args()
    folders = args.drawings or sorted(p for p in DEFAULT_DIR.iterdir() if (p / "char_cfg.yaml").is_file())
    for folder in folders:
        print(json.dumps(bench(folder)), flush=True)


if __name__ == "__main__":
    main()
