"""Key-shape contour capture: frames per second, and the weight QP against scipy's SLSQP; JSON lines.

    python benchmarks/keyshape.py [--keys K] [--points N] [--frames T] [--drawing DIR]
                                  [--footage VIDEO|DIR --outlines KEYS.json [--key-frames ...]
                                   [--truth CONTOURS.json]]

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

Then one line per video sequence (``keyshape/video.py``): the generated ones
(``toonmotion.sample_cartoons``: the bouncing ball, affine only; the morphing character, affine
and 10 eigen-images; with noise and an occluding bar; the character at twice the size, a layer
of about 170x160 px tracked at full size, and at four times, shrunk by 2), or footage given
with ``--footage VIDEO|DIR --outlines KEYS.json [--key-frames 0,8,16] [--truth CONTOURS.json]``.

Keys of a video line:
  sequence, frames, keys, eigen
  shrunk_by       the whole factor the frames were shrunk by (a layer over 200 px across, as
                  ``capture_video`` does), and window, the template's window, w x h px
  video_ms        milliseconds per frame tracked (one core), the model built beforehand
  build_ms        building the image model (matte, in-betweens, eigen-images)
  iterations      mean Levenberg-Marquardt steps per frame
  point_err_px    mean distance of the captured outline's points from the true ones (when known)
  ecc_ms, ecc_point_err_px   the peer on affine-only sequences: OpenCV's ECC image alignment
                  (findTransformECC, affine, the first key frame's layer as template, each frame
                  started from the one before); ms_ratio = ecc_ms / video_ms
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
    parser.add_argument("--footage", type=Path, default=None, help="a video or a folder of frames")
    parser.add_argument("--outlines", type=Path, default=None,
                        help="with --footage: the layer's outline at each key frame (a contours file)")
    parser.add_argument("--key-frames", default=None, help="with --footage: e.g. 0,8,16 [default: 0]")
    parser.add_argument("--truth", type=Path, default=None,
                        help="with --footage: the true outline of every frame (a contours file)")
    args = parser.parse_args(argv)
    contour_line(args)
    for name, frames, outlines, key_frames, truth, largest in sequences(args):
        video_line(name, frames, outlines, key_frames, truth, largest)


def contour_line(args):
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


def sequences(args):
    """(name, frames, key outlines, key frames, true outlines or None, largest layer tracked at
    full size) for each video line."""
    from toonmotion.keyshape.video import LARGEST

    if args.footage is not None:
        from toonmotion.io.frames import load_frames
        from toonmotion.io.keyshape_json import load_contours

        frames, _ = load_frames(args.footage)
        outlines, _, _ = load_contours(args.outlines)
        keys = [0] if args.key_frames is None else [int(k) for k in args.key_frames.split(",")]
        truth = None if args.truth is None else load_contours(args.truth)[0]
        yield args.footage.name, frames, outlines, keys, truth, LARGEST
        return
    from toonmotion.sample_cartoons import bouncing_ball, morphing_character

    twice = morphing_character(frames=48, size=(480, 400))
    for name, cartoon, largest in [
            ("ball", bouncing_ball(frames=48), LARGEST),
            ("ball_noise_bar", bouncing_ball(frames=48, noise=4.0, occluder=True), LARGEST),
            ("character", morphing_character(frames=48), LARGEST),
            ("character_noise_bar", morphing_character(frames=48, noise=4.0, occluder=True), LARGEST),
            ("character_2x", twice, LARGEST),
            ("character_2x_full_size", twice, np.inf),  # the 10 ms goal's 200 x 200 layer, not shrunk
            ("character_4x", morphing_character(frames=48, size=(960, 800)), LARGEST)]:
        keys = list(cartoon.key_frames)
        yield name, cartoon.frames, cartoon.contours[keys], keys, cartoon.contours, largest


def video_line(name, frames, outlines, key_frames, truth, largest):
    from toonmotion.keyshape.image_model import build_image_model
    from toonmotion.keyshape.matte import fit_matte
    from toonmotion.keyshape.video import region_mask, shrunk, track_layer

    first = key_frames[0]
    full_frames, full_outlines = frames, outlines
    frames, outlines, factor = shrunk(frames, outlines, largest)  # as capture_video does
    started = time.perf_counter()
    matte = fit_matte(frames[first], region_mask(outlines[0], frames[first].shape[:2]))
    model = build_image_model(frames, key_frames, outlines, matte)
    build_s = time.perf_counter() - started
    started = time.perf_counter()
    found = track_layer(frames[first:], model, matte)
    video_s = time.perf_counter() - started
    count = len(found.shapes)
    shapes = found.shapes * factor + (factor - 1) / 2
    line = {"sequence": name, "frames": count, "keys": len(outlines), "eigen": len(model.eigen),
            "shrunk_by": factor, "window": "x".join(map(str, model.mean.shape[::-1])),
            "video_ms": round(1000 * video_s / count, 2), "build_ms": round(1000 * build_s),
            "iterations": round(float(found.iterations.mean()), 1)}
    if truth is not None:
        line["point_err_px"] = round(_point_error(shapes, truth[first:]), 3)
    if len(outlines) == 1:  # affine only: OpenCV's ECC alignment is the peer
        started = time.perf_counter()
        ecc = ecc_track(full_frames[first:], full_outlines[0])
        ecc_s = time.perf_counter() - started
        line["ecc_ms"] = round(1000 * ecc_s / count, 2)
        if truth is not None:
            line["ecc_point_err_px"] = round(_point_error(ecc, truth[first:]), 3)
        line["ms_ratio"] = round(ecc_s / video_s, 2)
    print(json.dumps(line), flush=True)


def ecc_track(frames, outline):
    """The outline (N, 2) moved through ``frames`` by OpenCV's ECC affine alignment of the first
    frame's layer (its outline's region and a band of 4 px), each frame from the one before."""
    import cv2

    from toonmotion.keyshape.video import region_mask

    grey = [cv2.cvtColor(np.ascontiguousarray(f), cv2.COLOR_RGB2GRAY).astype(np.float32) for f in frames]
    mask = cv2.dilate(region_mask(outline, grey[0].shape).astype(np.uint8), np.ones((9, 9), np.uint8))
    W = np.eye(2, 3, dtype=np.float32)
    shapes = []
    criteria = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-5)
    for image in grey:
        try:
            _, W = cv2.findTransformECC(grey[0], image, W, cv2.MOTION_AFFINE, criteria, mask, 5)
        except cv2.error:  # did not converge: keep the last warp
            pass
        shapes.append(outline @ W[:, :2].T.astype(float) + W[:, 2])
    return np.array(shapes)


def _point_error(shapes, truth):
    return float(np.hypot(*(np.asarray(shapes) - np.asarray(truth)).T).mean())


if __name__ == "__main__":
    sys.exit(main())
