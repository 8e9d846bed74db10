"""A 3D proxy (section 3.4): what lifting a drawn animation gives, at its three levels of detail.

- **Points** (3.4.1): every marker's 3D trajectory, ``(T, N, 3)``; they project onto the drawn
  markers through the estimated camera.
- **Collision volumes** (3.4.2): per limb a tapered cylinder between its two markers' points,
  with a radius at each end, ``(T, K, 2)``; per marker a sphere as large as the largest cylinder
  end at it. Absent (``None``) when no drawn frames were given to measure the limbs' widths.
- **Skeleton** (3.4.3): joint positions ``(T, N, 3)`` whose limb lengths are constant (the
  prior's), and each limb's rotation per frame from its rest vector: ``skeleton[:, c] -
  skeleton[:, p] == rotate(limb_rotations[:, k], rest[k])`` for limb ``k = (p, c)``.

3D is right-handed, +Y up, metres; the ground is the plane Y = 0. The camera maps it to drawing
pixels (x right, y down).

Glossary: ``T`` frames, ``N`` markers, ``K`` limbs (a marker and its parent marker, listed
parents first as :attr:`Proxy.limbs`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from toonmotion.errors import ProxyError
from toonmotion.geometry.arrays import frame_rate, frozen_array
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.prior import Prior


@dataclass(frozen=True, eq=False)
class Proxy:
    """A lifted animation: camera, point trajectories, collision volumes and skeleton.

    Attributes
    ----------
    names : tuple of str
        Marker names.
    parents : (N,) int
        Each marker's parent marker, -1 for a root (the prior's hierarchy).
    fps : float
        The drawing's frame rate.
    camera : PerspectiveCamera
        The artist's camera, one per frame.
    points : (T, N, 3) float
        Single-point proxies, metres.
    radii : (T, K, 2) float or None
        Each limb's cylinder radius at its parent end and its child end, metres.
    skeleton : (T, N, 3) float
        Joint positions of the skeleton proxy, metres.
    rest : (K, 3) float
        Each limb's rest vector (parent to child), metres; its length is the limb's length.
    limb_rotations : (T, K, 4) float
        Each limb's rotation from its rest vector, unit quaternions ``(x, y, z, w)`` (SciPy's
        order).

    Construction copies the arrays (read-only) and raises :class:`ProxyError` unless the
    shapes agree, the values are finite, the radii are not negative and the quaternions are
    unit length.
    """

    names: tuple[str, ...]
    parents: NDArray[np.int64]
    fps: float
    camera: PerspectiveCamera
    points: NDArray[np.float64]
    radii: NDArray[np.float64] | None
    skeleton: NDArray[np.float64]
    rest: NDArray[np.float64]
    limb_rotations: NDArray[np.float64]

    def __post_init__(self) -> None:
        hierarchy = Prior(self.names, self.parents, np.zeros((1, len(tuple(self.names)), 3)), fps=1.0)
        N, K = len(hierarchy.names), len(hierarchy.limbs)
        T = self.camera.frame_count
        arrays: dict[str, NDArray[np.float64] | None] = {}
        for field, shape in (("points", (T, N, 3)), ("skeleton", (T, N, 3)), ("rest", (K, 3)),
                             ("limb_rotations", (T, K, 4)), ("radii", (T, K, 2))):
            value = getattr(self, field)
            if value is None and field == "radii":
                arrays[field] = None
                continue
            array = frozen_array(value, dtype=np.float64, name=f"the proxy's {field}", error=ProxyError,
                                 finite=True)
            if array.shape != shape:
                raise ProxyError(f"the proxy's {field} must have shape {shape} (frames, markers or limbs), "
                                 f"got {array.shape}")
            arrays[field] = array
        radii, quaternions = arrays["radii"], arrays["limb_rotations"]
        if radii is not None and np.any(radii < 0):
            raise ProxyError("the proxy's cylinder radii must not be negative")
        if K and quaternions is not None and not np.allclose(np.linalg.norm(quaternions, axis=-1), 1.0,
                                                             atol=1e-6):
            raise ProxyError("the proxy's limb rotations must be unit quaternions")
        object.__setattr__(self, "names", hierarchy.names)
        object.__setattr__(self, "parents", hierarchy.parents)
        object.__setattr__(self, "fps", frame_rate(self.fps, name="the proxy's fps", error=ProxyError))
        for field, value in arrays.items():
            object.__setattr__(self, field, value)

    @property
    def frame_count(self) -> int:
        """Number of frames, ``T``."""
        return len(self.points)

    @property
    def limbs(self) -> NDArray[np.int64]:
        """``(parent, child)`` marker indices per limb, ``(K, 2)``, parents first."""
        return Prior(self.names, self.parents, np.zeros((1, len(self.names), 3)), fps=1.0).limbs

    @property
    def cylinders(self) -> NDArray[np.float64]:
        """Each limb's cylinder ends (its markers' points), ``(T, K, 2, 3)`` metres."""
        L = self.limbs
        return np.stack([self.points[:, L[:, 0]], self.points[:, L[:, 1]]], axis=2)

    @property
    def sphere_radii(self) -> NDArray[np.float64] | None:
        """Each marker's joint sphere radius, ``(T, N)``: the largest cylinder end at it."""
        if self.radii is None:
            return None
        out = np.zeros((self.frame_count, len(self.names)))
        L = self.limbs
        for end in (0, 1):
            np.maximum.at(out.T, L[:, end], self.radii[:, :, end].T)
        return out

    @property
    def lengths(self) -> NDArray[np.float64]:
        """Each skeleton limb's length, ``(K,)`` metres."""
        return np.linalg.norm(self.rest, axis=-1)

    def limb_vectors(self) -> NDArray[np.float64]:
        """The skeleton's limb vectors from its rotations, ``(T, K, 3)``: rotation applied to rest."""
        T, K = self.limb_rotations.shape[:2]
        if K == 0:
            return np.zeros((T, 0, 3))
        turned = Rotation.from_quat(self.limb_rotations.reshape(-1, 4)).apply(np.tile(self.rest, (T, 1)))
        return turned.reshape(T, K, 3)
