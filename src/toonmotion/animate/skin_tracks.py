"""An animation as a skinned rig: node transforms per frame plus per-vertex offsets.

Stage one of the deformation (:mod:`toonmotion.deform.needles`) is exactly linear blend
skinning: each bone carries its vertices by one affine map, a rotation and a scale along the
bone (``sigma``, its posed over rest length) and across it (``rho``: ``1 / sigma`` with area
preservation, else 1). So game engines and 3D tools, which skin meshes, can reproduce it exactly.
Stage two's displacement, and fine-tuning edits, are the rest: per-vertex offsets that morph
targets (glTF) and deform timelines (Spine) carry.

The rig this module describes, which the exporters write:

- a **joint frame** per skeleton joint, at the joint, turned to the angle of the bone that ends
  there (a root: angle 0; a bone of zero rest length: its parent's angle). Each is a child of
  its parent joint's frame and has no scale, so turning a joint in an editor swings everything
  below it.
- a **bone frame** per bone, a child of its start joint's frame at the same point, turned along
  the bone and scaled ``(sigma, rho)`` in its own axes. Bones of zero rest length (their vertices
  only follow the start joint, as in stage one) stay at angle 0 with scale 1. Nothing hangs
  below a bone frame, so no child inherits its non-uniform scale.

Vertices are skinned to bone frames only: one bone each as in the thesis, or up to four with the
blended needles of ``skinning="weights"``. Angles are unwrapped over time, so consecutive frames
differ by less than half a turn and interpolating between them takes the short way.

Everything is in whatever 2D frame the positions are given in; the exporters convert image
pixels (y down) to their own y-up frames first. A reflection changes nothing here: the skin
reproduces stage one in any orthonormal frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.deform.skinning import heat_weights, skinned_needles
from toonmotion.errors import ExportError, SettingsError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.rig.character import Character
from toonmotion.rig.skeleton import MIN_BONE_LENGTH, Skeleton

# A skin matrix this close to singular (a bone squashed to a point) cannot carry offsets.
_SINGULAR = 1e-12


@dataclass(frozen=True, eq=False)
class SkinTracks:
    """A skeleton's poses as joint and bone frames (module docstring), at rest and per frame.

    Attributes
    ----------
    bones : (b, 2) int
        ``(start, end)`` joints of each bone (``skeleton.bones``).
    parents : (k,) int
        Each joint's parent, -1 for roots.
    rigid : (b,) bool
        Bones of zero rest length.
    joint_position : (T, k, 2) float
    joint_angle : (T, k) float
        Each joint frame's angle, radians, unwrapped over time.
    bone_angle : (T, b) float
        Each bone frame's angle, radians, unwrapped over time.
    bone_scale : (T, b, 2) float
        ``(sigma, rho)``: scale along the bone and across it.
    rest_position : (k, 2) float
    rest_joint_angle : (k,) float
    rest_bone_angle : (b,) float
        The same at rest (scale 1); each track is unwrapped from its rest angle.
    """

    bones: NDArray[np.int64]
    parents: NDArray[np.int64]
    rigid: NDArray[np.bool_]
    joint_position: NDArray[np.float64]
    joint_angle: NDArray[np.float64]
    bone_angle: NDArray[np.float64]
    bone_scale: NDArray[np.float64]
    rest_position: NDArray[np.float64]
    rest_joint_angle: NDArray[np.float64]
    rest_bone_angle: NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            object.__setattr__(self, name, frozen_array(value, dtype=np.asarray(value).dtype,
                                                        name=f"skin tracks' {name}"))

    @property
    def frame_count(self) -> int:
        return len(self.joint_position)

    def local_joints(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Each joint frame relative to its parent's: ``(translation (T+1, k, 2), angle (T+1, k))``,
        row 0 at rest, then every frame; roots are relative to the origin."""
        P = np.concatenate([self.rest_position[None], self.joint_position])
        g = np.concatenate([self.rest_joint_angle[None], self.joint_angle])
        parent = np.maximum(self.parents, 0)
        root = self.parents < 0
        offset = np.where(root[:, None], P, P - P[:, parent])
        turn = np.where(root, 0.0, g[:, parent])
        return _rotated(offset, -turn), np.where(root, g, g - turn)

    def local_bones(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Each bone frame relative to its start joint's frame: ``(angle (T+1, b), scale (T+1, b, 2))``,
        row 0 at rest (its translation is always zero)."""
        g = np.concatenate([self.rest_joint_angle[None], self.joint_angle])
        angle = np.concatenate([self.rest_bone_angle[None], self.bone_angle]) - g[:, self.bones[:, 0]]
        scale = np.concatenate([np.ones((1, len(self.bones), 2)), self.bone_scale])
        return angle, scale


def skin_tracks(skeleton: Skeleton, positions: NDArray[np.float64], *, preserve_area: bool = True,
                rest: NDArray[np.float64] | None = None) -> SkinTracks:
    """The joint and bone frames of ``skeleton`` posed at ``positions`` ``(T, k, 2)``.

    Parameters
    ----------
    skeleton : Skeleton
    positions : (T, k, 2) float
        Joint positions per frame.
    preserve_area : bool
        Bones thin as they stretch (``rho = 1 / sigma``), as the deformer's setting.
    rest : (k, 2) float, optional
        The rest positions in the same frame as ``positions`` (default ``skeleton.positions``).

    Raises
    ------
    ExportError
        A bone is squashed to a point in some frame: no skin matrix carries that.

    Examples
    --------
    >>> arm = Skeleton.from_joints([("shoulder", None, (0, 0)), ("hand", "shoulder", (10, 0))])
    >>> tracks = skin_tracks(arm, np.array([[[0, 0], [0, 20]]], float))
    >>> np.degrees(tracks.bone_angle).tolist(), tracks.bone_scale.tolist()
    ([[90.0]], [[[2.0, 0.5]]])
    """
    P = np.asarray(positions, dtype=float)
    R = np.asarray(skeleton.positions if rest is None else rest, dtype=float)
    bones = skeleton.bones
    rest_d = R[bones[:, 1]] - R[bones[:, 0]]
    rest_length = np.hypot(rest_d[:, 0], rest_d[:, 1])
    rigid = rest_length <= MIN_BONE_LENGTH
    both = np.concatenate([R[None], P])
    d = both[:, bones[:, 1]] - both[:, bones[:, 0]]
    length = np.hypot(d[..., 0], d[..., 1])
    squashed = (length <= MIN_BONE_LENGTH) & ~rigid
    if squashed.any():
        t, b = np.argwhere(squashed)[0]
        raise ExportError(f"bone {skeleton.bone_names[b]} is squashed to a point in frame {t - 1}; "
                          "a skinned rig cannot carry that (move its joints apart)")
    bone_angle = np.unwrap(np.where(rigid, 0.0, np.arctan2(d[..., 1], d[..., 0])), axis=0)
    joint_angle = np.zeros(both.shape[:2])
    ends = {int(c): i for i, c in enumerate(bones[:, 1])}
    for j, parent in enumerate(skeleton.parents):
        if parent >= 0:
            b = ends[j]
            joint_angle[:, j] = joint_angle[:, parent] if rigid[b] else bone_angle[:, b]
    sigma = np.where(rigid, 1.0, length / np.where(rigid, 1.0, rest_length))
    rho = 1.0 / sigma if preserve_area else np.ones_like(sigma)
    return SkinTracks(
        bones=bones, parents=np.asarray(skeleton.parents), rigid=rigid,
        joint_position=P, joint_angle=joint_angle[1:], bone_angle=bone_angle[1:],
        bone_scale=np.stack([sigma, rho], axis=-1)[1:], rest_position=R,
        rest_joint_angle=joint_angle[0], rest_bone_angle=bone_angle[0],
    )


def bone_matrices(tracks: SkinTracks, frame: int) -> NDArray[np.float64]:
    """Each bone's skin matrix at ``frame``: rest to posed, ``(b, 2, 3)`` affine ``[L | t]``.

    It is the bone frame's posed transform times the inverse of its rest transform.
    """
    A0 = tracks.rest_position[tracks.bones[:, 0]]
    A = tracks.joint_position[frame, tracks.bones[:, 0]]
    scaled = _rotations(tracks.bone_angle[frame]) * tracks.bone_scale[frame][:, None, :]  # R diag(s)
    linear = scaled @ np.swapaxes(_rotations(tracks.rest_bone_angle), 1, 2)
    return np.concatenate([linear, (A - np.einsum("bij,bj->bi", linear, A0))[:, :, None]], axis=2)


def skinned(V: NDArray[np.float64], bone: NDArray[np.int64], weight: NDArray[np.float64],
            matrices: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rest vertices ``V`` ``(n, 2)`` skinned: ``sum_k weight[:, k] * M[bone[:, k]] V``, ``(n, 2)``.

    ``bone`` and ``weight`` are ``(n, K)``, weights summing to 1; ``matrices`` from
    :func:`bone_matrices`.
    """
    M = _blend(bone, weight, matrices)
    return np.einsum("nij,nj->ni", M[:, :, :2], V) + M[:, :, 2]


def bind_offsets(V: NDArray[np.float64], bone: NDArray[np.int64], weight: NDArray[np.float64],
                 matrices: NDArray[np.float64], U: NDArray[np.float64]) -> NDArray[np.float64]:
    """The offsets in the rest frame that, added to ``V`` before skinning, land the vertices on
    ``U``: ``(sum_k w_k L_k)^-1 (U - skinned(V))``, ``(n, 2)``, with ``L_k`` the linear parts."""
    M = _blend(bone, weight, matrices)
    linear = M[:, :, :2]
    if (np.abs(np.linalg.det(linear)) < _SINGULAR).any():
        raise ExportError("a vertex's bones are squashed flat in this frame; its offset cannot be carried")
    residual = U - (np.einsum("nij,nj->ni", linear, V) + M[:, :, 2])
    return np.linalg.solve(linear, residual[:, :, None])[:, :, 0]


def _blend(bone, weight, matrices):
    """Each vertex's blended affine map, ``(n, 2, 3)``."""
    return np.einsum("nk,nkij->nij", weight, matrices[bone])


def _rotations(angle):
    """Rotation matrices ``(..., 2, 2)`` for angles ``(...)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def _rotated(points, angle):
    """``points`` ``(..., 2)`` turned by ``angle`` ``(...)``."""
    c, s = np.cos(angle), np.sin(angle)
    x, y = points[..., 0], points[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def vertex_bones(character: Character, *, skinning: str = "one-bone"
                 ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """The bones each vertex of ``character``'s mesh follows and their weights, ``(n, K)`` each:
    its own bone with weight 1 (``"one-bone"``, K = 1), or the deformer's blended needles
    (``"weights"``, K = :data:`~toonmotion.deform.skinning.KEEP`; unused slots have weight 0).
    """
    mesh, skeleton, binding = character.mesh, character.skeleton, character.binding
    if skinning == "one-bone":
        return np.asarray(binding.bone)[:, None], np.ones((len(mesh.V), 1))
    if skinning != "weights":
        raise SettingsError(f"skinning must be one-bone or weights, got {skinning!r}")
    skin = skinned_needles(mesh.V, skeleton, heat_weights(mesh, skeleton, binding.bone))
    return np.asarray(skin.bone), np.asarray(skin.weight)
