"""3D proxies (Jain et al. 2012) on real motion capture; JSON lines.

    python benchmarks/proxy3d.py [--input BVH] [--prior BVH ...] [--view=AZ,EL] [--repeat N]

Line 1 times dynamic time warping (section 3.1.2) of 1,000 x 1,000 frames of real pose
descriptors (the input clip and the first prior, each seen from the view and resampled to 1,000
frames) within a 10% Sakoe-Chiba band: toonmotion's vectorised NumPy implementation against
dtaidistance's C one (the library toonmotion uses), best of ``--repeat`` runs each, on one core:

  dtw, frames, band, ours_ms, library_ms, ratio (ours over library), same_path

Then one line per prior: the input clip (default: the CMU walk in ../shared/data/mocap, its
T-pose frame left out, at 24 fps) is projected through the orthographic camera ``--view`` into
2D markers; the prior (default: every other CMU clip there) is aligned to them in time through
that camera, and the camera's angles are then searched from scratch on the aligned prior:

  input, prior, frames, prior_frames, align_ms, dtw_cost, view, found, error_deg (angle between
  the true and found view directions), facing_deg (how far the prior's figure faces from the
  input's, about the vertical: angles are in each clip's own world, so a prior facing elsewhere
  shifts the azimuth found by about this much), twin (the found view's planar twin and its
  cost), cost, view_ms
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toonmotion.capture.mocap import STANDARD_JOINTS  # noqa: E402
from toonmotion.errors import ToonmotionError  # noqa: E402
from toonmotion.io.bvh import load_bvh  # noqa: E402
from toonmotion.proxy3d.descriptor import descriptor_features  # noqa: E402
from toonmotion.proxy3d.markers import Markers  # noqa: E402
from toonmotion.proxy3d.orthographic import camera, find_view, view_direction  # noqa: E402
from toonmotion.proxy3d.prior import prior_from_bvh, resample_prior, sample_frames  # noqa: E402
from toonmotion.proxy3d.timewarp import align_prior, dtw, warp_prior  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
DEFAULT_INPUT = DEFAULT_DIR / "cmu_07_01_walk.bvh"
FPS = 24.0


def load_prior(path):
    clip = load_bvh(path)
    # CMU clips open with a T-pose frame the motion jumps away from.
    return prior_from_bvh(clip, STANDARD_JOINTS, start=1 if Path(path).name.startswith("cmu") else 0)


def best_ms(run, repeat):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - start)
    return min(times) * 1000, result


def dtw_line(source, prior, R, repeat, frames=1000, band=0.1):
    def features(p):
        seen = p.positions @ R.T
        return descriptor_features(sample_frames(seen, np.linspace(0, len(seen) - 1, frames)), p.limbs)

    A, B = features(source), features(prior)
    ours_ms, ours = best_ms(lambda: dtw(A, B, band=band, method="numpy"), repeat)
    library_ms, theirs = best_ms(lambda: dtw(A, B, band=band, method="dtaidistance"), repeat)
    return {"dtw": "numpy vs dtaidistance", "frames": frames, "band": band, "ours_ms": round(ours_ms, 2),
            "library_ms": round(library_ms, 2), "ratio": round(ours_ms / library_ms, 2),
            "same_path": bool(np.array_equal(ours.path, theirs.path))}


def facing(prior):
    """Mean horizontal facing, degrees about +Y from +Z: perpendicular to the hip line."""
    P = prior.positions
    left = (P[:, prior.names.index("left_hip")] - P[:, prior.names.index("right_hip")]).mean(axis=0)
    return float(np.degrees(np.arctan2(-left[2], left[0])))  # facing = left x up


def view_line(source, prior, view, input_name, prior_name):
    R = camera(*view)
    drawn = Markers(source.names, 5 * source.positions @ R.T + [320, 240], fps=source.fps)
    align_ms, found = best_ms(lambda: align_prior(drawn, prior, R), 1)
    warped = warp_prior(prior, found, drawn.fps)
    view_ms, fit = best_ms(lambda: find_view(drawn, warped), 1)
    error = np.degrees(np.arccos(np.clip(view_direction(*view) @ view_direction(fit.azimuth, fit.elevation),
                                         -1, 1)))
    return {"input": input_name, "prior": prior_name, "frames": drawn.frame_count,
            "prior_frames": prior.frame_count, "align_ms": round(align_ms, 1),
            "dtw_cost": round(found.cost, 3),
            "view": list(view), "found": [round(fit.azimuth, 2), round(fit.elevation, 2)],
            "error_deg": round(float(error), 2),
            "facing_deg": round((facing(prior) - facing(source) + 180) % 360 - 180, 2),
            "twin": [round(v, 3) for v in fit.twin],
            "cost": round(fit.cost, 4), "view_ms": round(view_ms, 1)}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--input", type=Path, default=DEFAULT_INPUT, help="The clip drawn (projected).")
    parser.add_argument("--prior", type=Path, nargs="*", default=None,
                        help="Prior clips (default: the other CMU clips beside the input).")
    parser.add_argument("--view", default="30,10", help="The true azimuth,elevation in degrees.")
    parser.add_argument("--repeat", type=int, default=5, help="DTW timing runs; the best counts.")
    args = parser.parse_args()
    view = tuple(float(v) for v in args.view.split(","))
    priors = args.prior or sorted(p for p in args.input.parent.glob("cmu_*.bvh") if p != args.input)
    source = resample_prior(load_prior(args.input), FPS)
    loaded = [(p, resample_prior(load_prior(p), FPS)) for p in priors]
    print(json.dumps(dtw_line(source, loaded[0][1] if loaded else source, camera(*view), args.repeat)),
          flush=True)
    for path, prior in loaded:
        try:
            line = view_line(source, prior, view, args.input.stem, path.stem)
        except ToonmotionError as error:  # a prior too short or too long to align, say
            line = {"input": args.input.stem, "prior": path.stem, "error": str(error)}
        print(json.dumps(line), flush=True)


if __name__ == "__main__":
    main()
