"""Joint tracking on rendered motion capture, against OpenCV's trackers; JSON lines.

    python benchmarks/track.py [CLIP.bvh ...] [--frames N] [--trackers toonmotion,MIL,CSRT,KCF]
                               [--style textured|flat ...] [--twos] [--noise SIGMA] [--seed N]
                               [--frame-by-frame | --both-ways] [--repeat N]
                               [--size WxH] [--full-resolution] [--restart N]

Each clip (default: every .bvh in ../shared/data/mocap) is read, 16 joints are picked by the
usual naming conventions (CMU, FAIR, Mixamo, Rokoko), projected orthographically from the front,
fitted into 640x480 (``--size``), resampled to about 30 fps (a leading T-pose frame the motion jumps away
from is dropped), and rendered as a limb figure drawn far to near so limbs cross and hide each
other (``toonmotion.testing.mocap_tracking``, which also scores): ``--style textured`` (the
default) a textured figure over a textured background, ``--style flat`` a cel cartoon, flat
colours from a small palette with dark outlines over a plain background. ``--twos`` holds each
drawing two frames (animation on twos); ``--noise`` adds Gaussian noise of that many grey levels
to every frame (default 1.5 on twos, so held frames differ a little, as scanned or filmed ones do,
and none on ones: compare twos with ``--noise 1.5`` on ones); ``--seed`` draws the
figure with other textures or colours; ``--frame-by-frame`` leaves out toonmotion's choice of each
joint's path over the whole clip (``TrackSettings.best_path``), ``--both-ways`` also tracks
backwards and chooses between the two ways (``TrackSettings.both_ways``). On frames larger than
1000 px (``--size 1280x960``) toonmotion tracks them halved (``TrackSettings.working_side``);
``--full-resolution`` tracks them at their own size. ``--restart N`` starts every tracker again
from the true joints every N frames, each stretch on its own, and scores the frames between:
one joint lost early cannot then weigh on the rest of the clip, which steadies comparisons of
two versions of the tracker (see docs/capture.md). Every tracker starts from the true frame-1
rectangles (a square of the joint disc's diameter, ~30 px at 640x480) and runs on
one core. toonmotion tracks each clip ``--repeat`` times (default 3), as ``timeit`` does, and its
speed is that of the fastest run (a shared machine only ever slows a run down; the runs give the
same joints); OpenCV's trackers, at a few frames a second, run once.

Keys, one line per clip, style and tracker:
  clip, style, twos, noise, seed, tracker, joints, frames
  size                 the frames' width x height
  restart              N of --restart, null without it
  best_path, both_ways whether toonmotion chose the paths over the whole clip, and between
                       the two ways (its lines only)
  working_side         toonmotion's TrackSettings.working_side, null at full resolution (its lines
                       only)
  mean_px, median_px   error of the tracked joint centres against the true ones, over every
                       joint and frame after the first (with --restart, but those it restarted at)
  pck5                 fraction of joint-frames within 5 px
  lost                 fraction of joint-frames more than 20 px off
  fps                  frames tracked per second, all 16 joints (rendering not counted); toonmotion:
                       its fastest of --repeat runs
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
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

import cv2  # noqa: E402
import numpy as np  # noqa: E402

from toonmotion.capture.track_settings import TrackSettings  # noqa: E402
from toonmotion.testing.mocap_tracking import render_bvh_clip, track_from_truth, tracking_scores  # noqa: E402

cv2.setNumThreads(1)
DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
OPENCV = {"MIL": "TrackerMIL_create", "CSRT": "TrackerCSRT_create", "KCF": "TrackerKCF_create"}


def run_opencv(kind, images, truth, side, restart=None):
    """An OpenCV tracker's joint centres from the true ones, started again every ``restart``
    frames as toonmotion is (``track_from_truth``), and the seconds it took."""
    step = restart or len(images)
    out, seconds = np.empty_like(truth), 0.0
    for begin in range(0, len(images), step):
        stop = min(len(images), begin + step)
        out[begin:stop], more = _run_opencv(kind, images[begin:stop], truth[begin], side)
        seconds += more
    return out, seconds


def _run_opencv(kind, images, start_points, side):
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


def bench(path, trackers, frames=None, style="textured", twos=False, seed=0, best_path=True,
          both_ways=False, noise=None, repeat=1, size=(640, 480), full_resolution=False, restart=None):
    clip = render_bvh_clip(path, frames=frames, style=style, twos=twos, seed=seed, noise=noise, size=size)
    images = clip.images
    lines, ours = [], None
    for name in trackers:
        if name == "toonmotion":
            settings = TrackSettings(best_path=best_path, both_ways=both_ways)
            if full_resolution:
                settings = replace(settings, working_side=None)
            found, seconds = track_from_truth(clip, settings=settings, restart=restart)
            for _ in range(repeat - 1):
                again, more = track_from_truth(clip, settings=settings, restart=restart)
                if not np.array_equal(again, found, equal_nan=True):
                    raise SystemExit(f"{Path(path).stem}: toonmotion's runs disagree")
                seconds = min(seconds, more)
        else:
            found, seconds = run_opencv(name, images, clip.truth, clip.side, restart)
        line = {"clip": Path(path).stem, "style": style, "twos": twos, "noise": clip.noise, "seed": seed,
                "tracker": name, "size": f"{size[0]}x{size[1]}", "restart": restart,
                "joints": len(clip.skeleton), "frames": len(images),
                **tracking_scores(found, clip.truth, restart=restart),
                "fps": round((len(images) - 1) / max(seconds, 1e-9), 1)}
        if name == "toonmotion":
            ours, line["best_path"], line["both_ways"] = line["mean_px"], best_path, both_ways
            line["working_side"] = settings.working_side
        elif ours:
            line["ratio_mean_px"] = round(line["mean_px"] / ours, 2)
        lines.append(line)
    return lines


def _grey_levels(text):
    value = float(text)
    if not value >= 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of grey levels >= 0")
    return value


def _whole_number(least, what):
    """An argparse type: a whole number of ``what`` at least ``least``."""
    def parse(text):
        try:
            value = int(text)
        except ValueError:
            value = least - 1
        if value < least:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number of {what} >= {least}")
        return value
    return parse


def _size(text):
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        width = height = 0
    if width < 64 or height < 64:
        raise argparse.ArgumentTypeError(f"{text!r} is not a frame size WxH of at least 64x64 pixels")
    return width, height


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="*", type=Path)
    parser.add_argument("--frames", type=int, default=None, help="Use only the first N frames.")
    parser.add_argument("--trackers", default="toonmotion,MIL,CSRT,KCF")
    parser.add_argument("--style", nargs="+", choices=("textured", "flat"), default=["textured"],
                        help="how the figure is drawn, a set of lines each (default: textured)")
    parser.add_argument("--twos", action="store_true", help="hold each drawing two frames")
    parser.add_argument("--noise", type=_grey_levels, default=None, metavar="SIGMA",
                        help="Gaussian noise on every frame, grey levels (default: 1.5 on twos, else 0)")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the figure's textures or colours and the background (default 0)")
    ways = parser.add_mutually_exclusive_group()
    ways.add_argument("--frame-by-frame", action="store_true",
                      help="leave out toonmotion's choice of each joint's path over the whole clip")
    ways.add_argument("--both-ways", action="store_true",
                      help="toonmotion also tracks backwards and chooses between the two ways")
    parser.add_argument("--repeat", type=_whole_number(1, "runs"), default=3, metavar="N",
                        help="toonmotion's runs per clip; its fps is the fastest's (default 3)")
    parser.add_argument("--size", type=_size, default=(640, 480), metavar="WxH",
                        help="the frames' size in pixels (default 640x480)")
    parser.add_argument("--full-resolution", action="store_true",
                        help="toonmotion tracks frames larger than 1000 px at their own size, not halved")
    parser.add_argument("--restart", type=_whole_number(2, "frames"), default=None, metavar="N",
                        help="every tracker starts again from the true joints every N frames")
    args = parser.parse_args()
    clips = args.clips or sorted(DEFAULT_DIR.glob("*.bvh"))
    for clip in clips:
        for style in args.style:
            lines = bench(clip, args.trackers.split(","), frames=args.frames, style=style, twos=args.twos,
                          seed=args.seed, best_path=not args.frame_by_frame, both_ways=args.both_ways,
                          noise=args.noise, repeat=args.repeat, size=args.size,
                          full_resolution=args.full_resolution, restart=args.restart)
            for line in lines:
                print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
