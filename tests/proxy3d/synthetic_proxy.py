"""Synthetic 3D proxies for the file and export tests: random limb rotations on a given hierarchy.

The skeleton satisfies the proxy's invariant exactly as the limbs are placed (each child marker
at its parent's position plus the limb's rotated rest vector); the points are the skeleton with
noise; the camera stands a few metres away looking at the figure.
"""

import numpy as np
from scipy.spatial.transform import Rotation

from toonmotion.proxy3d.camera import PerspectiveCamera, rotations
from toonmotion.proxy3d.prior import Prior
from toonmotion.proxy3d.proxy import Proxy

# A pelvis with three children (spine and two hips), listed children before parents on purpose.
BRANCHING = {
    "head": "neck", "left_foot": "left_knee", "neck": "spine", "spine": "pelvis", "left_knee": "left_hip",
    "left_hip": "pelvis", "right_hip": "pelvis", "right_knee": "right_hip", "pelvis": None,
}
# The same figure with a hat tracked apart (a second tree) and a ball with no limbs (a third).
FOREST = {**BRANCHING, "hat": None, "hat_tip": "hat", "ball": None}


def synthetic_proxy(hierarchy=None, *, frames=6, seed=0, radii=True, gimbal=False):
    """A proxy over ``hierarchy`` (marker name -> parent name or None), random but exact.

    ``gimbal``: the first limb under a root is turned, on frame 0, to a rotation whose ZXY Euler
    angles are in gimbal lock (X = 90 degrees).
    """
    hierarchy = FOREST if hierarchy is None else hierarchy
    rng = np.random.default_rng(seed)
    names = tuple(hierarchy)
    parents = np.array([-1 if hierarchy[n] is None else names.index(hierarchy[n]) for n in names])
    limbs = Prior(names, parents, np.zeros((1, len(names), 3)), fps=1.0).limbs
    K, N, T = len(limbs), len(names), frames
    rest = rng.normal(size=(K, 3))
    rest *= rng.uniform(0.1, 0.5, size=(K, 1)) / np.linalg.norm(rest, axis=1, keepdims=True)
    q = Rotation.random(T * K, random_state=seed).as_quat().reshape(T, K, 4) if K else np.zeros((T, 0, 4))
    if gimbal and K:
        q[0, 0] = Rotation.from_euler("ZXY", [30, 90, 0], degrees=True).as_quat()
    skeleton = np.zeros((T, N, 3))
    roots = np.flatnonzero(parents < 0)
    skeleton[:, roots] = rng.normal(scale=0.3, size=(1, len(roots), 3)) + [0, 1, 0]
    skeleton[:, roots] += np.cumsum(rng.normal(scale=0.05, size=(T, len(roots), 3)), axis=0)
    for k, (p, c) in enumerate(limbs):
        skeleton[:, c] = skeleton[:, p] + Rotation.from_quat(q[:, k]).apply(rest[k])
    points = skeleton + rng.normal(scale=0.02, size=skeleton.shape)
    angles = np.stack([rng.uniform(-0.6, 0.6, T), rng.uniform(-0.3, 0.3, T), rng.uniform(-0.2, 0.2, T)],
                      axis=1)
    centres = points.mean(axis=1) - 6.0 * rotations(angles)[:, 2]  # 6 m back along the viewing direction
    camera = PerspectiveCamera(850.0, 640, 480, np.concatenate([angles, centres], axis=1))
    r = rng.uniform(0.02, 0.12, size=(T, K, 2)) if radii else None
    return Proxy(names, parents, 24.0, camera, points=points, radii=r, skeleton=skeleton, rest=rest,
                 limb_rotations=q)
