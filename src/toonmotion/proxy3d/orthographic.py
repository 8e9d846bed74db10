"""The orthographic camera approximation (section 3.1.3), and a search for it.

The paper's user turns the prior's pose until its orthographic projection looks like the
drawing; the two angles give ``R`` (2x3), the first approximation of the artist's camera. Roll
is zero. Conventions (world right-handed, +Y up, as :class:`~toonmotion.proxy3d.prior.Prior`):

- ``azimuth`` (degrees) turns the camera about +Y, from +Z towards +X: at 0 the camera is on
  the +Z side looking towards -Z (a character facing +Z, as CMU and Mixamo T-poses do, is seen
  from the front), at 90 on the +X side, at 180 behind.
- ``elevation`` (degrees) raises the camera above the horizontal plane, looking down; in
  ``[-90, 90]``.
- The view direction (from the character towards the camera) is
  ``f = (cos el sin az, sin el, cos el cos az)``; the image's x axis is the horizontal
  ``r = (cos az, 0, -sin az)`` and its y axis points down, ``-(f x r)``; ``R = [r; -(f x r)]``.
  So image points ``R X`` are ``(x, y)`` with y down, in the prior's units, like the drawing's
  pixels up to a scale and a translation.

Beyond the paper, :func:`find_view` searches the two angles that best match the projected,
time-aligned prior to the drawn markers: poses are compared by the directions of their limbs in
the image (so the drawing's size, position and proportions do not matter), over a coarse grid
then refined by Nelder-Mead.

Orthographic views have twins. A figure moving in one plane (normal ``n``) looks the same from
``f`` and from ``f' = 2 (f . n) n - f``: for a walk along +Z seen from the front-left and above,
``(azimuth, elevation) = (30, 10)``, the twin is the back-left view from below, ``(150, -10)``;
seen from the side, ``(90, e)`` and ``(90, -e)``. A real motion is not quite planar and the
markers are named, so the left/right shoulders and hips, which stick out of the plane, usually
tell the twins apart: the search keeps the lower cost, and reports the twin of
the chosen view with its cost as :attr:`ViewFit.twin` (:func:`plane_normal` gives ``n``), so
a caller can see how close the call was and take the other.

Limbs are weighted by how steady the prior holds them (:data:`STEADY`): the line of the hips or
the shoulders and the spine say more about the view than a swinging arm, whose swing in the
drawing may be wider or narrower than the prior's (a run for a walk) -- a difference the search
would otherwise explain by turning the view towards the swing's plane.

The search reports its own confidence: the best view of every *other* basin of the cost (a
local minimum more than :data:`SEPARATE` degrees away, the twin included) is refined too, and the
cheapest is :attr:`ViewFit.second`. When it explains the drawing about as well as the chosen
view (:attr:`ViewFit.ambiguous`: within :data:`AMBIGUOUS` times its cost), the drawing cannot
tell the two apart, and the caller should ask for the view rather than pick one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize

from toonmotion.errors import ProxyError
from toonmotion.geometry.arrays import finite_float
from toonmotion.proxy3d.descriptor import limb_vectors
from toonmotion.proxy3d.markers import Markers
from toonmotion.proxy3d.prior import Prior

# The search grid, degrees: azimuth over a full turn, elevation over the views artists draw.
AZIMUTHS = tuple(float(a) for a in range(-180, 180, 10))
ELEVATIONS = tuple(float(e) for e in range(-60, 61, 10))
# The coarse grid compares at most this many frames (evenly spread); the refinement uses all.
GRID_FRAMES = 120
# A limb's weight is 1 / (1 - steadiness + STEADY), its steadiness the length of its mean unit
# direction over the prior (1 for a limb that never turns, less the more it swings). Measured by
# benchmarks/view_search.py; see docs/proxy3d.md.
STEADY = 0.005
# Views further apart than this (degrees) are in different basins of the cost.
SEPARATE = 25.0
# A second basin within this factor of the best cost (or within AMBIGUOUS_FLOOR of it, for fits
# that are all but exact) explains the drawing about as well: the view is ambiguous.
AMBIGUOUS = 1.25
AMBIGUOUS_FLOOR = 1e-6
# Second basins refined, cheapest first on the grid.
RIVALS = 3


def camera(azimuth: float, elevation: float) -> NDArray[np.float64]:
    """The orthographic camera ``R`` (2x3) for an azimuth and elevation in degrees, roll zero.

    Rows are the image's x (right) and y (down) axes in the world (right-handed, +Y up); see the
    module docstring for the angles.

    Examples
    --------
    From the front, a point up (+Y) goes up the image (negative y); from the +X side, the
    world's +Z (the front of a character facing +Z) is on the image's left; from straight
    above, +Z is at the bottom:

    >>> (camera(0, 0).round(12) + 0.0).tolist()
    [[1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]
    >>> (camera(90, 0) @ [0.0, 0.0, 1.0]).round(12).tolist()
    [-1.0, 0.0]
    >>> (camera(0, 90) @ [0.0, 0.0, 1.0]).round(12).tolist()
    [0.0, 1.0]
    """
    az = np.radians(finite_float(azimuth, name="azimuth", error=ProxyError))
    el = np.radians(finite_float(elevation, name="elevation", error=ProxyError))
    if abs(el) > np.pi / 2 + 1e-12:
        raise ProxyError(f"elevation must be between -90 and 90 degrees, got {elevation!r}")
    return _cameras(np.array([az]), np.array([el]))[0]


def view_direction(azimuth: float, elevation: float) -> NDArray[np.float64]:
    """The unit vector from the character towards the camera, ``(3,)``, for angles in degrees.

    >>> view_direction(90, 0).round(12).tolist()
    [1.0, 0.0, 0.0]
    """
    az, el = np.radians(azimuth), np.radians(elevation)
    return np.array([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)])


@dataclass(frozen=True)
class ViewFit:
    """The orthographic view that best matches a drawing.

    Attributes
    ----------
    azimuth, elevation : float
        Degrees (:func:`camera`); azimuth in ``[-180, 180)``.
    cost : float
        Mean over limbs and frames of ``|d - p|^2`` between the drawn and projected limbs' unit
        directions (``2 - 2 cos`` of their angle), weighted by the drawn limbs' lengths: 0 for a
        perfect match, 4 for every limb reversed.
    R : (2, 3) float
        :func:`camera` of the angles.
    scale : float
        Drawing pixels per prior unit, and ``translation`` ``(T, 2)`` pixels per frame: the
        least-squares fit of ``scale * R X + translation`` to the markers (closed form).
    twin : tuple of float
        ``(azimuth, elevation, cost)`` of the chosen view's twin (module docstring): the view
        that would look the same if the prior moved in one plane. A cost close to
        :attr:`cost` means the drawing cannot tell the two apart.
    second : tuple of float or None
        ``(azimuth, elevation, cost)``: the best view outside the chosen one's basin (more than
        :data:`SEPARATE` degrees away; the twin when it is the cheapest), None when the cost
        has no other basin.
    """

    azimuth: float
    elevation: float
    cost: float
    R: NDArray[np.float64]
    scale: float
    translation: NDArray[np.float64]
    twin: tuple[float, float, float]
    second: tuple[float, float, float] | None = None

    @property
    def ambiguous(self) -> bool:
        """Whether :attr:`second` explains the drawing about as well (:data:`AMBIGUOUS`)."""
        return self.second is not None and self.second[2] <= AMBIGUOUS * self.cost + AMBIGUOUS_FLOOR

    @property
    def mean_angle(self) -> float:
        """:func:`limb_angle` of :attr:`cost`."""
        return limb_angle(self.cost)


def limb_angle(cost: float) -> float:
    """The angle, degrees, between drawn and projected limbs that a :attr:`ViewFit.cost` amounts
    to (``cost = 2 - 2 cos angle``).

    >>> round(limb_angle(2 - 2 * np.cos(np.radians(20))), 9)
    20.0
    """
    return float(np.degrees(np.arccos(np.clip(1 - cost / 2, -1.0, 1.0))))


def view_cost(markers: Markers, prior: Prior, azimuth: float, elevation: float) -> float:
    """How well the prior seen from these angles matches the drawing (:attr:`ViewFit.cost`).

    ``prior`` must be time-aligned to the markers (same frames, same names).
    """
    drawn, weight, V = _limb_data(markers, prior)
    return float(_costs(drawn, weight, V, np.radians([azimuth]), np.radians([elevation]))[0])


def find_view(
    markers: Markers,
    prior: Prior,
    *,
    azimuths: ArrayLike = AZIMUTHS,
    elevations: ArrayLike = ELEVATIONS,
) -> ViewFit:
    """Search the azimuth and elevation whose projection of the prior best matches the drawing.

    Every grid view is scored by :func:`view_cost` on up to :data:`GRID_FRAMES` frames; the best
    is refined over all frames by Nelder-Mead (to about 1e-4 degree). Its twin (module
    docstring) is scored too, and refined: should that find a lower cost, the two swap. The
    cheapest other basins of the grid are refined as well, for :attr:`ViewFit.second`.
    Scale and translation are then fitted in closed form.

    Parameters
    ----------
    markers : Markers
    prior : Prior
        Time-aligned to the markers (:func:`~toonmotion.proxy3d.timewarp.warp_prior`): the same
        frame count and names.
    azimuths, elevations : sequence of float
        The grid, degrees.

    Returns
    -------
    ViewFit

    Raises
    ------
    ProxyError
        The prior is not aligned to the markers, or the markers form no limb of some length.

    Examples
    --------
    A bent arm drawn as seen from the side (+X):

    >>> P = np.array([[[0.0, 1.5, 0.0], [0.0, 1.2, 0.3], [0.0, 1.5, 0.5]]])
    >>> prior = Prior(("shoulder", "elbow", "hand"), [-1, 0, 1], P, fps=12)
    >>> drawn = Markers(prior.names, 100 * P @ camera(90, 0).T + 200, fps=12)
    >>> fit = find_view(drawn, prior)
    >>> round(fit.azimuth, 3), round(fit.elevation, 3), round(fit.scale, 6)
    (90.0, 0.0, 100.0)
    """
    drawn, weight, V = _limb_data(markers, prior)
    az_grid = np.radians(np.asarray(azimuths, dtype=float))
    el_grid = np.radians(np.asarray(elevations, dtype=float))
    if az_grid.ndim != 1 or el_grid.ndim != 1 or not len(az_grid) or not len(el_grid):
        raise ProxyError("azimuths and elevations must each list at least one angle")
    A, E = np.meshgrid(az_grid, el_grid, indexing="ij")
    step = max(1, int(np.ceil(len(V) / GRID_FRAMES)))
    grid = _costs(drawn[::step], weight[::step], V[::step], A.ravel(), E.ravel()).reshape(A.shape)

    def refine(az0, el0):
        def cost(x):
            el = np.clip(x[1], -90.0, 90.0)
            return float(_costs(drawn, weight, V, np.radians([x[0]]), np.radians([el]))[0])

        found = minimize(cost, [az0, el0], method="Nelder-Mead",
                         options={"xatol": 1e-4, "fatol": 1e-14, "initial_simplex": [
                             [az0, el0], [az0 + 5.0, el0], [az0, el0 + 5.0]]})
        az = float((found.x[0] + 180.0) % 360.0 - 180.0)
        return az, float(np.clip(found.x[1], -90.0, 90.0)), float(found.fun)

    best_cell = np.unravel_index(int(np.argmin(grid)), grid.shape)
    az, el, cost = refine(np.degrees(A[best_cell]), np.degrees(E[best_cell]))
    twin_az, twin_el = twin_view(az, el, plane_normal(prior))
    twin = (twin_az, twin_el, view_cost(markers, prior, twin_az, twin_el))
    other = refine(twin_az, twin_el)
    if other[2] < cost and _apart((az, el), other) > 1.0:  # the grid missed the better valley
        (az, el, cost), twin, other = other, (az, el, cost), (az, el, cost)
    rivals = [other] + [refine(*start) for start in _basins(grid, A, E, (az, el))]
    rivals = [r for r in rivals if _apart((az, el), r) > SEPARATE]
    R = camera(az, el)
    scale, translation = fit_scale_translation(markers.positions, prior.positions @ R.T)
    return ViewFit(azimuth=az, elevation=el, cost=cost, R=R, scale=scale, translation=translation,
                   twin=twin, second=min(rivals, key=lambda r: r[2]) if rivals else None)


def plane_normal(prior: Prior) -> NDArray[np.float64]:
    """The unit normal of the plane the prior's motion stays closest to.

    Each pose is centred on its mean (the figure's travel removed), then each marker on its mean
    over the clip: what is left is how the limbs swing, and its direction of least variance is
    returned (the body's width, for a walk; its depth, for jumping jacks).

    >>> swing = np.array([[[0.0, 0, 0], [0, -1, 0.5]], [[0.0, 0, 0], [0, -1, -0.5]],
    ...                   [[0.0, 0, 0], [0.0, -0.9, 0]]])                   # a leg swinging in y-z
    >>> np.abs(plane_normal(Prior(("hip", "foot"), [-1, 0], swing, fps=12))).round(2).tolist()
    [1.0, 0.0, 0.0]
    """
    P = prior.positions - prior.positions.mean(axis=1, keepdims=True)
    flat = (P - P.mean(axis=0)).reshape(-1, 3)
    _, vectors = np.linalg.eigh(flat.T @ flat)
    return vectors[:, 0]


def twin_view(azimuth: float, elevation: float, normal: ArrayLike) -> tuple[float, float]:
    """The view that sees a figure in the plane of ``normal`` as ``(azimuth, elevation)`` does.

    ``f' = 2 (f . n) n - f`` for the view direction ``f`` (:func:`view_direction`), in degrees.

    >>> [round(v, 9) + 0.0 for v in twin_view(30, 10, [1.0, 0.0, 0.0])]
    [150.0, -10.0]
    """
    n = np.asarray(normal, dtype=float)
    n = n / np.linalg.norm(n)
    f = view_direction(azimuth, elevation)
    g = 2 * (f @ n) * n - f
    el = float(np.degrees(np.arcsin(np.clip(g[1], -1, 1))))
    az = float(np.degrees(np.arctan2(g[0], g[2])))
    return (az + 180.0) % 360.0 - 180.0, el


def fit_scale_translation(drawn: ArrayLike, projected: ArrayLike) -> tuple[float, NDArray[np.float64]]:
    """One scale and a translation per frame, least squares: ``drawn ~ scale * projected + t``.

    Closed form: with both centred per frame, ``scale = sum <p, x> / sum |p|^2``, and each
    frame's translation moves the projected centroid onto the drawn one.

    >>> s, t = fit_scale_translation(np.array([[[2.0, 1], [4, 1]]]), np.array([[[0.0, 0], [1, 0]]]))
    >>> s, t.tolist()
    (2.0, [[2.0, 1.0]])
    """
    X = np.asarray(drawn, dtype=float)
    P = np.asarray(projected, dtype=float)
    x0, p0 = X.mean(axis=1, keepdims=True), P.mean(axis=1, keepdims=True)
    spread = float(((P - p0) ** 2).sum())
    if spread <= 0:
        raise ProxyError("the projected prior has no extent: every marker projects to one point")
    scale = float(((P - p0) * (X - x0)).sum()) / spread
    return scale, (x0 - scale * p0)[:, 0]


# -- helpers ---------------------------------------------------------------------------------


def _cameras(az, el):
    """``(C, 2, 3)`` cameras for radians ``az``, ``el`` ``(C,)``."""
    ca, sa, ce, se = np.cos(az), np.sin(az), np.cos(el), np.sin(el)
    zero = np.zeros_like(az)
    right = np.stack([ca, zero, -sa], axis=-1)
    down = np.stack([se * sa, -ce, se * ca], axis=-1)  # -(f x r)
    return np.stack([right, down], axis=1)


def _apart(a, b):
    """Degrees between the views ``a`` and ``b`` (their first two values: azimuth, elevation)."""
    return float(np.degrees(np.arccos(np.clip(view_direction(*a[:2]) @ view_direction(*b[:2]), -1, 1))))


def _basins(grid, A, E, best):
    """Starting views (degrees) of the cheapest :data:`RIVALS` grid minima away from ``best``.

    A grid cell is a minimum when no neighbour (azimuth wraps round; elevation does not) costs
    less.
    """
    padded = np.pad(np.pad(grid, ((1, 1), (0, 0)), mode="wrap"), ((0, 0), (1, 1)), mode="edge")
    neighbours = np.stack([padded[1 + i:1 + i + grid.shape[0], 1 + j:1 + j + grid.shape[1]]
                           for i in (-1, 0, 1) for j in (-1, 0, 1) if (i, j) != (0, 0)])
    minima = np.argwhere(grid <= neighbours.min(axis=0))
    starts = [(float(np.degrees(A[i, j])), float(np.degrees(E[i, j])), float(grid[i, j])) for i, j in minima]
    starts = sorted((s for s in starts if _apart(best, s) > SEPARATE), key=lambda s: s[2])
    return [s[:2] for s in starts[:RIVALS]]


def _limb_data(markers, prior):
    if tuple(prior.names) != tuple(markers.names) or prior.frame_count != markers.frame_count:
        raise ProxyError(
            f"the prior ({prior.frame_count} frames) must be aligned to the markers ({markers.frame_count} "
            "frames, the same names in the same order) first: align_prior, then warp_prior"
        )
    limbs = prior.limbs
    drawn = limb_vectors(markers.positions, limbs)
    length = np.linalg.norm(drawn, axis=-1)
    mean = length.mean(axis=1, keepdims=True)
    if len(limbs) == 0 or not np.all(mean > 0):
        raise ProxyError("the drawn markers form no limb of some length on some frame; a view cannot be "
                         "fitted")
    V = limb_vectors(prior.positions, limbs)
    weight = length / mean * _steadiness_weights(V)
    unit = drawn / np.where(length > 0, length, 1.0)[..., None]
    return unit, weight, V


def _steadiness_weights(V):
    """Each limb's weight by how steadily the prior holds its direction (:data:`STEADY`), ``(K,)``,
    mean 1."""
    norm = np.linalg.norm(V, axis=-1, keepdims=True)
    unit = V / np.where(norm > 0, norm, 1.0)
    steadiness = np.linalg.norm(unit.mean(axis=0), axis=-1)
    weight = 1.0 / (1.0 - steadiness + STEADY)
    return weight / weight.mean()


def _costs(unit, weight, V, az, el):
    """Weighted mean ``|d - p|^2`` of unit limb directions for each camera, ``(C,)``."""
    R = _cameras(az, el)
    out = np.empty(len(R))
    for start in range(0, len(R), 64):  # bounded memory: (64, T, K, 2) at a time
        p = np.einsum("tkd,cjd->ctkj", V, R[start:start + 64])
        norm = np.linalg.norm(p, axis=-1, keepdims=True)
        p = p / np.where(norm > 0, norm, 1.0)
        out[start:start + 64] = (((unit - p) ** 2).sum(-1) * weight).sum(axis=(1, 2)) / weight.sum()
    return out
