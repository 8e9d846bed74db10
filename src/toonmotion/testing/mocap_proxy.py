"""3D proxies measured on real motion capture, where the true 3D motion is known (paper, section 5).

A BVH clip is the ground truth: its :data:`~toonmotion.capture.mocap.STANDARD_JOINTS` in metres,
seen by a still perspective camera (:func:`truth_camera`), optionally with every limb scaled per
frame like a drawing's squash and stretch (:func:`squashed`) and with Gaussian noise on the
markers. The markers are lifted with another clip as the prior and the proxy is scored against
the truth (:func:`lift_scores`): the single-point proxies' depth error (the paper's fig. 19) and
the skeleton proxy's distance from the truth, upper and lower body, beside the prior's (fig. 22).

``benchmarks/proxy3d.py`` runs this on every shared CMU clip; ``tests/proxy3d/test_proxy_benchmark.py``
on short pieces of them.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion.capture.mocap import STANDARD_JOINTS
from toonmotion.errors import AmbiguousViewError
from toonmotion.io.bvh import load_bvh
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.descriptor import upper_body
from toonmotion.proxy3d.lift import lift
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.orthographic import view_direction
from toonmotion.proxy3d.prior import Prior, prior_from_bvh, prior_in_metres, resample_prior

DISTANCE = 7.0  # metres from the camera to the truth's middle
FOCAL = 1000.0
IMAGE = (960, 720)


def load_prior(path: str | Path, fps: float | None = None) -> Prior:
    """A BVH clip's standard joints in metres (ground at Y = 0), resampled to ``fps`` if given.

    CMU's clips (named ``cmu_*``) open with a T-pose frame that the motion jumps away from; it is
    left out.
    """
    clip = load_bvh(path)
    start = 1 if Path(path).name.startswith("cmu") else 0
    prior = prior_in_metres(prior_from_bvh(clip, STANDARD_JOINTS, start=start))[0]
    return prior if fps is None else resample_prior(prior, fps)


def first_frames(prior: Prior, count: int) -> Prior:
    """The prior's first ``count`` frames."""
    turns = None if prior.turns is None else prior.turns[:count]
    return Prior(prior.names, prior.parents, prior.positions[:count], prior.fps, prior.joints, turns)


def truth_camera(truth: Prior, view: tuple[float, float]) -> PerspectiveCamera:
    """A still camera ``DISTANCE`` m from the clip's middle, looking at it from ``view`` (degrees)."""
    middle = truth.positions.reshape(-1, 3).mean(axis=0)
    centre = middle + DISTANCE * view_direction(*view)
    extrinsics = np.concatenate([np.radians([view[0], view[1], 0.0]), centre])
    return PerspectiveCamera(FOCAL, *IMAGE, np.tile(extrinsics, (truth.frame_count, 1)))


def squashed(truth: Prior, amount: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """The truth's positions with every limb scaled per frame by up to ``amount``, rebuilt from the roots."""
    P = truth.positions
    if amount == 0:
        return P
    out = P.copy()
    for p, c in truth.limbs:  # parents first, so each child follows its rebuilt parent
        phase, speed = rng.uniform(0, 2 * np.pi), rng.uniform(0.1, 0.4)
        scale = 1 + amount * np.sin(phase + speed * np.arange(len(P)))
        out[:, c] = out[:, p] + scale[:, None] * (P[:, c] - P[:, p])
    return out


def facing_difference(prior: Prior, truth: Prior) -> float:
    """How far the prior faces from the truth about the vertical, degrees in [-180, 180)."""
    return (_facing(prior) - _facing(truth) + 180) % 360 - 180


def turn_about_vertical(prior: Prior, truth: Prior) -> float:
    """Degrees about +Y (from +Z towards +X) that best turn the truth's poses onto the prior's.

    ``prior`` is time-aligned to the truth (the same frames and names); each pose is taken
    relative to its root, so only the figures' facing counts, not where they walk. Least squares
    on the horizontal components (closed form, as complex numbers ``z + i x``).
    """
    root = int(np.flatnonzero(truth.parents < 0)[0])
    a = prior.positions - prior.positions[:, root:root + 1]
    b = truth.positions - truth.positions[:, root:root + 1]
    wa, wb = a[..., 2] + 1j * a[..., 0], b[..., 2] + 1j * b[..., 0]
    return float(np.degrees(np.angle((np.conj(wb) * wa).sum())))


def view_error(found: tuple[float, float], true: tuple[float, float]) -> float:
    """Degrees between two views' directions (azimuth, elevation in degrees)."""
    cos = view_direction(*found) @ view_direction(*true)
    return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))


