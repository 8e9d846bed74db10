"""A rigged character: the drawing and everything built on it."""

from __future__ import annotations

from dataclasses import dataclass, field
from numbers import Integral, Real

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import SettingsError
from toonmotion.geometry.arrays import frozen_array
from toonmotion.rig.binding import RULES as DECOMPOSITIONS
from toonmotion.rig.binding import Binding, Correction
from toonmotion.rig.depth_edit import DepthEdit
from toonmotion.rig.skeleton import Skeleton
from toonmotion.shape.curve_skeleton import CurveSkeleton
from toonmotion.shape.mesh import Mesh
from toonmotion.shape.segment import METHODS
from toonmotion.shape.silhouette import Silhouette


@dataclass(frozen=True)
class RigSettings:
    """How a drawing was rigged; saved in the project so a rig can be rebuilt the same way.

    Attributes
    ----------
    spacing : float or None
        Mesh sampling spacing in pixels; None picks it from ``vertices``.
    vertices : int or None
        Target vertex count (used when ``spacing`` is None; default 1,500).
    tolerance : float or None
        Outline simplification tolerance in pixels; None: 1 px, or a tenth of the spacing for
        coarse meshes, so a coarse mesh is not crowded with outline vertices.
    refine_joints : bool
        Sample denser around joints where bones meet (thesis 7.2 item 4).
    largest_only : bool
        Keep only the largest part of the figure.
    min_part : float
        Parts smaller than this fraction of the largest part are dropped as specks.
    prune : float
        Curve-skeleton spur pruning strength (see ``curve_skeleton``).
    max_bone : float or None
        Longest bone of an automatic skeleton, pixels; None: a fifth of the figure's size.
    segmentation : str
        Background model for drawings without alpha or mask: "auto", "flat" or "paper".
    decomposition : str
        Which bone each vertex follows: "geodesic" (nearest through the drawing, the default) or
        "straight" (the thesis's rule, eq. 3.1); see :func:`toonmotion.rig.binding.decompose`.

    Construction checks every value and raises :class:`~toonmotion.errors.SettingsError` (one
    line) for one out of range; numbers are stored as ``float`` (``vertices`` as ``int``), so
    settings compare and save the same however they were typed.

    Examples
    --------
    >>> RigSettings(spacing=4).spacing
    4.0
    >>> RigSettings(vertices=2)
    Traceback (most recent call last):
    ...
    toonmotion.errors.SettingsError: the vertex count must be at least 3, got 2
    """

    spacing: float | None = None
    vertices: int | None = None
    tolerance: float | None = None
    refine_joints: bool = False
    largest_only: bool = False
    min_part: float = 0.01
    prune: float = 0.5
    max_bone: float | None = None
    segmentation: str = "auto"
    decomposition: str = "geodesic"

    def __post_init__(self) -> None:
        if self.decomposition not in DECOMPOSITIONS:
            raise SettingsError(f"decomposition must be one of {', '.join(DECOMPOSITIONS)}, got "
                                f"{self.decomposition!r}")
        if self.segmentation not in METHODS:
            raise SettingsError(
                f"segmentation must be one of {', '.join(METHODS)}, got {self.segmentation!r}"
            )
        if self.spacing is not None and self.vertices is not None:
            raise SettingsError("give either a spacing or a vertex count, not both")
        spacing, tolerance, max_bone = (
            None if value is None else self._number(name, value)
            for name, value in (("spacing", self.spacing), ("tolerance", self.tolerance),
                                ("max_bone", self.max_bone))
        )
        min_part, prune = self._number("min_part", self.min_part), self._number("prune", self.prune)
        # Ranges as the mesher, the outline and the CLI have always taken them.
        if spacing is not None and not (np.isfinite(spacing) and spacing >= 1):
            raise SettingsError(f"spacing must be at least 1 pixel, got {spacing}")
        if tolerance is not None and not 0 <= tolerance <= 100:
            raise SettingsError(f"tolerance must be between 0 and 100 px, got {tolerance}")
        if not 0 <= min_part < 1:
            raise SettingsError(f"min_part must be in [0, 1), got {min_part}")
        if not (np.isfinite(prune) and prune >= 0):
            raise SettingsError(f"prune must be a finite number >= 0, got {prune}")
        if max_bone is not None and not (np.isfinite(max_bone) and max_bone > 0):
            raise SettingsError(f"max_bone must be a finite number of pixels > 0, got {max_bone}")
        vertices = self.vertices
        if vertices is not None:
            if isinstance(vertices, bool) or not isinstance(vertices, Integral):
                raise SettingsError(f"the vertex count must be a whole number, got {vertices!r}")
            if vertices < 3:
                raise SettingsError(f"the vertex count must be at least 3, got {vertices}")
            vertices = int(vertices)
        for name in ("refine_joints", "largest_only"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise SettingsError(f"{name} must be True or False, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))
        for name, value in (("spacing", spacing), ("vertices", vertices), ("tolerance", tolerance),
                            ("min_part", min_part), ("prune", prune), ("max_bone", max_bone)):
            object.__setattr__(self, name, value)

    @staticmethod
    def _number(name: str, value: object) -> float:
        if isinstance(value, bool) or not isinstance(value, Real):
            raise SettingsError(f"{name} must be a number, got {value!r}")
        return float(value)


@dataclass(frozen=True, eq=False)
class Character:
    """A drawing rigged for animation.

    Attributes
    ----------
    texture : (h, w, 4) uint8
        The drawing, RGBA.
    mask : (h, w) bool
        The figure's pixels.
    silhouette : Silhouette
    curve_skeleton : CurveSkeleton
    skeleton : Skeleton
    mesh : Mesh
    binding : Binding
    settings : RigSettings
        What was asked for; ``mesh.spacing`` and ``silhouette.tolerance`` say what was used.
    depth : (b,) int
        Depth layer of each bone's region, higher in front (thesis 3.5); None (the default)
        puts every region at 0.
    edits : tuple
        The corrections and depth edits made, in order (see :mod:`toonmotion.rig.edits`);
        ``binding`` and ``depth`` are their result.
    undone : tuple
        Edits taken back by undo, in the order they were made, for redo.

    Construction copies the arrays (read-only) and raises ``TypeError`` or ``ValueError``
    unless every part has its type and they fit together: the mask is the texture's size, the
    binding has a bone for each mesh vertex and triangle flags for each triangle, every bone
    it names exists, and ``depth`` has a value per bone.
    """

    texture: NDArray[np.uint8]
    mask: NDArray[np.bool_]
    silhouette: Silhouette
    curve_skeleton: CurveSkeleton
    skeleton: Skeleton
    mesh: Mesh
    binding: Binding
    settings: RigSettings = field(default_factory=RigSettings)
    depth: NDArray[np.int64] = None  # type: ignore[assignment]  # None: every region at depth 0
    edits: tuple[Correction | DepthEdit, ...] = ()
    undone: tuple[Correction | DepthEdit, ...] = ()

    def __post_init__(self) -> None:
        for name, kind in (("silhouette", Silhouette), ("curve_skeleton", CurveSkeleton),
                           ("skeleton", Skeleton), ("mesh", Mesh), ("binding", Binding),
                           ("settings", RigSettings)):
            value = getattr(self, name)
            if not isinstance(value, kind):
                raise TypeError(f"a character's {name} must be a {kind.__name__}, got {type(value).__name__}")
        texture = frozen_array(self.texture, dtype=np.uint8, shape=(None, None, 4),
                               name="a character's texture")
        mask = frozen_array(self.mask, dtype=np.bool_, shape=texture.shape[:2], name="a character's mask")
        binding, mesh = self.binding, self.mesh
        if len(binding.bone) != len(mesh.V) or len(binding.joint_triangle) != len(mesh.F):
            raise ValueError(f"the binding is for another mesh: {len(binding.bone)} vertices and "
                             f"{len(binding.joint_triangle)} triangles, not {len(mesh.V)} and {len(mesh.F)}")
        bones = len(self.skeleton.bones)
        if len(binding.bone) and binding.bone.max() >= bones:
            raise ValueError(f"the binding names bone {binding.bone.max()}; the skeleton has {bones} bones")
        depth = frozen_array(np.zeros(bones, dtype=np.int64) if self.depth is None else self.depth,
                             dtype=np.int64, name="a character's depth")
        if depth.shape != (bones,):
            raise ValueError(f"depth needs one value per bone ({bones}), got shape {depth.shape}")
        object.__setattr__(self, "texture", texture)
        object.__setattr__(self, "mask", mask)
        object.__setattr__(self, "depth", depth)
        object.__setattr__(self, "edits", tuple(self.edits))
        object.__setattr__(self, "undone", tuple(self.undone))

    @property
    def size(self) -> tuple[int, int]:
        """``(width, height)`` of the drawing in pixels."""
        return self.texture.shape[1], self.texture.shape[0]
