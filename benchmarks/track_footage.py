"""Joint tracking on footage whose true joints are known: a video and its frame motion; JSON lines.

    python benchmarks/track_footage.py [VIDEO MOTION.json ...] [--drawings FOLDER ...] [--seeds N ...]
                                       [--free] [--frame-by-frame | --both-ways] [--full-resolution]

Each VIDEO is read as ``toonmotion track`` reads it, and MOTION.json holds its true joints in the
video's pixels, frame by frame (what ``toonmotion animate ... --save-frame-motion`` writes beside
the frames it renders). The joints start at their true frame-0 places with rectangles sized as
``track`` suggests them (twice the figure's local thickness), the figure found as ``track`` finds
it; the tracker runs on one core. Without arguments the bundled character's demo is made in a
temporary folder as ``make demo`` makes ``demo/demo.mp4`` and ``demo/motion.json`` (sample, rig,
animate), and measured. ``--drawings`` takes Animated Drawings character folders (``texture.png``,
``mask.png``, ``char_cfg.yaml``; e.g. ``../shared/data/drawings/char*``): each is rigged and
animated into footage by key-frames that swing its bones, one clip per ``--seeds`` seed
(``toonmotion.testing.swinging_keys``; 49 frames at 12 fps, bones turning up to 8-30 degrees
about their parents). ``--free`` does not hold joints to the figure; ``--frame-by-frame`` leaves
out the choice of each joint's path over the whole clip (``TrackSettings.best_path``);
``--both-ways`` also tracks backwards and chooses between the two ways (``TrackSettings.both_ways``);
``--full-resolution`` tracks footage larger than 1000 px at its own size, not halved
(``TrackSettings.working_side``).

Keys, one line per video:
  video, joints, frames            (drawings: video is FOLDER:seed)
  mean_px, median_px, pck5, lost   as in benchmarks/track.py, frame 0 left out
  worst_joint, worst_mean_px       the joint with the largest mean error
  fps                              frames tracked per second (reading the video not counted)
  figure, best_path, both_ways     the settings the line was measured with
  working_side                     TrackSettings.working_side, null at full resolution
Goal: mean error at most 3 px on the demo.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import tempfile  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from toonmotion.animate.motion import motion_for  # noqa: E402
from toonmotion.capture.footage import capture_motion, suggested_sizes  # noqa: E402
from toonmotion.capture.track_settings import TrackSettings  # noqa: E402
from toonmotion.io.frames import load_frames  # noqa: E402
from toonmotion.io.motion_json import load_motion  # noqa: E402
from toonmotion.io.pose_json import save_keyframes  # noqa: E402
from toonmotion.io.skeleton_json import load_skeleton_file  # noqa: E402
from toonmotion.rig.skeleton import Skeleton  # noqa: E402
from toonmotion.testing.mocap_tracking import tracking_errors, tracking_scores  # noqa: E402
from toonmotion.testing.swinging_keys import swinging_keys  # noqa: E402

cv2.setNumThreads(1)


def make_demo(folder):
    """``demo.mp4`` and ``motion.json`` made as ``make demo`` makes them, in ``folder``."""
    cli = Path(sys.executable).with_name("toonmotion")
    steps = [
        ["sample", "-o", "hero.png", "--skeleton", "hero.json", "--keys", "keys.json"],
        ["rig", "hero.png", "--skeleton", "hero.json", "-o", "hero"],
        ["depth", "hero", "right_elbow=1", "right_hand=1"],
        ["animate", "hero", "keys.json", "-o", "demo.mp4", "--save-frame-motion", "motion.json"],
    ]
    for step in steps:
        subprocess.run([str(cli), *step], cwd=folder, check=True, capture_output=True)
    return folder / "demo.mp4", folder / "motion.json"


def make_swinging(drawing, seeds, folder):
    """An Animated Drawings folder rigged and animated by swinging key-frames, one clip per seed:
    ``[(video, motion.json, seed), ...]`` in ``folder``."""
    cli = Path(sys.executable).with_name("toonmotion")
    project = folder / f"{drawing.name}_project"
    subprocess.run([str(cli), "rig", str(drawing / "texture.png"), "--mask", str(drawing / "mask.png"),
                    "--skeleton", str(drawing / "char_cfg.yaml"), "-o", str(project)], check=True,
                   capture_output=True)
    skeleton = load_skeleton_file(drawing / "char_cfg.yaml")
    clips = []
    for seed in seeds:
        keys, video, truth = (folder / f"{drawing.name}_{seed}{suffix}" for suffix in (".keys.json", ".mp4",
                                                                                       ".motion.json"))
        save_keyframes(keys, skeleton, swinging_keys(skeleton, seed=seed))
        subprocess.run([str(cli), "animate", str(project), str(keys), "-o", str(video), "--save-frame-motion",
                        str(truth)], check=True, capture_output=True)
        clips.append((video, truth, seed))
    return clips


def bench(video, truth_file, figure=True, best_path=True, both_ways=False, full_resolution=False):
    frames, fps = load_frames(video)
    truth = load_motion(truth_file)
    skeleton = truth.skeleton
    positions = motion_for(skeleton, truth, where="the true motion")
    count = min(len(frames), len(positions))
    frames, positions = frames[:count], positions[:count]
    sizes = suggested_sizes(frames, positions[0])
    start = time.perf_counter()
    placed = Skeleton.from_joints([(n, p, tuple(xy)) for (n, p, _), xy in zip(skeleton.joints(), positions[0],
                                                                              strict=True)])
    settings = TrackSettings(figure=figure, best_path=best_path, both_ways=both_ways)
    if full_resolution:
        settings = replace(settings, working_side=None)
    captured = capture_motion(frames, placed, sizes, fps=fps or 24.0, settings=settings)
    seconds = time.perf_counter() - start
    found = captured.motion.positions
    per_joint = tracking_errors(found, positions).reshape(count - 1, -1).mean(axis=0)
    worst = int(np.argmax(per_joint))
    scores = tracking_scores(found, positions)
    return {"video": str(video), "joints": len(skeleton), "frames": count, **scores,
            "worst_joint": skeleton.names[worst], "worst_mean_px": round(float(per_joint[worst]), 3),
            "fps": round((count - 1) / max(seconds, 1e-9), 1), "figure": figure, "best_path": best_path,
            "both_ways": both_ways, "working_side": settings.working_side}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pairs", nargs="*", type=Path, help="VIDEO MOTION.json, repeated")
    parser.add_argument("--drawings", nargs="+", type=Path, default=[],
                        help="Animated Drawings folders to animate by swinging key-frames and track")
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2], help="swinging key-frames' seeds")
    parser.add_argument("--free", action="store_true", help="do not hold joints to the figure")
    ways = parser.add_mutually_exclusive_group()
    ways.add_argument("--frame-by-frame", action="store_true",
                      help="leave out the choice of each joint's path over the whole clip")
    ways.add_argument("--both-ways", action="store_true",
                      help="also track backwards, and choose each joint's path between the two ways")
    parser.add_argument("--full-resolution", action="store_true",
                        help="track footage larger than 1000 px at its own size, not halved")
    args = parser.parse_args()
    how = {"figure": not args.free, "best_path": not args.frame_by_frame, "both_ways": args.both_ways,
           "full_resolution": args.full_resolution}
    if len(args.pairs) % 2:
        parser.error("give each video with its true motion: VIDEO MOTION.json [VIDEO MOTION.json ...]")
    pairs = list(zip(args.pairs[::2], args.pairs[1::2], strict=True))
    with tempfile.TemporaryDirectory() as folder:
        if not pairs and not args.drawings:
            pairs = [make_demo(Path(folder))]
        for video, truth in pairs:
            print(json.dumps(bench(video, truth, **how)), flush=True)
        for drawing in args.drawings:
            for video, truth, seed in make_swinging(drawing, args.seeds, Path(folder)):
                line = bench(video, truth, **how)
                print(json.dumps({**line, "video": f"{drawing}:{seed}"}), flush=True)


if __name__ == "__main__":
    main()