def lift_scores(truth: Prior, prior: Prior, view: tuple[float, float], noise: float = 0.0,
                squash: float = 0.0, seed: int = 0, search_view: bool = True) -> dict:
    """Lift the truth, seen from ``view``, with ``prior``; the proxy's errors against the truth.

    Returns a dict: ``frames``, ``view_found``, ``view_err_deg`` (degrees between the view found
    and the true one, turned by how the time-aligned prior faces against the truth:
    :func:`turn_about_vertical`), ``view_asked`` (the search found two views about equally good
    and asked: the view is then given, and ``view_found`` is the search's first choice),
    ``z_err_mean`` (mean |depth| error of the point
    proxies, metres, each in its own camera), ``reproj_px`` (largest distance of a point proxy's
    projection from its marker), ``camera_px``, ``skeleton_rms_upper``, ``prior_rms_upper``,
    ``skeleton_rms_lower``, ``prior_rms_lower`` (RMS distance, metres, of the skeleton proxy's and
    the time-aligned prior's joints from the truth's, in camera axes and relative to the root, so
    that the pose is compared and not its placement), ``limb_len_spread`` (largest change of a
    skeleton limb's length over the clip) and the stages' times in ms.
    """
    rng = np.random.default_rng(seed)
    true_camera = truth_camera(truth, view)
    drawn3d = squashed(truth, squash, rng)
    seen = true_camera.project(drawn3d) + rng.normal(0, noise, (truth.frame_count, len(truth.names), 2))
    markers = Markers(truth.names, seen, fps=truth.fps)
    asked = False
    try:
        proxy, report = lift(markers, prior, focal=FOCAL, size=IMAGE, units=1.0,
                             view=None if search_view else view)
    except AmbiguousViewError as question:  # as a user would, answer with the view drawn from
        asked, chosen = True, question.views[0]
        proxy, report = lift(markers, prior, focal=FOCAL, size=IMAGE, units=1.0, view=view)
        report = replace(report, azimuth=chosen[0], elevation=chosen[1])
    turn = turn_about_vertical(report.warped, truth)
    view_err = view_error((report.azimuth, report.elevation), (view[0] + turn, view[1]))
    z = np.abs(proxy.camera.depth(proxy.points) - true_camera.depth(drawn3d)).mean()
    root = int(np.flatnonzero(truth.parents < 0)[0])
    truth_pose = _from_root(true_camera.to_camera(truth.positions), root)
    skeleton_pose = _from_root(proxy.camera.to_camera(proxy.skeleton), root)
    prior_pose = _from_root(proxy.camera.to_camera(report.warped.positions), root)
    upper = upper_body(truth)
    L = proxy.limbs
    lengths = np.linalg.norm(proxy.skeleton[:, L[:, 1]] - proxy.skeleton[:, L[:, 0]], axis=-1)
    t = report.times_ms
    return {"frames": truth.frame_count,
            "view_found": [round(report.azimuth, 2), round(report.elevation, 2)],
            "view_err_deg": round(view_err, 2), "view_asked": asked,
            "z_err_mean": round(float(z), 4), "reproj_px": float(f"{report.reproj_px:.3g}"),
            "camera_px": round(report.camera_px, 2),
            "skeleton_rms_upper": _rms(skeleton_pose, truth_pose, upper),
            "prior_rms_upper": _rms(prior_pose, truth_pose, upper),
            "skeleton_rms_lower": _rms(skeleton_pose, truth_pose, ~upper),
            "prior_rms_lower": _rms(prior_pose, truth_pose, ~upper),
            "limb_len_spread": float(f"{np.ptp(lengths, axis=0).max():.3g}"),
            "align_ms": t["align"], "camera_ms": t["camera"], "points_ms": t["points"],
            "volumes_ms": t["volumes"], "skeleton_ms": t["skeleton"]}


def many_markers(path: str | Path, frames: int, markers: int) -> Prior:
    """A clip's first ``markers`` joints apart from their parents (End Sites last) at ``frames`` frames.

    For timing at scale: the clip resampled so that its whole duration fills ``frames`` frames.
    """
    clip = load_bvh(path)
    # CMU has joints at their parent's place; those add nothing to see.
    apart = [j for j in range(len(clip.names))
             if clip.parents[j] < 0 or np.linalg.norm(clip.offsets[j]) > 1e-9]
    apart.sort(key=lambda j: clip.names[j].endswith("_end"))
    names = [clip.names[j] for j in apart][:markers]
    start = 1 if Path(path).name.startswith("cmu") else 0
    own = prior_in_metres(prior_from_bvh(clip, names, start=start))[0]
    duration = (own.frame_count - 1) / own.fps
    return first_frames(resample_prior(own, (frames - 1) / duration), frames)


def _facing(prior):
    """Mean horizontal facing, degrees about +Y from +Z: perpendicular to the hip line."""
    P = prior.positions
    left = (P[:, prior.names.index("left_hip")] - P[:, prior.names.index("right_hip")]).mean(axis=0)
    return float(np.degrees(np.arctan2(-left[2], left[0])))  # facing = left x up


def _from_root(P, root):
    return P - P[:, root:root + 1]


def _rms(a, b, which):
    return round(float(np.sqrt(((a[:, which] - b[:, which]) ** 2).sum(-1).mean())), 4)
