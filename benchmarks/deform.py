"""Deformation speed against libigl's ARAP, and rendering speed; JSON lines.

    python benchmarks/deform.py [DRAWING_DIR ...]

Each drawing (default: every drawing in ../shared/data/drawings, with its char_cfg.yaml
skeleton) is rigged to about 1,500 vertices and animated through a sequence of poses: rest,
elbows bent, knees bent, arms raised, back to rest, 8 in-betweens apart (40 frames). Runs on one
core (thread pools pinned before NumPy loads). Needs the benchmark extra: pip install -e '.[bench]'.

Keys, one line per drawing:
  drawing, vertices, free        mesh size; vertices stage two moves (the joint areas)
  precompute_ms                  building the Deformer (needle model, joint area, factorisation)
  frame_ms                       median time per frame, stage one + stage two, each frame's solve
                                 warm-started from the previous frame (goal: at most 2)
  cold_frame_ms                  median per key pose solved from stage one alone (no warm start)
  iterations                     median stage-two iterations per frame
  libigl_frame_ms                median time per frame of libigl's ARAP (ARAP_ENERGY_TYPE_ELEMENTS,
                                 10 iterations) on the same mesh, with the vertices nearest the
                                 joints and to 3 samples per bone as handles placed where our
                                 stage one puts them, warm-started from its previous frame
  speedup                        libigl_frame_ms / frame_ms (goal: at least 3)
One more line: render_1024_ms, the median time to render one 1024x1024 frame of the bundled
character (goal: at most 15).
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toonmotion.animate.timeline import interpolate_pose  # noqa: E402
from toonmotion.deform.deformer import Deformer  # noqa: E402
from toonmotion.deform.depth import draw_order  # noqa: E402
from toonmotion.io.drawing_folder import rig_drawing_folder  # noqa: E402
from toonmotion.render.raster import render_mesh  # noqa: E402
from toonmotion.rig.pipeline import rig_drawing  # noqa: E402
from toonmotion.rig.pose import Pose, rotate_about  # noqa: E402
from toonmotion.samples import sample_character  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
INBETWEENS = 8


def key_poses(skeleton):
    """Rest, elbows bent 60 degrees, knees bent 45, arms raised, rest (AD joint names)."""
    rest = skeleton.positions
    elbows = rotate_about(skeleton, rest, "right_elbow", np.pi / 3)
    elbows = rotate_about(skeleton, elbows, "left_elbow", -np.pi / 3)
    knees = rotate_about(skeleton, rest, "right_knee", np.pi / 4)
    knees = rotate_about(skeleton, knees, "left_knee", -np.pi / 4)
    raised = rest
    for side, outwards in (("right", -1.0), ("left", 1.0)):
        shoulder, elbow = skeleton.index(f"{side}_shoulder"), skeleton.index(f"{side}_elbow")
        d = raised[elbow] - raised[shoulder]
        target = np.arctan2(-np.sin(np.pi / 3), outwards * np.cos(np.pi / 3))
        turn = (target - np.arctan2(d[1], d[0]) + np.pi) % (2 * np.pi) - np.pi
        raised = rotate_about(skeleton, raised, f"{side}_shoulder", turn)
    return [Pose(np.array(p)) for p in (rest, elbows, knees, raised, rest)]


def pose_sequence(skeleton, keys):
    frames = [keys[0]]
    for a, b in zip(keys, keys[1:], strict=False):
        frames += [interpolate_pose(skeleton, a, b, (i + 1) / INBETWEENS) for i in range(INBETWEENS)]
    return frames


def handles(mesh, skeleton):
    """Vertices nearest each joint and 3 samples along each bone, unique."""
    bones = skeleton.bones
    A, B = skeleton.positions[bones[:, 0]], skeleton.positions[bones[:, 1]]
    samples = [A + t * (B - A) for t in (0.25, 0.5, 0.75)]
    points = np.concatenate([skeleton.positions, *samples])
    nearest = np.argmin(np.linalg.norm(mesh.V[:, None] - points[None], axis=2), axis=0)
    return np.unique(nearest)


def bench_drawing(folder):
    import igl  # the benchmark extra

    character = rig_drawing_folder(folder)
    skeleton, mesh = character.skeleton, character.mesh

    start = time.perf_counter()
    deformer = Deformer(character)
    precompute_ms = (time.perf_counter() - start) * 1e3

    keys = key_poses(skeleton)
    sequence = pose_sequence(skeleton, keys)
    times, iterations, stage_ones = [], [], []
    for _ in range(3):
        previous = None
        for pose in sequence:
            t0 = time.perf_counter()
            previous = deformer.deform(pose, previous=previous)
            times.append((time.perf_counter() - t0) * 1e3)
            iterations.append(previous.iterations)
            stage_ones.append(previous.stage_one)
    cold = []
    for pose in keys[1:-1]:
        for _ in range(5):
            t0 = time.perf_counter()
            deformer.deform(pose)
            cold.append((time.perf_counter() - t0) * 1e3)

    b = handles(mesh, skeleton)
    data = igl.ARAPData()
    data.energy = igl.ARAP_ENERGY_TYPE_ELEMENTS
    data.max_iter = 10
    V, F = np.ascontiguousarray(mesh.V), np.ascontiguousarray(mesh.F, dtype=np.int64)
    igl.arap_precomputation(V, F, 2, b.astype(np.int32), data)
    igl_times = []
    U = V.copy()
    for U1 in stage_ones:
        bc = np.ascontiguousarray(U1[b])
        t0 = time.perf_counter()
        U = igl.arap_solve(bc, data, U)
        igl_times.append((time.perf_counter() - t0) * 1e3)

    frame_ms = statistics.median(times)
    libigl_ms = statistics.median(igl_times)
    return {
        "drawing": folder.name,
        "vertices": len(mesh.V),
        "free": int(deformer.free.sum()),
        "handles": len(b),
        "precompute_ms": round(precompute_ms, 2),
        "frame_ms": round(frame_ms, 3),
        "cold_frame_ms": round(statistics.median(cold), 3),
        "iterations": statistics.median(iterations),
        "libigl_frame_ms": round(libigl_ms, 3),
        "speedup": round(libigl_ms / frame_ms, 2),
    }


def bench_render():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    deformer = Deformer(character)
    U = deformer.deform(key_poses(skeleton)[3]).U
    order = draw_order(character.mesh, character.binding, character.depth)
    # The figure fills the frame's height, as in a 1024x1024 export.
    lo, hi = U.min(axis=0) - 10, U.max(axis=0) + 10
    side = max(hi - lo)
    view = (lo[0], lo[1], lo[0] + side, lo[1] + side)
    times = []
    for _ in range(15):
        t0 = time.perf_counter()
        render_mesh(character.texture, character.mesh.V, U, character.mesh.F, size=(1024, 1024), view=view,
                    order=order, background=(255, 255, 255), mask=character.mask)
        times.append((time.perf_counter() - t0) * 1e3)
    return {"render_1024_ms": round(statistics.median(times), 2), "triangles": len(character.mesh.F)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders (default: the shared ones)")
    args = parser.parse_args(argv)
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:
        pass
    folders = args.drawings or sorted(p for p in DEFAULT_DIR.glob("*") if (p / "char_cfg.yaml").is_file())
    if not folders:
        sys.exit(f"no drawings found (looked in {DEFAULT_DIR})")
    for folder in folders:
        print(json.dumps(bench_drawing(folder)), flush=True)
    print(json.dumps(bench_render()), flush=True)


if __name__ == "__main__":
    main()
