"""The skeleton proxy as a joint hierarchy with a joint per limb, and as a BVH clip.

A proxy's limbs turn independently: a marker with three child limbs (a pelvis with a spine and
two legs) has three rotations, which no single BVH joint at that marker can carry. So the tree
has **a joint per limb**:

- every root marker ``r`` is a root joint named ``r``, at the marker, not turned;
- every limb ``k = (p, c)`` is a joint named after its child marker ``c``, placed at marker
  ``p`` and turned by the limb's rotation, so that it carries the bone from ``p`` to ``c``. Its
  parent is the joint of the limb ending at ``p`` (or ``p``'s root joint), and its OFFSET is that
  parent limb's rest vector (zero under a root joint): the parent's rotation turns it from ``q``
  to ``p``;
- a limb whose child marker has no limbs of its own ends in an End Site at OFFSET ``rest[k]``,
  at marker ``c``, named ``<c>_end`` (with a number after it if that name is taken, as
  :func:`toonmotion.io.bvh.load_bvh` names End Sites).

A joint's local rotation is ``inverse(G_parent) * G_k``, with ``G`` the limbs' rotations
(:attr:`Proxy.limb_rotations <toonmotion.proxy3d.proxy.Proxy.limb_rotations>`, global, from the rest
vectors) and ``G_parent`` the identity under a root. Joints are listed depth first, parents
before children, as a BVH file lists them.

The BVH clip (:func:`skeleton_clip`) gives each root joint the channels ``Xposition Yposition
Zposition Zrotation Xrotation Yrotation`` (the rotations all zero) and each limb joint
``Zrotation Xrotation Yrotation``, intrinsic Euler angles in degrees. Units are the proxy's:
metres, right-handed, +Y up. Its forward kinematics put the joint where each marker sits
(:attr:`LimbTree.markers`) on ``proxy.skeleton``; the Euler angles of a rotation in gimbal lock
are still angles of that rotation, so the positions hold there too.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from toonmotion.capture.bvh_kinematics import BvhClip, name_end_sites
from toonmotion.geometry.arrays import frozen_array
from toonmotion.proxy3d.proxy import Proxy

ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
LIMB_CHANNELS = ("Zrotation", "Xrotation", "Yrotation")
# Upper case: intrinsic rotations in the order of LIMB_CHANNELS, as the BVH reader composes them.
EULER_ORDER: Final = "ZXY"


@dataclass(frozen=True, eq=False)
class LimbTree:
    """A proxy's skeleton as a joint hierarchy with a joint per limb (module docstring).

    Attributes
    ----------
    names : tuple of str
        Joint names, ``J`` of them: root markers, limbs' child markers, End Sites ``<c>_end``.
    parents : (J,) int
        Each joint's parent joint, -1 for a root; parents come first (depth-first order).
    offsets : (J, 3) float
        Each joint's offset from its parent in the parent's frame, metres: the parent limb's
        rest vector, zero under a root and for the roots.
    limbs : (J,) int
        The limb whose rotation each joint carries, -1 for roots and End Sites.
    markers : (N,) int
        The joint that sits at each marker: a root joint, a joint of one of the limbs starting
        at the marker, or the End Site ending at it.
    """

    names: tuple[str, ...]
    parents: NDArray[np.int64]
    offsets: NDArray[np.float64]
    limbs: NDArray[np.int64]
    markers: NDArray[np.int64]

    def __post_init__(self) -> None:
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "parents", frozen_array(self.parents, dtype=np.int64))
        object.__setattr__(self, "offsets", frozen_array(self.offsets, dtype=np.float64))
        object.__setattr__(self, "limbs", frozen_array(self.limbs, dtype=np.int64))
        object.__setattr__(self, "markers", frozen_array(self.markers, dtype=np.int64))

    @property
    def roots(self) -> NDArray[np.int64]:
        """The root joints' indices."""
        return np.flatnonzero(self.parents < 0)

    def local_rotations(self, limb_rotations: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each joint's rotation relative to its parent joint, ``(T, J, 4)`` quaternions ``(x, y, z, w)``.

        ``limb_rotations`` are the limbs' global rotations ``(T, K, 4)``; roots and End Sites get
        the identity.
        """
        G = np.asarray(limb_rotations, dtype=float)
        T = G.shape[0]
        out = np.zeros((T, len(self.names), 4))
        out[..., 3] = 1.0
        joints = np.flatnonzero(self.limbs >= 0)
        if len(joints) == 0:
            return out
        own = Rotation.from_quat(G[:, self.limbs[joints]].reshape(-1, 4))
        above = self.limbs[self.parents[joints]]  # the parent limb, -1 under a root joint
        parent_q = np.zeros((T, len(joints), 4))
        parent_q[..., 3] = 1.0
        parent_q[:, above >= 0] = G[:, above[above >= 0]]
        local = Rotation.from_quat(parent_q.reshape(-1, 4)).inv() * own
        out[:, joints] = local.as_quat().reshape(T, len(joints), 4)
        return out


def limb_tree(proxy: Proxy) -> LimbTree:
    """The joint-per-limb hierarchy of ``proxy``'s skeleton (module docstring).

    Examples
    --------
    A pelvis with a spine and two legs, one of them with a knee:

    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> names = ("pelvis", "spine", "left_knee", "right_foot", "left_foot")
    >>> rest = [[0, 0.5, 0], [0.1, -0.4, 0], [-0.1, -0.8, 0], [0, -0.4, 0]]
    >>> X = [[[0, 1, 0], [0, 1.5, 0], [0.1, 0.6, 0], [-0.1, 0.2, 0], [0.1, 0.2, 0]]]
    >>> proxy = Proxy(names, [-1, 0, 0, 0, 2], 12, PerspectiveCamera(500.0, 64, 64, [[0, 0, 0, 0, 1, 5]]),
    ...               points=X, radii=None, skeleton=X, rest=rest, limb_rotations=[[[0, 0, 0, 1]] * 4])
    >>> tree = limb_tree(proxy)
    >>> list(zip(tree.names, tree.parents.tolist(), tree.limbs.tolist()))  # doctest: +NORMALIZE_WHITESPACE
    [('pelvis', -1, -1), ('spine', 0, 0), ('spine_end', 1, -1), ('left_knee', 0, 1),
     ('left_foot', 3, 3), ('left_foot_end', 4, -1), ('right_foot', 0, 2), ('right_foot_end', 6, -1)]
    >>> [tree.names[j] for j in tree.markers]  # the joint sitting at each marker
    ['pelvis', 'spine_end', 'left_foot', 'right_foot_end', 'left_foot_end']
    """
    L = proxy.limbs
    N = len(proxy.names)
    starting: list[list[int]] = [[] for _ in range(N)]  # limbs starting at each marker, in limb order
    for k, (p, _) in enumerate(L):
        starting[p].append(k)
    names: list[str | None] = []
    parents: list[int] = []
    offsets: list[NDArray[np.float64]] = []
    limbs: list[int] = []
    markers = np.full(N, -1, dtype=np.int64)

    def add(name: str | None, parent: int, offset: NDArray[np.float64], limb: int) -> int:
        names.append(name)
        parents.append(parent)
        offsets.append(offset)
        limbs.append(limb)
        return len(names) - 1

    zero = np.zeros(3)
    for r in np.flatnonzero(proxy.parents < 0):
        markers[r] = add(proxy.names[r], -1, zero, -1)
        # Depth first without recursion (a chain may be long): (limb, parent joint, offset).
        stack = [(k, int(markers[r]), zero) for k in reversed(starting[r])]
        while stack:
            k, parent, offset = stack.pop()
            c = int(L[k, 1])
            j = add(proxy.names[c], parent, offset, k)
            if starting[c]:
                stack.extend((k2, j, proxy.rest[k]) for k2 in reversed(starting[c]))
                if markers[c] < 0:
                    markers[c] = j + 1  # the first limb starting at c comes next, at c
            else:
                markers[c] = add(None, j, proxy.rest[k], -1)
    return LimbTree(tuple(name_end_sites(names, parents)), np.array(parents),
                    np.array(offsets).reshape(-1, 3), np.array(limbs), markers)


def skeleton_clip(proxy: Proxy) -> BvhClip:
    """``proxy``'s skeleton as a BVH clip: a joint per limb, metres, ``1 / fps`` seconds a frame.

    Forward kinematics of the clip (:func:`~toonmotion.capture.bvh_kinematics.forward_kinematics`)
    put joint ``limb_tree(proxy).markers[n]`` on ``proxy.skeleton[:, n]`` for every marker ``n``.
    Channels and naming: the module docstring.

    Examples
    --------
    An arm turned 90 degrees about Z at its shoulder:

    >>> from toonmotion.capture.bvh_kinematics import forward_kinematics
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> turn = Rotation.from_euler("z", 90, degrees=True).as_quat()
    >>> X = [[[0, 1, 0], [0, 1.3, 0], [-0.25, 1.3, 0]]]
    >>> proxy = Proxy(("shoulder", "elbow", "hand"), [-1, 0, 1], 24,
    ...               PerspectiveCamera(500.0, 64, 64, [[0, 0, 0, 0, 1, 5]]), points=X, radii=None,
    ...               skeleton=X, rest=[[0, 0.3, 0], [0, 0.25, 0]], limb_rotations=[[[0, 0, 0, 1], turn]])
    >>> clip = skeleton_clip(proxy)
    >>> clip.names, clip.channels[1], (clip.motion.round(9) + 0.0).tolist()
    (('shoulder', 'elbow', 'hand', 'hand_end'), ('Zrotation', 'Xrotation', 'Yrotation'), \
[[0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 90.0, 0.0, 0.0]])
    >>> forward_kinematics(clip)[0, limb_tree(proxy).markers].round(12).tolist()
    [[0.0, 1.0, 0.0], [0.0, 1.3, 0.0], [-0.25, 1.3, 0.0]]
    """
    tree = limb_tree(proxy)
    T = proxy.frame_count
    local = tree.local_rotations(proxy.limb_rotations)
    channels: list[tuple[str, ...]] = []
    columns: list[NDArray[np.float64]] = []
    for j, parent in enumerate(tree.parents):
        if parent < 0:
            marker = int(np.flatnonzero(tree.markers == j)[0])
            channels.append(ROOT_CHANNELS)
            columns += [proxy.skeleton[:, marker], np.zeros((T, 3))]
        elif tree.limbs[j] >= 0:
            channels.append(LIMB_CHANNELS)
            columns.append(_euler_degrees(local[:, j]))
        else:
            channels.append(())
    motion = np.concatenate(columns, axis=1) if columns else np.zeros((T, 0))
    return BvhClip(names=tree.names, parents=tree.parents, offsets=tree.offsets, channels=tuple(channels),
                   motion=motion, frame_time=1.0 / proxy.fps)


def _euler_degrees(quaternions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Intrinsic ``EULER_ORDER`` angles in degrees ``(T, 3)`` of quaternions ``(T, 4)``."""
    with warnings.catch_warnings():
        # In gimbal lock scipy sets the third angle to zero and still returns angles of the same
        # rotation: the joint's positions do not change.
        warnings.filterwarnings("ignore", message="Gimbal lock detected", category=UserWarning)
        return Rotation.from_quat(quaternions).as_euler(EULER_ORDER, degrees=True)
