"""The extended linear space of key-shapes (Bregler et al. 3.1.3, eq. 3).

Every pair of hand-picked key-shapes gets ``inbetweens`` as-rigid-as-possible in-betweens
(:mod:`~toonmotion.keyshape.arap`); PCA over the keys and the in-betweens gives a mean ``M`` and
the fewest eigen-shapes ``E_1..E_L`` that reconstruct every example within ``tolerance`` px
(the largest point distance). The extended key-shapes are ``S_l = M + E_l`` and
``S_{L+1} = M``: weights that sum to 1 give ``M + sum_l a_l E_l``.

PCA's eigenvectors have unit length, so their coefficients are in pixels and the paper's weight
bounds would mean nothing; here each ``E_l`` is scaled so that the examples' coefficients span
``[-1, 1]``, and capture bounds the coefficients of ``E_1..E_L`` (the mean's weight is what makes
the sum 1). This choice is ours (docs/keyshapes.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import KeyShapeError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.keyshape.arap import ArapPair, triangulate_shape
from toonmotion.keyshape.model import check_shapes

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class KeyShapeSpace:
    """Hand-picked key-shapes and the extended space built from them.

    Attributes
    ----------
    keys : (K, N, 2) float
        The hand-picked key-shapes, points in correspondence.
    closed : bool
        Whether the points run round a closed contour (its inside is triangulated).
    inbetweens : int
        In-betweens made per pair of keys.
    tolerance : float
        The largest reconstruction error allowed, px.
    mean : (N, 2) float
    eigen : (L, N, 2) float
        The eigen-shapes, scaled so the examples' coefficients span [-1, 1].
    error : float
        The largest reconstruction error of any example with these L eigen-shapes, px.
    """

    keys: FloatArray
    closed: bool
    inbetweens: int
    tolerance: float
    mean: FloatArray
    eigen: FloatArray
    error: float

    def __post_init__(self) -> None:
        keys = check_shapes(self.keys)
        object.__setattr__(self, "keys", frozen_array(keys, dtype=np.float64, name="key-shapes",
                                                      error=KeyShapeError))
        N = keys.shape[1]
        for name, shape in (("mean", (N, 2)), ("eigen", (None, N, 2))):
            object.__setattr__(self, name, frozen_array(getattr(self, name), dtype=np.float64, shape=shape,
                                                        name=f"the space's {name}", error=KeyShapeError,
                                                        coordinates=True))

    @property
    def extended(self) -> FloatArray:
        """The extended key-shapes ``[M + E_1, ..., M + E_L, M]``: (L + 1, N, 2)."""
        return np.concatenate([self.mean + self.eigen, self.mean[None]])

    def coefficients(self, shape: ArrayLike) -> FloatArray:
        """The weights of ``shape`` (N, 2) in the extended space (summing to 1), least squares."""
        E = self.eigen.reshape(len(self.eigen), -1)
        alpha = np.linalg.lstsq(E.T, (np.asarray(shape, dtype=float) - self.mean).ravel(), rcond=None)[0]
        return np.append(alpha, 1 - alpha.sum())


def build_space(keys: ArrayLike, *, closed: bool = True, inbetweens: int = 5, tolerance: float = 0.5
                ) -> KeyShapeSpace:
    """The extended space of ``keys`` (K, N, 2): in-betweens of every pair, then PCA.

    Examples
    --------
    >>> square = np.array([(0.0, 0), (10, 0), (10, 10), (0, 10)])
    >>> space = build_space([square, square * [2, 1]], inbetweens=3)
    >>> len(space.eigen), space.error <= 0.5
    (1, True)
    """
    K = check_shapes(keys)
    if not (isinstance(inbetweens, int) and 0 <= inbetweens <= 1000):
        raise KeyShapeError(f"in-betweens per pair must be a whole number from 0 to 1,000, "
                            f"got {inbetweens!r}")
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise KeyShapeError(f"the tolerance must be a positive number of pixels, got {tolerance!r}")
    triangles = triangulate_shape(K[0], closed=closed)
    examples = [*K]
    for i in range(len(K)):
        for j in range(i + 1, len(K)):
            examples.extend(ArapPair(K[i], K[j], closed=closed, triangles=triangles).inbetweens(inbetweens))
    X = np.stack(examples).reshape(len(examples), -1)
    mean = X.mean(axis=0)
    _, _, Vt = np.linalg.svd(X - mean, full_matrices=False)
    for L in range(len(Vt) + 1):
        basis = Vt[:L]
        coefficients = (X - mean) @ basis.T
        residual = (X - mean - coefficients @ basis).reshape(len(X), -1, 2)
        error = float(np.hypot(residual[..., 0], residual[..., 1]).max())
        if error <= tolerance:
            break
    scale = np.abs(coefficients).max(axis=0) if L else np.zeros(0)
    scale[scale == 0] = 1.0
    eigen = (basis * scale[:, None]).reshape(L, len(mean) // 2, 2)
    return KeyShapeSpace(keys=K, closed=closed, inbetweens=inbetweens, tolerance=tolerance,
                         mean=mean.reshape(-1, 2), eigen=eigen, error=error)
