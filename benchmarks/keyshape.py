"""Key-shape contour capture: frames per second, and the weight QP against scipy's SLSQP; JSON lines.

    python benchmarks/keyshape.py [--keys K] [--points N] [--frames T] [--drawing DIR]

The key-shapes are a drawing's outer outline (default: the bundled character's; ``--drawing``
takes a folder with texture.png, mask.png and char_cfg.yaml) resampled by arc length to N
points, and K - 1 smooth variations of it (leaning, tapering and bulging by turns,
none of them an affine map of another).
T contours are made from random affines and weights (summing to 1, within [-0.5, 1.5]) with
1 px of noise, then captured (``keyshape/contour.py``).

Keys of the one line:
  keys, points, frames
  contour_fps     frames captured per second (affine and weights, to convergence)
  rounds_mean     constrained Gauss-Newton rounds per frame
  error_px        mean rms point distance between a contour and its model shape
  qp_per_s        the weight QP's solves per second (DAQP), on the weight problems of the
                  captured frames (the affine fixed at the one found)
  slsqp_per_s     scipy's SLSQP on the same problems (same constraints), and qp_speedup the ratio
  qp_max_gap      how much higher DAQP's objective ever was than SLSQP's (relative; 0 or below
                  means DAQP always found the lower)
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from toonmotion.keyshape.contour import capture_contours, solve_weights
from toonmotion.keyshape.model import warp


def outline(drawing: Path | None, points: int) -> np.ndarray:
    """The figure's outer outline, resampled by arc length to ``points`` points."""
    from toonmotion.geometry.segments import resample_by_arc_length

    if drawing is None:
        from toonmotion.samples import sample_rig

        character = sample_rig()
    else:
        from toonmotion.io.drawing_folder import rig_drawing_folder

        character = rig_drawing_folder(drawing)
    loop = character.mesh.V[character.mesh.boundary[0]]
    closed = np.vstack([loop, loop[:1]])
    return resample_by_arc_length(closed, np.arange(points) / points, fraction=True)


def variations(rest: np.ndarray, count: int, rng) -> np.ndarray:
    base = np.array([rest[:, 0].mean(), rest[:, 1].max()])
    height = np.ptp(rest[:, 1])
    out = [rest]
    for k in range(count):
        d = rest - base
        kind = k % 3
        if kind == 0:  # lean
            turn = rng.uniform(-0.5, 0.5) * (-d[:, 1]) / height
            out.append(base + np.stack([d[:, 0] * np.cos(turn) - d[:, 1] * np.sin(turn),
                                        d[:, 0] * np.sin(turn) + d[:, 1] * np.cos(turn)], axis=1))
        elif kind == 1:  # wider at the top than at the feet, or narrower: no affine makes it
            taper = 1 + rng.uniform(-0.3, 0.3) * (-d[:, 1]) / height
            out.append(base + d * np.stack([taper, np.ones(len(d))], axis=1))
        else:  # bulging in the middle, or pinched
            bulge = 1 + rng.uniform(-0.25, 0.25) * np.sin(np.pi * (-d[:, 1]) / height)
            out.append(base + d * np.stack([bulge, np.ones(len(d))], axis=1))
    return np.stack(out)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--keys", type=int, default=8)
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--drawing", type=Path, default=None,
                        help="a drawing folder (texture, mask, char_cfg)")
    args = parser.parse_args(argv)
    rng = np.random.default_rng(0)
    shapes = variations(outline(args.drawing, args.points), args.keys - 1, rng)
    contours, K = [], len(shapes)
    for _ in range(args.frames):
        w = rng.dirichlet(np.ones(K)) * 1.4 - 0.4 / K  # sums to 1, within [-0.5, 1.5]
        angle = rng.uniform(-0.4, 0.4)
        A = np.column_stack([rng.uniform(0.8, 1.2) * np.array([[np.cos(angle), -np.sin(angle)],
                                                                [np.sin(angle), np.cos(angle)]]),
                             rng.uniform(-80, 80, 2)])
        contours.append(warp(A, w, shapes) + rng.normal(0, 1 / np.sqrt(2), shapes.shape[1:]))
    started = time.perf_counter()
    found = capture_contours(contours, shapes)
    capture_s = time.perf_counter() - started
    low, high = np.full(K, -0.5), np.full(K, 1.5)
    started = time.perf_counter()
    ours = [solve_weights(A, c, shapes, low, high) for A, c in zip(found.affine, contours, strict=True)]
    qp_s = time.perf_counter() - started
    started = time.perf_counter()
    peer, gap = [], 0.0
    for A, c, (_, best) in zip(found.affine, contours, ours, strict=True):
        B = (shapes @ A[:, :2].T + A[:, 2]).reshape(K, -1).T
        v = c.ravel()
        scale = float(v @ v)  # the same problem, scaled so SLSQP's tolerances mean something
        result = minimize(lambda w, B=B, v=v, k=scale: float(((B @ w - v) ** 2).sum()) / k,
                          np.full(K, 1 / K), jac=lambda w, B=B, v=v, k=scale: 2 * B.T @ (B @ w - v) / k,
                          method="SLSQP", bounds=list(zip(low, high, strict=True)), options={"ftol": 1e-12},
                          constraints=[{"type": "eq", "fun": lambda w: w.sum() - 1,
                                        "jac": lambda w: np.ones(K)}])
        peer.append(result.fun * scale)
        gap = max(gap, (best - result.fun * scale) / max(result.fun * scale, 1e-12))
    slsqp_s = time.perf_counter() - started
    n = len(contours)
    print(json.dumps({"keys": K, "points": args.points, "frames": n,
                      "contour_fps": round(n / capture_s, 1),
                      "rounds_mean": round(float(found.rounds.mean()), 2),
                      "error_px": round(float(found.error.mean()), 3),
                      "qp_per_s": round(n / qp_s, 1), "slsqp_per_s": round(n / slsqp_s, 1),
                      "qp_speedup": round(slsqp_s / qp_s, 2), "qp_max_gap": float(f"{gap:.2e}")}), flush=True)


if __name__ == "__main__":
    sys.exit(main())
