"""Depth layers (thesis 3.5, 6.3b): which bone regions are drawn in front of which.

Every bone region has a depth, a whole number; higher is nearer the viewer. Clicking a vertex
sets the depth of its whole region. A triangle belongs to the layer of the deepest-in-front of
its vertices' bones, so the band of joint triangles between an arm and the body is drawn with
the arm. Within one layer triangles keep the mesh's order.

In a pose, regions that overlap are found and reported so the animator can order them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import SettingsError
from toonmotion.geometry.arrays import finite_float
from toonmotion.rig.binding import Binding
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.mesh import Mesh


@dataclass(frozen=True)
class Overlap:
    """Two bone regions that overlap in a pose.

    Attributes
    ----------
    bone_a, bone_b : str
        The two bones' names.
    area : float
        How much they overlap, square pixels (>= 0).
    same_depth : bool
        Both regions are at the same depth layer, so their drawing order is the mesh's.
    """

    bone_a: str
    bone_b: str
    area: float
    same_depth: bool

    def __post_init__(self) -> None:
        if not (isinstance(self.bone_a, str) and isinstance(self.bone_b, str)):
            raise TypeError(f"an overlap names two bones, got {self.bone_a!r} and {self.bone_b!r}")
        object.__setattr__(self, "area", finite_float(self.area, name="an overlap's area", minimum=0))
        object.__setattr__(self, "same_depth", bool(self.same_depth))


def default_depth(skeleton: Skeleton) -> NDArray[np.int64]:
    """Depth 0 for every bone, ``(b,)`` int."""
    return np.zeros(len(skeleton.bones), dtype=np.int64)


def set_region_depth(depth: ArrayLike, binding: Binding, vertex: int, value: int) -> NDArray[np.int64]:
    """New depths with the region of ``vertex`` (its bone) at ``value`` (clicking a vertex)."""
    if not (0 <= vertex < len(binding.bone)):
        raise SettingsError(f"there is no vertex {vertex}; the mesh has {len(binding.bone)} vertices")
    out = np.array(depth, dtype=np.int64)
    out[binding.bone[vertex]] = int(value)
    return out


def triangle_layers(mesh: Mesh, binding: Binding, depth: ArrayLike) -> NDArray[np.int64]:
    """Each triangle's depth: the highest depth among its vertices' bones, ``(m,)`` int."""
    return np.asarray(depth)[binding.bone[mesh.F]].max(axis=1)


def draw_order(mesh: Mesh, binding: Binding, depth: ArrayLike) -> NDArray[np.intp]:
    """Triangle indices back to front, ``(m,)``: by layer, then in mesh order."""
    return np.argsort(triangle_layers(mesh, binding, depth), kind="stable")


def find_overlaps(
    mesh: Mesh,
    binding: Binding,
    skeleton: Skeleton,
    U: NDArray[np.float64],
    depth: NDArray[np.integer],
    *,
    min_area: float | None = None,
) -> list[Overlap]:
    """Pairs of bone regions whose deformed triangles overlap by more than ``min_area`` px².

    A triangle counts for the region most of its vertices belong to. ``min_area`` defaults to
    a quarter of the mesh spacing squared, so regions that merely touch along a seam are not
    reported. Bones that share a joint (an upper arm and its forearm) are not compared: where
    they fold over each other is stage two's business, not a depth order's.
    """
    if min_area is None:
        min_area = 0.25 * mesh.spacing**2
    region = _triangle_region(mesh, binding)
    polygons = shapely.polygons(U[mesh.F])
    names = skeleton.bone_names
    unions = {}
    for b in np.unique(region):
        tris = polygons[region == b]
        unions[int(b)] = shapely.union_all(shapely.buffer(tris, 0))
    bones = sorted(unions)
    ends = [set(pair) for pair in skeleton.bones.tolist()]
    out = []
    for x, a in enumerate(bones):
        for b in bones[x + 1:]:
            if ends[a] & ends[b] or not unions[a].intersects(unions[b]):
                continue
            area = unions[a].intersection(unions[b]).area
            if area > min_area:
                out.append(Overlap(names[a], names[b], float(area), bool(depth[a] == depth[b])))
    return sorted(out, key=lambda o: -o.area)


def _triangle_region(mesh, binding):
    b = binding.bone[mesh.F]
    # The majority bone; with three different bones, the first vertex's.
    return np.where(b[:, 1] == b[:, 2], b[:, 1], b[:, 0])
