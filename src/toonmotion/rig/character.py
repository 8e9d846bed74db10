"""A rigged character: the drawing and everything built on it."""

from dataclasses import dataclass, field

import numpy as np


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
        Depth layer of each bone's region, higher in front (thesis 3.5); all 0 by default.
    edits : tuple
        The corrections and depth edits made, in order (see :mod:`toonmotion.rig.edits`);
        ``binding`` and ``depth`` are their result.
    undone : tuple
        Edits taken back by undo, in the order they were made, for redo.
    """

    texture: np.ndarray
    mask: np.ndarray
    silhouette: object
    curve_skeleton: object
    skeleton: object
    mesh: object
    binding: object
    settings: RigSettings = field(default_factory=RigSettings)
    depth: np.ndarray = None
    edits: tuple = ()
    undone: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "edits", tuple(self.edits))
        object.__setattr__(self, "undone", tuple(self.undone))
        bones = len(self.skeleton.bones)
        depth = np.zeros(bones) if self.depth is None else self.depth
        depth = np.array(depth, dtype=np.int64)
        if depth.shape != (bones,):
            raise ValueError(f"depth needs one value per bone ({bones}), got shape {depth.shape}")
        depth.setflags(write=False)
        object.__setattr__(self, "depth", depth)

    @property
    def size(self):
        """``(width, height)`` of the drawing in pixels."""
        return self.texture.shape[1], self.texture.shape[0]
