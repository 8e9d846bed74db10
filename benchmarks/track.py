"""Joint tracking on rendered motion capture, against OpenCV's trackers; JSON lines.

    python benchmarks/track.py [CLIP.bvh ...] [--frames N] [--trackers toonmotion,MIL,CSRT,KCF]

Each clip (default: every .bvh in ../shared/data/mocap) is read, 16 joints are picked by the
usual naming conventions (CMU, FAIR, Mixamo, Rokoko), projected orthographically from the front,
fitted into 640x480, resampled to about 30 fps (a leading T-pose frame the motion jumps away
from is dropped), and rendered as a textured limb figure over a
textured background, drawn far to near so limbs cross and hide each other
(``toonmotion.capture.synthetic``). Every tracker starts from the true frame-1 rectangles (a
square of the joint disc's diameter, ~30 px) and runs on one core.

Keys, one line per clip and tracker:
  clip, tracker, joints, frames
  mean_px, median_px   error of the tracked joint centres against the true ones, over every
                       joint and frame after the first
  pck5                 fraction of joint-frames within 5 px
  lost                 fraction of joint-frames more than 20 px off
  fps                  frames tracked per second, all 16 joints (rendering not counted)
  ratio_mean_px        this tracker's mean error over toonmotion's (OpenCV lines only)
Goal on the jumping-jacks clip: toonmotion mean <= 3 px, pck5 >= 0.95, fps > 100, and a lower
mean error than every OpenCV tracker.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from toonmotion.capture.mocap import (  # noqa: E402
    STANDARD_JOINTS,
    fit_to_frame,
    pick_joints,
    project_orthographic,
    standard_skeleton_parents,
)
from toonmotion.capture.synthetic import limb_figure_frames  # noqa: E402
from toonmotion.capture.tracker import TrackSetup, track  # noqa: E402
from toonmotion.io.bvh import forward_kinematics, load_bvh  # noqa: E402
from toonmotion.rig.skeleton import Skeleton  # noqa: E402

cv2.setNumThreads(1)
DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
SIZE = (640, 480)
FPS = 30.0
OPENCV = {"MIL": "TrackerMIL_create", "CSRT": "TrackerCSRT_create", "KCF": "TrackerKCF_create"}


def rendered_clip(path, *, frames=None, fps=FPS, seed=0):
    """A clip as ``(images (T, h, w, 3), truth (T, 16, 2), skeleton, box side, fps)``."""
    clip = load_bvh(path)
    X = forward_kinematics(clip)
    # The MotionBuilder-style CMU files start with a T-pose frame that the motion jumps away from.
    jumps = np.linalg.norm(np.diff(X, axis=0), axis=2).max(axis=1)
    if len(jumps) > 2 and jumps[0] > 5 * np.median(jumps):
        X = X[1:]
    step = max(1, round(clip.fps / fps))
    X = X[::step][:frames]
    picks = pick_joints(clip.names, clip.parents)
    X = X[:, [picks[n] for n in STANDARD_JOINTS]]
    points, depth = project_orthographic(X, with_depth=True)
    truth = fit_to_frame(points, SIZE)
    parents_by_name = standard_skeleton_parents()
    parents = np.array([-1 if parents_by_name[n] is None else STANDARD_JOINTS.index(parents_by_name[n])
                        for n in STANDARD_JOINTS])
    images, radius = limb_figure_frames(truth, parents, depth=depth, size=SIZE, seed=seed)
    skeleton = Skeleton.from_joints(
        [(n, parents_by_name[n], tuple(truth[0, i])) for i, n in enumerate(STANDARD_JOINTS)]
    )
    order = [STANDARD_JOINTS.index(n) for n in skeleton.names]
    return images, truth[:, order], skeleton, 2 * radius, clip.fps / step


def run_toonmotion(images, skeleton, side):
    setup = TrackSetup(skeleton=skeleton, sizes=np.full((len(skeleton), 2), side))
    start = time.perf_counter()
    result = track(images, setup)
    return result.positions, time.perf_counter() - start


def run_opencv(kind, images, start_points, side):
    trackers = []
    frames = [cv2.cvtColor(f, cv2.COLOR_RGB2BGR) for f in images]
    for x, y in start_points:
        tracker = getattr(cv2, OPENCV[kind])()
        box = (int(round(x - side / 2)), int(round(y - side / 2)), int(round(side)), int(round(side)))
        tracker.init(frames[0], box)
        trackers.append((tracker, np.array([x, y], dtype=float)))
    out = np.empty((len(frames), len(start_points), 2))
    out[0] = start_points
    start = time.perf_counter()
    for t in range(1, len(frames)):
        for j, (tracker, last) in enumerate(trackers):
            ok, box = tracker.update(frames[t])
            if ok:
                last[:] = (box[0] + box[2] / 2, box[1] + box[3] / 2)
            out[t, j] = last  # a tracker that reports failure stays where it was last seen
    return out, time.perf_counter() - start


def scores(found, truth):
    error = np.hypot(*(found[1:] - truth[1:]).reshape(-1, 2).T)
    return {
        "mean_px": round(float(error.mean()), 3),
        "median_px": round(float(np.median(error)), 3),
        "pck5": round(float((error <= 5).mean()), 4),
        "lost": round(float((error > 20).mean()), 4),
    }


def bench(path, trackers, frames=None):
    images, truth, skeleton, side, fps = rendered_clip(path, frames=frames)
    lines, ours = [], None
    for name in trackers:
        if name == "toonmotion":
            found, seconds = run_toonmotion(images, skeleton, side)
        else:
            found, seconds = run_opencv(name, images, truth[0], side)
        line = {"clip": Path(path).stem, "tracker": name, "joints": len(skeleton), "frames": len(images),
                **scores(found, truth), "fps": round((len(images) - 1) / max(seconds, 1e-9), 1)}
        if name == "toonmotion":
            ours = line["mean_px"]
        elif ours:
            line["ratio_mean_px"] = round(line["mean_px"] / ours, 2)
        lines.append(line)
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="*", type=Path)
    parser.add_argument("--frames", type=int, default=None, help="Use only the first N frames.")
    parser.add_argument("--trackers", default="toonmotion,MIL,CSRT,KCF")
    args = parser.parse_args()
    clips = args.clips or sorted(DEFAULT_DIR.glob("*.bvh"))
    for clip in clips:
        for line in bench(clip, args.trackers.split(","), frames=args.frames):
            print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
