"""Deformation speed against libigl's ARAP, folds and area over extreme poses, and rendering
speed; JSON lines.

    python benchmarks/deform.py [DRAWING_DIR|sample ...] [--decomposition straight|geodesic]
                                [--skinning one-bone|weights ...] [--joint-anchor W] [--joint-width W]
                                [--exact] [--compiled] [--no-table]

Each drawing folder (texture.png, mask.png, char_cfg.yaml; default: every drawing in
../shared/data/drawings, then the bundled sample character, named ``sample``) is rigged to about
1,500 vertices. Every pose is built from the
skeleton's structure, never from joint names: a *bend joint* is one with a parent and exactly one
child; a *chain* starts at a joint whose parent has two or more children (or is the root) and
runs to a leaf; *above the root* is above it in the image (drawings stand upright).
Runs on one core (thread pools pinned before NumPy loads). Needs the benchmark extra:
pip install -e '.[bench]'.

Keys, one line per drawing and binding (--skinning one-bone weights, both by default):
  drawing, vertices, free        mesh size; vertices stage two moves (the joint areas)
  decomposition, fallback        the rule; vertices without an inside path to their bone
  skinning                       one-bone (the thesis) or weights (blended needles, 7.2 item 3)
  solve                          default, or converged (--exact: tolerance 1e-10, the eq. 3.8
                                 minimum over the same joint areas)
  compiled                       stage two's compiled loop (--compiled, as the editor runs it;
                                 DeformSettings.compiled) or the NumPy loop (the commands' default)
  precompute_ms                  building the Deformer (needle model, joint area, factorisation)
  frame_ms                       median time per frame, stage one + stage two, each frame's solve
                                 warm-started from the previous frame; the sequence is rest,
                                 every bend joint at 60 degrees, chains raised 60 degrees, rest,
                                 8 in-betweens apart (goal: at most 3, and speedup at least 3)
  frame_ms_p99                   the 99th percentile of those frames
  cold_frame_ms                  median per key pose solved from stage one alone
  pose_ms_max                    the slowest single-pose solve over the sequence, the key poses
                                 cold, the extreme set and the stretch set (goal: at most 15)
  iterations                     median stage-two iterations per frame of the sequence
  iterations_max                 the most over every pose above, all of a pose's solves summed
                                 (goal: at most 30)
  libigl_frame_ms                median time per frame of libigl's ARAP (ARAP_ENERGY_TYPE_ELEMENTS,
                                 10 iterations) on the same mesh, with the vertices nearest the
                                 joints and to 3 samples per bone as handles placed where our
                                 stage one puts them, warm-started from its previous frame
  speedup                        libigl_frame_ms / frame_ms (goal: at least 3)
  extreme_poses, inverted        the extreme pose set (each bend joint bent 150 degrees above the
                                 root and 120 below, both ways, one at a time; every chain raised
                                 overhead, or sideways below the root; the upper body turned 40
                                 degrees both ways against the lower) and the inverted triangles
                                 after stage two summed over it (goal: 0)
  area_change_max                largest whole-figure area change over every bone stretched 1.5x,
                                 one at a time, and the single-frame filter's jump (goal: 0.02)
  edge_stretch_max               the largest factor by which a mesh edge grows beyond the stretch
                                 of the bones its ends follow, over the sequence, the extreme set
                                 and the stretch set: spikes (goal: at most 4)
  joint_anchor, joint_width      stage two's joint anchor weight and joint area width (DeformSettings)
  joint_gap_px, joint_gap_max_px how far the drawing carries its joints from the skeleton's (the
                                 point of the drawing at each joint in the rest pose, against the
                                 pose's joint), mean and largest over the sequence's frames and the
                                 extreme poses, joints drawn inside the figure (goal: at most 5)
A line per drawing with the key table_3_1 (thesis Table 3.1): the joint-area solve against a
full-mesh solve of the same energy (every vertex free) over the sequence, warm-started, no
unfolding: each one's free vertices, median ms per iteration and per frame, and the ratios.
One more line: render_1024_ms, the median time to render one 1024x1024 frame of the bundled
character (goal: at most 15).
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

from toonmotion.animate.timeline import interpolate_pose  # noqa: E402
from toonmotion.deform.deformer import Deformer, DeformSettings  # noqa: E402
from toonmotion.deform.depth import draw_order  # noqa: E402
from toonmotion.deform.joint_solve import JointSolver  # noqa: E402
from toonmotion.deform.needles import stretch_maps  # noqa: E402
from toonmotion.geometry.polygon import triangle_areas  # noqa: E402
from toonmotion.io.drawing_folder import rig_drawing_folder  # noqa: E402
from toonmotion.render.raster import render_mesh  # noqa: E402
from toonmotion.rig.character import RigSettings  # noqa: E402
from toonmotion.rig.pipeline import rig_drawing  # noqa: E402
from toonmotion.samples import sample_character  # noqa: E402
from toonmotion.shape.mesh import unique_edges  # noqa: E402
from toonmotion.testing.poses import extreme_poses, filter_jump, key_poses, stretch_poses  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
INBETWEENS = 8


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


def rig_for(folder, decomposition):
    """``(name, Character)``: a drawing folder rigged, or the bundled sample for ``"sample"``."""
    settings = RigSettings(decomposition=decomposition)
    if str(folder) == "sample":
        rgba, skeleton = sample_character()
        return "sample", rig_drawing(rgba, skeleton=skeleton, settings=settings)
    return folder.name, rig_drawing_folder(folder, settings=settings)


def bench_drawing(name, character, decomposition, skinning, joint_anchor, exact=False, compiled=False,
                  joint_width=None):
    import igl  # the benchmark extra

    skeleton, mesh = character.skeleton, character.mesh

    start = time.perf_counter()
    options = {"skinning": skinning, "compiled": compiled}
    if joint_anchor is not None:
        options["joint_anchor"] = joint_anchor
    if joint_width is not None:
        options["joint_width"] = joint_width
    if exact:  # iterated to convergence: eq. 3.8's minimum over the same joint areas
        options.update(tolerance=1e-10, max_iterations=5000)
    settings = DeformSettings(**options)
    deformer = Deformer(character, settings)
    precompute_ms = (time.perf_counter() - start) * 1e3

    keys = key_poses(skeleton)
    sequence = pose_sequence(skeleton, keys)
    times, iterations, stage_ones, gaps, pose_ms = [], [], [], [], []
    stretch = []
    for round_ in range(3):
        previous = None
        for pose in sequence:
            t0 = time.perf_counter()
            previous = deformer.deform(pose, previous=previous)
            times.append((time.perf_counter() - t0) * 1e3)
            iterations.append(previous.iterations)
            stage_ones.append(previous.stage_one)
            if round_ == 0:
                gaps.append(joint_gaps(deformer, previous.U, pose))
                stretch.append(edge_stretch(character, previous.U, pose))
    pose_ms += times
    cold = []
    for pose in keys[1:-1]:
        for _ in range(5):
            t0 = time.perf_counter()
            deformer.deform(pose)
            cold.append((time.perf_counter() - t0) * 1e3)
    pose_ms += cold

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
    F = mesh.F
    extremes = extreme_poses(skeleton)
    inverted = 0
    for _, pose in extremes:
        result = timed_solve(deformer, pose, pose_ms, iterations)
        inverted += int((triangle_areas(result.U, F) <= 0).sum())
        gaps.append(joint_gaps(deformer, result.U, pose))
        stretch.append(edge_stretch(character, result.U, pose))
    gaps = np.concatenate(gaps)
    rest_area = float(triangle_areas(mesh.V, F).sum())
    area_cases = [*stretch_poses(skeleton), ("filter jump", filter_jump(character))]
    area_change = 0.0
    for _, pose in area_cases:
        result = timed_solve(deformer, pose, pose_ms, iterations)
        area_change = max(area_change, abs(float(triangle_areas(result.U, F).sum()) / rest_area - 1))
        stretch.append(edge_stretch(character, result.U, pose))
    return {
        "drawing": name,
        "decomposition": decomposition,
        "skinning": skinning,
        "solve": "converged" if exact else "default",
        "compiled": compiled,
        "vertices": len(mesh.V),
        "free": int(deformer.free.sum()),
        "fallback": int(character.binding.fallback.sum()),
        "handles": len(b),
        "precompute_ms": round(precompute_ms, 2),
        "frame_ms": round(frame_ms, 3),
        "frame_ms_p99": round(float(np.percentile(times, 99)), 3),
        "cold_frame_ms": round(statistics.median(cold), 3),
        "pose_ms_max": round(max(pose_ms), 2),
        "iterations": statistics.median(iterations[:len(times)]),
        "iterations_max": max(iterations),
        "libigl_frame_ms": round(libigl_ms, 3),
        "speedup": round(libigl_ms / frame_ms, 2),
        "extreme_poses": len(extremes),
        "inverted": inverted,
        "area_change_max": round(area_change, 4),
        "edge_stretch_max": round(max(stretch), 2),
        "joint_anchor": deformer.settings.joint_anchor,
        "joint_width": deformer.settings.joint_width,
        "joint_gap_px": round(float(gaps.mean()), 3),
        "joint_gap_max_px": round(float(gaps.max()), 2),
    }


def timed_solve(deformer, pose, pose_ms, iterations):
    """``deformer.deform(pose)`` from stage one, its time and iterations appended to the lists."""
    t0 = time.perf_counter()
    result = deformer.deform(pose)
    pose_ms.append((time.perf_counter() - t0) * 1e3)
    iterations.append(result.iterations)
    return result


def edge_stretch(character, U, pose):
    """The largest factor by which a mesh edge grows beyond its bones' own stretch in ``pose``:
    each edge's length over its rest length, divided by the larger stretch of the bones its two
    ends follow (at least 1). A spike drawn out of the figure shows as a large factor."""
    skeleton, mesh = character.skeleton, character.mesh
    bones = skeleton.bones
    rest = np.maximum(skeleton.bone_lengths, 1e-9)
    posed = np.linalg.norm(pose.positions[bones[:, 1]] - pose.positions[bones[:, 0]], axis=1)
    bone_stretch = np.maximum(posed / rest, 1.0)
    edges = unique_edges(mesh.F)
    grown = np.linalg.norm(U[edges[:, 0]] - U[edges[:, 1]], axis=1) / np.maximum(
        np.linalg.norm(mesh.V[edges[:, 0]] - mesh.V[edges[:, 1]], axis=1), 1e-9)
    bone = character.binding.bone
    allowed = np.maximum(bone_stretch[bone[edges[:, 0]]], bone_stretch[bone[edges[:, 1]]])
    return float((grown / allowed).max())


def bench_full_mesh(name, character, compiled=False):
    """Table 3.1: the joint-area solve against a full-mesh solve of the same energy on the same
    poses (every vertex free), per iteration and per frame, warm-started along the sequence."""
    deformer = Deformer(character, DeformSettings(unfold=0, compiled=compiled))
    every = np.ones(len(character.mesh.V), bool)
    full = JointSolver(character.mesh, every, weights=deformer.settings.weights,
                       edge_term=deformer.settings.edge_term, anchors=deformer.anchors, compiled=compiled)
    sequence = pose_sequence(character.skeleton, key_poses(character.skeleton))
    s = deformer.settings
    area = float(triangle_areas(character.mesh.V, character.mesh.F).sum())
    out = {}
    for label, solver in (("joint_area", deformer.solver), ("full_mesh", full)):
        frame, per_iteration, previous = [], [], None
        for pose in sequence:
            U1 = deformer.stage_one(pose)
            maps = stretch_maps(deformer.needles, pose.positions, preserve_area=s.preserve_area)
            shape = deformer._shape_for(solver, maps)
            initial = None if previous is None else U1 + previous
            t0 = time.perf_counter()
            result = solver.solve(U1, initial=initial, max_iterations=s.max_iterations, tolerance=s.tolerance,
                                  shape=shape, area=area)
            elapsed = (time.perf_counter() - t0) * 1e3
            previous = result.U - U1
            frame.append(elapsed)
            per_iteration.append(elapsed / max(result.iterations, 1))
        out[f"{label}_free"] = len(solver.free)
        out[f"{label}_iteration_ms"] = round(statistics.median(per_iteration), 4)
        out[f"{label}_frame_ms"] = round(statistics.median(frame), 3)
    out["iteration_ratio"] = round(out["full_mesh_iteration_ms"] / out["joint_area_iteration_ms"], 2)
    out["frame_ratio"] = round(out["full_mesh_frame_ms"] / out["joint_area_frame_ms"], 2)
    return {"table_3_1": name, **out}


def joint_gaps(deformer, U, pose):
    """How far the drawing deformed to ``U`` carries each joint drawn inside it from ``pose``'s."""
    drawn = deformer.drawn_joints(U)
    inside = np.isfinite(drawn[:, 0])
    return np.hypot(*(drawn[inside] - pose.positions[inside]).T)


