"""3D proxies (Jain et al. 2012) on real motion capture, after the paper's section 5; JSON lines.

    python benchmarks/proxy3d.py [--input BVH] [--prior BVH ...] [--view AZ,EL] [--noise PX]
                                 [--squash FRACTION] [--repeat N] [--no-scale]

Line 1 times dynamic time warping (section 3.1.2) of 1,000 x 1,000 frames of real pose
descriptors (the input clip and the first prior, each seen from the view and resampled to 1,000
frames) within a 10% Sakoe-Chiba band: toonmotion's vectorised NumPy implementation against
dtaidistance's C one (the library toonmotion uses), best of ``--repeat`` runs each, on one core.

Then one line per prior (default: the input itself, then every other CMU clip beside it; any BVH
clip works as input or prior). The input clip (default: the CMU walk in ../shared/data/mocap, its
T-pose frame left out, at 24 fps) is the ground truth: it is seen by a still perspective camera
(``--view``, 7 m from the walk's middle, focal 1,000 px, 960 x 720), optionally with Gaussian
noise on the markers (``--noise`` px) and every limb scaled per frame by up to ``--squash`` (a
drawing's squash and stretch, rebuilt from the root). It is lifted with the prior (its first
``2 x`` the input's duration at most; the view searched, the focal length given) and compared:

  input, prior, frames, prior_frames, noise_px, squash, view_found, facing_deg (how far the
  prior faces from the input about the vertical; the view found differs by about that),
  z_err_mean (mean |depth| error of the single-point proxies against the drawn truth, metres,
  each in its own camera: the paper's fig. 19), reproj_px (largest distance of a point proxy's
  projection from its marker), camera_px (what the camera fit leaves), skeleton_rms_upper,
  prior_rms_upper, skeleton_rms_lower, prior_rms_lower (RMS distance, metres, of the skeleton
  proxy's and the time-aligned prior's joints from the truth's, in camera coordinates: the
  paper's fig. 22), limb_len_spread (largest change of a skeleton limb's length over the clip),
  align_ms, camera_ms, points_ms, volumes_ms, skeleton_ms (the whole clip)

The last line times 1,000 frames x 24 markers (the input's first 24 joints apart from their
parents, End Sites if need be; resampled; itself as the prior; view given): points_ms (goal
<= 1,000) and skeleton_ms (goal <= 5,000), on one core.
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

from toonmotion.errors import ToonmotionError  # noqa: E402
from toonmotion.proxy3d.descriptor import descriptor_features  # noqa: E402
from toonmotion.proxy3d.lift import lift  # noqa: E402
from toonmotion.proxy3d.markers import Markers  # noqa: E402
from toonmotion.proxy3d.orthographic import camera  # noqa: E402
from toonmotion.proxy3d.prior import sample_frames  # noqa: E402
from toonmotion.proxy3d.timewarp import dtw  # noqa: E402
from toonmotion.testing.mocap_proxy import (  # noqa: E402
    FOCAL,
    IMAGE,
    facing_difference,
    first_frames,
    lift_scores,
    load_prior,
    many_markers,
    truth_camera,
)

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
DEFAULT_INPUT = DEFAULT_DIR / "cmu_07_01_walk.bvh"
FPS = 24.0


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


def lift_line(truth, prior, view, input_name, prior_name, noise, squash):
    longest = first_frames(prior, int(2 * truth.frame_count * prior.fps / truth.fps))
    scores = lift_scores(truth, longest, view, noise=noise, squash=squash)
    return {"input": input_name, "prior": prior_name, "frames": scores.pop("frames"),
            "prior_frames": longest.frame_count, "noise_px": noise, "squash": squash,
            "facing_deg": round(facing_difference(prior, truth), 2), **scores}


def scale_line(path, view, frames=1000, markers=24):
    """1,000 frames x 24 markers of the input's own joints, itself the prior, the view given."""
    truth = many_markers(path, frames, markers)
    drawn = Markers(truth.names, truth_camera(truth, view).project(truth.positions), fps=truth.fps)
    _, report = lift(drawn, truth, view=view, focal=FOCAL, size=IMAGE, units=1.0)
    t = report.times_ms
    return {"scale": "points and skeleton", "frames": truth.frame_count, "markers": len(truth.names),
            "points_ms": t["points"], "points_goal_ms": 1000, "skeleton_ms": t["skeleton"],
            "skeleton_goal_ms": 5000, "camera_ms": t["camera"], "align_ms": t["align"],
            "reproj_px": float(f"{report.reproj_px:.3g}")}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--input", type=Path, default=DEFAULT_INPUT, help="The clip drawn (projected).")
    parser.add_argument("--prior", type=Path, nargs="*", default=None,
                        help="Prior clips (default: the input, then the other CMU clips beside it).")
    parser.add_argument("--view", default="30,10", help="The true azimuth,elevation in degrees.")
    parser.add_argument("--noise", type=float, default=0.0, help="Gaussian noise on the markers, px.")
    parser.add_argument("--squash", type=float, default=0.0, help="Limb length change per frame, up to.")
    parser.add_argument("--repeat", type=int, default=5, help="DTW timing runs; the best counts.")
    parser.add_argument("--no-scale", action="store_true", help="Leave out the 1,000-frame timing line.")
    args = parser.parse_args()
    view = tuple(float(v) for v in args.view.split(","))
    others = sorted(p for p in args.input.parent.glob("cmu_*.bvh") if p != args.input)
    priors = args.prior or [args.input, *others]
    truth = load_prior(args.input, FPS)
    loaded = [(p, load_prior(p)) for p in priors]
    first = load_prior(loaded[0][0], FPS) if loaded else truth
    print(json.dumps(dtw_line(truth, first, camera(*view), args.repeat)), flush=True)
    for path, prior in loaded:
        try:
            line = lift_line(truth, prior, view, args.input.stem, path.stem, args.noise, args.squash)
        except ToonmotionError as error:  # a prior too short to align, say
            line = {"input": args.input.stem, "prior": path.stem, "error": str(error)}
        print(json.dumps(line), flush=True)
    if not args.no_scale:
        print(json.dumps(scale_line(args.input, view)), flush=True)


if __name__ == "__main__":
    main()
