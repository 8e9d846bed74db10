"""Single-point proxies (section 3.4.1, eq. 3-6, Appendix eq. 27-32): 3D marker trajectories.

Each marker's 3D position must project exactly onto its drawn marker (eq. 3: the point of this
level is that a balloon tied to a drawn wrist stays on it) and take its depth from the motion
prior (eq. 4), smoothly over time (eq. 5).

The Appendix linearises eq. 3 by the cross product ``x~ x M X = 0`` (eq. 28-29), whose solutions
are the points of the ray from the camera's centre through the drawn marker, and weighs it
against the other terms in one least-squares system. We satisfy it exactly instead: every
point is written on its ray, ``X_ij = c_i + d_ij r_ij`` (:meth:`PerspectiveCamera.rays`, ``r``
scaled to unit depth, so ``d_ij`` *is* the depth ``m_3^T X``), which is the weighted system's
limit as the weight of eq. 29 grows, leaves one unknown per marker and frame instead of three,
and reprojects to rounding error. The other terms, on the depths ``d``:

- eq. 4, the prior's depth: ``w_m (d_ij - m_3^T X~_ij)``, metres;
- eq. 5, smoothness: ``w_r |(X_ij - X~_ij) - (X_(i+1)j - X~_(i+1)j)|`` -- the *departure from the
  prior* is smooth, metres. Eq. 5 as written, ``|X_ij - X_(i+1)j|``, penalises velocity: it
  would slow every marker and bias the depth of a prior that is exactly right; ours is zero at
  a right prior (so the ground truth as the prior gives the ground truth back) and still damps
  a drawing's jitter in depth.

Stacked over all frames and markers (eq. 31-32) these are one sparse linear least-squares
problem, ``T N`` unknowns; its normal matrix (tridiagonal per marker) is factorised once
(SuperLU) and solved.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from toonmotion.errors import ProxyError
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.prior import Prior


def point_proxies(
    camera: PerspectiveCamera,
    markers: Markers,
    prior: Prior,
    *,
    prior_weight: float = 1.0,
    smooth_weight: float = 1.0,
) -> NDArray[np.float64]:
    """Every marker's 3D trajectory, on its drawn ray, with the prior's depth, smoothly.

    Parameters
    ----------
    camera : PerspectiveCamera
        One camera per drawn frame.
    markers : Markers
        The drawn markers, pixels (x right, y down).
    prior : Prior
        Time-aligned to the markers, metres, +Y up.
    prior_weight, smooth_weight : float
        ``w_m`` and ``w_r`` (module docstring); their ratio is what matters.

    Returns
    -------
    (T, N, 3) float
        Metres, right-handed, +Y up. Reprojects onto the markers to rounding error.

    Raises
    ------
    ProxyError
        Shapes disagree, a weight is not a number >= 0 (``prior_weight`` > 0), or the prior puts
        a marker behind the camera.

    Examples
    --------
    With the truth as the prior, the truth comes back:

    >>> cam = PerspectiveCamera(500.0, 640, 480, [[0, 0, 0, 0, 1, 5], [0.1, 0, 0, 0.5, 1, 5]])
    >>> truth = np.array([[[0.0, 1, 0], [0.3, 1.6, 0.2]], [[0.1, 1, 0.1], [0.2, 1.5, 0.4]]])
    >>> drawn = Markers(("a", "b"), cam.project(truth), fps=12)
    >>> found = point_proxies(cam, drawn, Prior(("a", "b"), [-1, 0], truth, fps=12))
    >>> float(np.abs(found - truth).max()) < 1e-12
    True
    """
    T, N = markers.frame_count, len(markers.names)
    if camera.frame_count != T or prior.frame_count != T or tuple(prior.names) != tuple(markers.names):
        raise ProxyError(f"the camera ({camera.frame_count} frames), the prior ({prior.frame_count}) and the "
                         f"markers ({T}) must be aligned: the same frames and names")
    if not (np.isfinite(prior_weight) and prior_weight > 0):
        raise ProxyError(f"the prior's depth weight must be a positive number, got {prior_weight!r}")
    if not (np.isfinite(smooth_weight) and smooth_weight >= 0):
        raise ProxyError(f"the smoothness weight must be a number >= 0, got {smooth_weight!r}")
    depth = camera.depth(prior.positions)  # (T, N): m_3^T X~
    if np.any(depth <= 0):
        t, n = np.argwhere(depth <= 0)[0]
        raise ProxyError(f"the prior's marker {markers.names[n]!r} is behind the camera on frame {t}; the "
                         "camera "
                         "cannot see it")
    rays = camera.rays(markers.positions)  # (T, N, 3), unit depth
    # Unknown (t, n) is column n * T + t: each marker's frames are consecutive (a banded matrix).
    col = np.arange(T * N).reshape(N, T).T
    rows = [prior_weight * sp.identity(T * N, format="csr")]
    rhs = [prior_weight * depth.T.ravel()]
    if smooth_weight > 0 and T > 1:
        # (d_t r_t - d_(t+1) r_(t+1)) + (c_t - X~_t) - (c_(t+1) - X~_(t+1)) = 0, three rows each.
        offset = camera.centres[:, None] - prior.positions  # (T, N, 3)
        pairs = (T - 1) * N
        r = np.arange(3 * pairs).reshape(T - 1, N, 3)
        a, b = rays[:-1], rays[1:]
        data = np.concatenate([a.ravel(), -b.ravel()])
        cols = np.concatenate([np.repeat(col[:-1], 3, axis=1).ravel(), np.repeat(col[1:], 3, axis=1).ravel()])
        rows.append(smooth_weight * sp.csr_matrix((data, (np.tile(r.ravel(), 2), cols)), shape=(3 * pairs,
                                                                                                T * N)))
        rhs.append(-smooth_weight * (offset[:-1] - offset[1:]).ravel())
    A = sp.vstack(rows, format="csr")
    b = np.concatenate(rhs)
    solve = splu((A.T @ A).tocsc())  # factorised once
    d = solve.solve(A.T @ b).reshape(N, T).T
    return camera.centres[:, None] + d[..., None] * rays