def bench_render():
    rgba, skeleton = sample_character()
    character = rig_drawing(rgba, skeleton=skeleton)
    deformer = Deformer(character)
    U = deformer.deform(key_poses(skeleton)[2]).U
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
    parser.add_argument("--decomposition", choices=("geodesic", "straight"), default="geodesic",
                        help="the decomposition rule to rig with (default: geodesic, toonmotion's default)")
    parser.add_argument("--skinning", choices=("one-bone", "weights"), nargs="+",
                        default=["one-bone", "weights"],
                        help="the bindings to measure, a line each (default: both)")
    parser.add_argument("--joint-anchor", type=float, default=None, metavar="W",
                        help="stage two's joint anchor weight (default: DeformSettings' default)")
    parser.add_argument("--joint-width", type=float, default=None, metavar="W",
                        help="stage two's joint area width (default: DeformSettings' default)")
    parser.add_argument("--exact", action="store_true",
                        help="also measure stage two iterated to convergence (tolerance 1e-10), a line each")
    parser.add_argument("--compiled", action="store_true",
                        help="stage two's compiled loop (DeformSettings.compiled, as the editor runs it)")
    parser.add_argument("--no-table", dest="table", action="store_false",
                        help="skip Table 3.1's line (the joint-area solve against a full-mesh solve)")
    args = parser.parse_args(argv)
    try:
        import cv2

        cv2.setNumThreads(1)
    except ImportError:
        pass
    folders = args.drawings or [*sorted(p for p in DEFAULT_DIR.glob("*") if (p / "char_cfg.yaml").is_file()),
                                Path("sample")]
    for folder in folders:
        name, character = rig_for(folder, args.decomposition)
        for skinning in args.skinning:
            line = bench_drawing(name, character, args.decomposition, skinning, args.joint_anchor,
                                 compiled=args.compiled, joint_width=args.joint_width)
            print(json.dumps(line), flush=True)
            if args.exact:
                line = bench_drawing(name, character, args.decomposition, skinning, args.joint_anchor,
                                     exact=True, compiled=args.compiled, joint_width=args.joint_width)
                print(json.dumps(line), flush=True)
        if args.table:
            print(json.dumps(bench_full_mesh(name, character, args.compiled)), flush=True)
    print(json.dumps(bench_render()), flush=True)


if __name__ == "__main__":
    main()
