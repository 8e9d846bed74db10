"""Motion-capture clips as arrays, and their forward kinematics: every joint in every frame.

A :class:`BvhClip` holds what a Biovision ``.bvh`` file says (``toonmotion.io.bvh.load_bvh``
reads one); :func:`forward_kinematics` turns it into world positions.

Glossary: ``J`` joints (End Sites included), ``T`` frames, ``C`` channels in all. World
coordinates are the file's own: its units (often inches or centimetres) and its up axis
(usually +Y, sometimes +Z), 3D and right-handed; nothing is converted.

Conventions, as BVH means them:

- Angles are degrees. A joint with channels ``Zrotation Yrotation Xrotation`` has the local
  rotation ``R = Rz @ Ry @ Rx`` acting on column vectors: intrinsic rotations composed in the
  order listed, which is ``Rotation.from_euler("ZYX", ...)`` (upper case: intrinsic). Any order
  of the axes is allowed, per joint.
- A joint sits at its OFFSET in its parent's frame. Position channels, on any joint, replace
  the matching OFFSET component, so a root's ``Xposition Yposition Zposition`` are where it is.
- A joint's world rotation is its parent's times its own; its position is the parent's plus
  the parent's world rotation applied to its (offset or position-channel) translation.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from toonmotion.errors import MotionError

AXES = "XYZ"


@dataclass(frozen=True, eq=False)
class BvhClip:
    """A BVH file's contents, as plain arrays.

    Attributes
    ----------
    names : tuple of str
        Joint names in file order, parents first; End Sites are named ``<parent>_end``.
    parents : (J,) int
        Index of each joint's parent, -1 for a root (a file may have several ROOTs).
    offsets : (J, 3) float
        Rest offset of each joint from its parent, in the parent's frame (a root's own OFFSET).
    channels : tuple of tuple of str
        Each joint's channel names in file order, e.g. ``("Zrotation", "Yrotation",
        "Xrotation")``; ``()`` for End Sites.
    motion : (T, C) float
        The MOTION section: one row per frame, the joints' channels in file order.
    frame_time : float
        Seconds per frame.
    """

    names: tuple
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple
    motion: np.ndarray
    frame_time: float

    def __post_init__(self) -> None:
        channels = tuple(tuple(c) for c in self.channels)
        arrays = {
            "parents": np.array(self.parents, dtype=np.int64),
            "offsets": np.array(self.offsets, dtype=float),
            "motion": np.array(self.motion, dtype=float),
        }
        J, width = len(self.names), sum(len(c) for c in channels)
        if arrays["parents"].shape != (J,) or arrays["offsets"].shape != (J, 3) or len(channels) != J:
            raise MotionError(f"a BVH clip of {J} joints needs {J} parents, offsets and channel lists")
        if np.any((arrays["parents"] < -1) | (arrays["parents"] >= np.arange(J))):
            raise MotionError("a BVH clip lists parents first: each parent index must be -1 or smaller")
        if arrays["motion"].ndim != 2 or arrays["motion"].shape[1] != width:
            raise MotionError(
                f"a BVH clip with {width} channels needs motion of shape (frames, {width}), "
                f"got {arrays['motion'].shape}"
            )
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "channels", channels)
        for field, array in arrays.items():
            array.setflags(write=False)
            object.__setattr__(self, field, array)
        object.__setattr__(self, "frame_time", float(self.frame_time))

    @property
    def fps(self) -> float:
        """Frames per second, ``1 / frame_time``."""
        return 1.0 / self.frame_time

    @property
    def frame_count(self) -> int:
        return len(self.motion)


def forward_kinematics(clip: BvhClip) -> NDArray[np.float64]:
    """World positions of every joint at every frame.

    Vectorised over frames: the local rotations of all joints that share a channel order come
    from one ``Rotation.from_euler`` call, then one pass over the joints, parents first, each
    step a batch of ``(T, 3, 3)`` matrix products.

    Parameters
    ----------
    clip : BvhClip

    Returns
    -------
    (T, J, 3) float
        Joint positions in the file's world frame and units.

    Examples
    --------
    A root turned 90 degrees about Z carries its child's offset from +X to +Y:

    >>> clip = BvhClip(names=("root", "root_end"), parents=np.array([-1, 0]),
    ...                offsets=np.array([[0.0, 0, 0], [1, 0, 0]]),
    ...                channels=(("Zrotation",), ()), motion=np.array([[90.0]]), frame_time=0.04)
    >>> forward_kinematics(clip).round(12)[0].tolist()
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    return _world(clip)[0]


