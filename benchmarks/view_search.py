"""The orthographic view search (Jain et al. 2012, 3.1.3) on a generated test set; JSON lines.

    python benchmarks/view_search.py [BVH ...] [--frames N] [--noise PX] [--squash FRACTION]
                                     [--priors self|others|both] [--cases] [--steady X]

Each clip given (default: every clip in ../shared/data/mocap) is drawn: its first ``--frames``
frames at 24 fps, seen by a still perspective camera 7 m away from each of 24 views (azimuths
-165, -120, ..., 150 -- none on the search's 10-degree grid -- at elevations 0, 15 and 30),
with every limb squashed and stretched per frame by up to ``--squash`` and Gaussian noise of
``--noise`` px on the markers. The view is then searched as ``toonmotion lift`` searches it
(:func:`toonmotion.proxy3d.lift.search_view`) with a prior: the clip itself ("self"), and every
other clip long enough ("others": twice the drawing's duration at most is used).

The true view is the one drawn from, turned by how the prior faces against the drawn clip
(:func:`toonmotion.testing.mocap_proxy.turn_about_vertical`, on the prior aligned in time through
the view found): for the clip itself, the view drawn from.

Lines:
  one per case with --cases: input, prior, view, found, view_err_deg, cost, limb_angle_deg (the
  cost as the mean angle between drawn and projected limbs), second (the best view of another
  basin, its cost), asked (the two explain the drawing about equally: lift asks for --view), ms
  one per (input, prior): cases, within_10 (found within 10 degrees), asked, wrong_unasked (more
  than 10 degrees off and not asked: the failures a user would not be told about),
  view_err_median, view_err_max
  one per prior kind (self, others): the same, summed; within_10_share (goal: at least 0.9)
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

from toonmotion.errors import ToonmotionError  # noqa: E402
from toonmotion.proxy3d import orthographic  # noqa: E402
from toonmotion.proxy3d.lift import search_view  # noqa: E402
from toonmotion.proxy3d.markers import Markers  # noqa: E402
from toonmotion.proxy3d.orthographic import camera  # noqa: E402
from toonmotion.proxy3d.timewarp import align_prior, warp_prior  # noqa: E402
from toonmotion.testing.mocap_proxy import (  # noqa: E402
    first_frames,
    load_prior,
    squashed,
    truth_camera,
    turn_about_vertical,
    view_error,
)

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap"
FPS = 24.0
VIEWS = [(float(az), float(el)) for az in range(-165, 180, 45) for el in (0, 15, 30)]
TOLERANCE = 10.0


def case(truth, prior, view, noise, squash, rng):
    """One drawing of ``truth`` from ``view``, its view searched with ``prior``."""
    seen = truth_camera(truth, view).project(squashed(truth, squash, rng))
    seen = seen + rng.normal(0, noise, seen.shape)
    markers = Markers(truth.names, seen, fps=truth.fps)
    start = time.perf_counter()
    fit = search_view(markers, prior)
    ms = (time.perf_counter() - start) * 1000
    aligned = warp_prior(prior, align_prior(markers, prior, camera(fit.azimuth, fit.elevation)), truth.fps)
    true = (view[0] + turn_about_vertical(aligned, truth), view[1])
    return {"view": list(view), "found": [round(fit.azimuth, 2), round(fit.elevation, 2)],
            "view_err_deg": round(view_error((fit.azimuth, fit.elevation), true), 2),
            "cost": round(fit.cost, 4), "limb_angle_deg": round(fit.mean_angle, 1),
            "second": None if fit.second is None else [round(v, 4) for v in fit.second],
            "asked": fit.ambiguous, "ms": round(ms, 1)}


def summary(cases):
    errors = [c["view_err_deg"] for c in cases]
    return {"cases": len(cases),
            "within_10": sum(e <= TOLERANCE for e in errors),
            "asked": sum(c["asked"] for c in cases),
            "wrong_unasked": sum(c["view_err_deg"] > TOLERANCE and not c["asked"] for c in cases),
            "view_err_median": round(statistics.median(errors), 2) if errors else None,
            "view_err_max": round(max(errors), 2) if errors else None}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("clips", nargs="*", type=Path, help="BVH clips (default: the shared ones).")
    parser.add_argument("--frames", type=int, default=96, help="Frames drawn of each clip, at 24 fps.")
    parser.add_argument("--noise", type=float, default=1.0, help="Gaussian noise on the markers, px.")
    parser.add_argument("--squash", type=float, default=0.1, help="Limb length change per frame, up to.")
    parser.add_argument("--priors", choices=("self", "others", "both"), default="both")
    parser.add_argument("--cases", action="store_true", help="A line per case, not only the sums.")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--steady", type=float, default=None,
                        help="orthographic.STEADY for this run (1e9 weighs every limb alike, as before it).")
    args = parser.parse_args()
    if args.steady is not None:
        orthographic.STEADY = args.steady
    clips = args.clips or sorted(DEFAULT_DIR.glob("*.bvh"))
    if not clips:
        raise SystemExit(f"no clips found (looked in {DEFAULT_DIR})")
    rng = np.random.default_rng(args.seed)
    kinds = {"self": [], "others": []}
    for path in clips:
        whole = load_prior(path, FPS)
        truth = first_frames(whole, min(whole.frame_count, args.frames))
        for other in clips:
            kind = "self" if other == path else "others"
            if args.priors not in (kind, "both"):
                continue
            prior = load_prior(other)
            prior = first_frames(prior, int(2 * truth.frame_count * prior.fps / truth.fps))
            cases = []
            for view in VIEWS:
                try:
                    found = case(truth, prior, view, args.noise, args.squash, rng)
                except ToonmotionError as error:  # a prior too short to align, say
                    line = {"input": path.stem, "prior": other.stem, "error": str(error)}
                    print(json.dumps(line), flush=True)
                    break
                cases.append(found)
                if args.cases:
                    print(json.dumps({"input": path.stem, "prior": other.stem, **found}), flush=True)
            if cases:
                kinds[kind] += cases
                print(json.dumps({"input": path.stem, "prior": other.stem, "noise_px": args.noise,
                                  "squash": args.squash, **summary(cases)}), flush=True)
    for kind, cases in kinds.items():
        if cases:
            line = summary(cases)
            share = round(line["within_10"] / line["cases"], 3)
            print(json.dumps({"priors": kind, **line, "within_10_share": share, "goal": 0.9}), flush=True)


if __name__ == "__main__":
    main()