def world_rotations(clip: BvhClip) -> NDArray[np.float64]:
    """Every joint's rotation from the world frame at every frame, ``(T, J, 3, 3)``.

    A joint's rotation turns its children's offsets into the world (identity for a joint with
    no rotation channel under none that turns).

    >>> clip = BvhClip(names=("root", "root_end"), parents=np.array([-1, 0]),
    ...                offsets=np.array([[0.0, 0, 0], [1, 0, 0]]),
    ...                channels=(("Zrotation",), ()), motion=np.array([[90.0]]), frame_time=0.04)
    >>> (world_rotations(clip)[0, 1] @ [1.0, 0, 0]).round(12).tolist()
    [0.0, 1.0, 0.0]
    """
    world_R = _world(clip)[1]
    out = np.tile(np.eye(3), (clip.frame_count, len(clip.names), 1, 1))
    for j, R in enumerate(world_R):
        if R is not None:
            out[:, j] = R
    return out


def _world(clip):
    """World positions ``(T, J, 3)`` and each joint's world rotation (None: not turned)."""
    local_R, local_t = _local_transforms(clip)
    world_R: list[NDArray[np.float64] | None] = []  # None: not turned from the world frame
    world_p = np.empty((clip.frame_count, len(clip.names), 3))
    for j, p in enumerate(clip.parents):  # parents come first
        R, t = local_R[j], local_t[j]
        if p >= 0:
            above = world_R[p]
            if above is not None:
                # (T,3,3) @ (3,) or (T,3,3) @ (T,3,1): the offset turned into the world frame.
                t = above @ t if t.ndim == 1 else (above @ t[..., None])[..., 0]
                R = above if R is None else above @ R
            t = world_p[:, p] + t
        world_R.append(R)
        world_p[:, j] = t
    return world_p, world_R


def _local_transforms(
    clip: BvhClip,
) -> tuple[list[NDArray[np.float64] | None], list[NDArray[np.float64]]]:
    """Each joint's local rotation ``(T, 3, 3)`` (None if it has no rotation channels) and
    translation: its ``(3,)`` offset, or ``(T, 3)`` where position channels replace parts of it."""
    R: list[NDArray[np.float64] | None] = [None] * len(clip.names)
    t: list[NDArray[np.float64]] = list(clip.offsets)
    starts = np.cumsum([0] + [len(c) for c in clip.channels])
    orders: dict[str, tuple[list[int], list[list[int]]]] = {}  # axis order -> joints, their columns
    for j, channels in enumerate(clip.channels):
        turns = [k for k, name in enumerate(channels) if name.endswith("rotation")]
        if turns:
            sequence = "".join(channels[k][0] for k in turns)  # upper case: intrinsic, as listed
            joints, columns = orders.setdefault(sequence, ([], []))
            joints.append(j)
            columns.append([int(starts[j]) + k for k in turns])
        moves = [k for k, name in enumerate(channels) if name.endswith("position")]
        if moves:
            t[j] = np.repeat(clip.offsets[j][None], clip.frame_count, axis=0)
            for k in moves:  # a position channel replaces that component of the offset
                t[j][:, AXES.index(channels[k][0])] = clip.motion[:, starts[j] + k]
    for sequence, (joints, columns) in orders.items():
        # All joints of one axis order at once; with (T, n, axes) angles, three dimensions, scipy
        # also takes its vectorised path rather than a loop over rotations.
        matrices = Rotation.from_euler(sequence, clip.motion[:, columns], degrees=True).as_matrix()
        for n, j in enumerate(joints):
            R[j] = np.ascontiguousarray(matrices[:, n])
    return R, t


def name_end_sites(names: list[str | None], parents: list[int]) -> list[str]:
    """Name each End Site (None) ``<parent>_end``, with a number added if the name is taken.

    The BVH reader names End Sites so, and the writers of BVH clips follow it.

    >>> name_end_sites(["hand", None, "hand_end", None], [-1, 0, 0, 0])
    ['hand', 'hand_end2', 'hand_end', 'hand_end3']
    """
    taken = {n for n in names if n is not None}
    out: list[str] = []
    for name, parent in zip(names, parents, strict=True):
        if name is None:
            base = f"{out[parent]}_end"
            name, n = base, 1
            while name in taken:
                n += 1
                name = f"{base}{n}"
            taken.add(name)
        out.append(name)
    return out
