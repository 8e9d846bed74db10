"""Spine 4.2 export of an animated drawing: skeleton JSON, texture atlas and page image.

``save_spine("hero.json", rig)`` writes ``hero.json``, ``hero.atlas`` and ``hero.png`` (the
drawing cropped round the figure) from a :class:`~toonmotion.io.exchange.drawing_rig.DrawingRig`
built with ``unit=1`` (Spine measures pixels). The rig is
:mod:`toonmotion.animate.skin_tracks`'s, one Spine bone per frame of it:

- ``root`` (``root_1``, ... if a joint has that name) at the origin;
- per joint, a bone named as the joint, child of its parent joint's bone (or of the root), at its
  rest place and angle relative to that parent, never scaled: keys ``translate`` and ``rotate``;
- per skeleton bone, ``bone:<end joint>``, child of its start joint's bone at the same point,
  turned along the bone (``length`` its rest length): keys ``rotate`` and ``scale``
  ``(sigma, rho)``. Nothing hangs below these, so the only scaled bones have no children and
  Spine's default ``inherit: normal`` composes the transforms exactly.

One slot ``drawing`` on the root shows one weighted mesh attachment ``drawing`` of skin
``default``: each vertex weighted to the ``bone:`` bones it follows (zero weights left out), its
triangles back to front, the outline first (below). Stage two and fine-tuning edits are a deform
timeline: per frame, each weighted entry's offset in its bone's frame, the smallest offsets that
move the vertex where the skin misses it (not one shared offset, which the blend of a squashed
bone and one turned from it can make enormous). One key per frame at
``frame / fps`` seconds, linear; a timeline whose values never leave the setup pose is left out,
as is a deform key's ``vertices`` when it offsets nothing.

**Exactness.** Bone values are written in full precision (``repr``). The deform offsets are
solved against the skin the runtime builds from the numbers written (world transforms from the
written degrees, binds and weights), and written to a millionth of a pixel
(:data:`OFFSET_DECIMALS`), so evaluating the file in float64 lands on every frame's vertices
within about 1e-6 px; offsets below ``1e-9`` of the figure's size are written as 0. Spine's own
runtimes compute in float32, good to about ``1e-7`` of the figure's size.

**The hull.** Spine wants the outer hull's vertices first, in order round it, and their count in
``hull``. The outline loop of largest area (traced from the triangles' boundary edges) comes first,
clockwise in Spine's y-up frame as the editor's own meshes run (its four-corner mesh in forum
thread 8121), starting at the loop's lowest-numbered vertex; the other vertices follow in the rig's
order. :attr:`SpineSkeleton.order` keeps the permutation. Holes are just triangles (Spine's meshes
have no holes of their own).

What this relies on, from Spine's documentation and its 4.2 runtime source (read, not copied):

- JSON format page (esotericsoftware.com/spine-json-format): the ``skeleton`` header's ``x, y``
  are the bottom-left of the setup pose's bounding box, ``images`` the image folder; bones are
  listed parents first; a mesh's ``hull`` is its hull vertex count and ``width/height`` are
  nonessential. Forum thread 8121 shows the weighted ``vertices`` layout (count, then index,
  x, y, weight per bone).
- ``spine-ts/spine-core/src/SkeletonJson.ts`` (4.2): ``inherit`` (default ``normal``) replaces 3.x's
  ``transform``; ``vertices`` are weighted when not as long as ``uvs``; rotate keys carry ``value``,
  translate and scale keys ``x, y`` (defaults 0, 0 and 1, 1); keys without ``curve`` are linear;
  deform timelines sit at ``animations.<name>.attachments.<skin>.<slot>.<attachment>.deform``,
  a key's ``vertices`` copied in at ``offset`` over zeros, 2 per weighted entry.
- ``Animation.ts``: rotate and translate keys add to the setup pose's values, scale keys multiply
  its scale. ``Bone.ts`` ``updateWorldTransformWith``: ``inherit: normal`` world transforms,
  ``a = cos(r) sx, b = cos(r + 90) sy, c = sin(r) sx, d = sin(r + 90) sy`` in degrees times
  the parent's. ``attachments/Attachment.ts`` ``computeWorldVertices``: a weighted vertex is
  ``sum_k w_k (W_k (bind_k + deform_k))``. ``MeshAttachment.ts``: uvs run from the region's
  top-left corner, v down, as ``rig.uv`` does.
- Atlas format page (esotericsoftware.com/spine-atlas-format): a page's image name line, then
  ``size: w,h`` and ``filter: min,mag``; a region's name line, then ``bounds: x,y,w,h`` in the
  page's pixels from its top-left.

The header's ``spine`` is ``"4.2.00"``: the runtimes and the editor's import read the major and
minor version as the data format's; the patch ``00`` claims no particular editor release.
"""

from __future__ import annotations

import json
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import ValidationError

from toonmotion.animate.skin_tracks import skinned
from toonmotion.errors import ExportError
from toonmotion.io.atomic import atomic_path
from toonmotion.io.exchange.drawing_rig import DrawingRig
from toonmotion.io.exchange.spine_schema import SpineFile
from toonmotion.io.image import png_bytes
from toonmotion.io.schema import describe

SPINE_VERSION = "4.2.00"
ROOT, SLOT, ATTACHMENT, SKIN = "root", "drawing", "drawing", "default"
BONE_PREFIX = "bone:"
# Offsets below this fraction of the figure's size are rounding, not stage two: written as 0.
_NEGLIGIBLE = 1e-9
# Deform offsets are written to this many decimals (pixels).
OFFSET_DECIMALS = 6
_DEG = np.pi / 180  # Spine's MathUtils.degRad


@dataclass(frozen=True, eq=False)
class SpineSkeleton:
    """A Spine skeleton file's contents, and how its mesh's vertices map to the rig's.

    Attributes
    ----------
    file : SpineFile
        The skeleton JSON as its model.
    order : (n,) int
        Written vertex ``i`` is the rig's vertex ``order[i]`` (the outer hull first).
    """

    file: SpineFile
    order: NDArray[np.int64]

    def json(self) -> str:
        """The skeleton file's text: defaults left out, every number in full precision."""
        return json.dumps(self.file.model_dump(by_alias=True, exclude_defaults=True), separators=(",", ":"))


def save_spine(path: str | Path, rig: DrawingRig, *, name: str = "animation") -> None:
    """Write ``rig`` as Spine 4.2 files: ``path`` (``X.json``), ``X.atlas`` and ``X.png``.

    The three are staged as temporary files beside ``path`` and renamed over their targets only
    once all three are written: an error leaves any earlier set as it was, and no temporaries.

    Parameters
    ----------
    path : str or Path
        The skeleton file, ending in ``.json``.
    rig : DrawingRig
        Built with ``unit=1`` (:func:`~toonmotion.io.exchange.drawing_rig.drawing_rig`).
    name : str
        The animation's name.

    Raises
    ------
    ExportError
        ``path`` does not end in ``.json``, the name is empty, two bones would share a name, or a
        value is not finite.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.sample_animation import sample_animated
    >>> from toonmotion.io.exchange.drawing_rig import drawing_rig
    >>> hero, animation = sample_animated()
    >>> rig = drawing_rig(hero, animation)
    >>> folder = Path(tempfile.mkdtemp())
    >>> save_spine(folder / "hero.json", rig, name="wave")
    >>> sorted(p.name for p in folder.iterdir())
    ['hero.atlas', 'hero.json', 'hero.png']
    >>> print((folder / "hero.atlas").read_text(), end="")
    hero.png
    size: 207,297
    filter: Linear,Linear
    drawing
    bounds: 0,0,207,297
    """
    path = Path(path)
    if path.suffix.lower() != ".json":
        raise ExportError(f"a Spine skeleton file ends in .json, not {path.name!r}; name it e.g. "
                          f"{path.with_suffix('.json').name!r} (the .atlas and .png go beside it)")
    skeleton = spine_skeleton(rig, name=name)
    page = path.with_suffix(".png")
    height, width = rig.page.shape[:2]
    _write_together({
        path: skeleton.json().encode("utf-8"),
        path.with_suffix(".atlas"): spine_atlas(page.name, width, height).encode("utf-8"),
        page: png_bytes(rig.page),
    })


def spine_atlas(page: str, width: int, height: int, *, region: str = ATTACHMENT) -> str:
    """A Spine 4 texture atlas of one page, the image ``page``, holding one region that covers it.

    Examples
    --------
    >>> print(spine_atlas("hero.png", 20, 30), end="")
    hero.png
    size: 20,30
    filter: Linear,Linear
    drawing
    bounds: 0,0,20,30
    """
    return f"{page}\nsize: {width},{height}\nfilter: Linear,Linear\n{region}\nbounds: 0,0,{width},{height}\n"


def spine_skeleton(rig: DrawingRig, *, name: str = "animation") -> SpineSkeleton:
    """The Spine skeleton file of ``rig`` (contents: the module docstring), not yet written.

    Raises
    ------
    ExportError
        As :func:`save_spine`.

    Examples
    --------
    >>> from toonmotion.sample_animation import sample_animated
    >>> from toonmotion.io.exchange.drawing_rig import drawing_rig
    >>> hero, animation = sample_animated()
    >>> rig = drawing_rig(hero, animation)
    >>> spine = spine_skeleton(rig)
    >>> [bone.name for bone in spine.file.bones[:3]], spine.file.bones[-1].name
    (['root_1', 'root', 'hip'], 'bone:left_foot')
    >>> mesh = spine.file.skins[0].attachments["drawing"]["drawing"]
    >>> mesh.hull == len(hero.mesh.boundary[0]), sorted(spine.order.tolist()) == list(range(len(rig.V)))
    (True, True)
    """
    if not isinstance(name, str) or not name:
        raise ExportError("a Spine animation needs a name (got an empty one)")
    arrays = {"rest vertices": rig.V, "deformed vertices": rig.U, "uvs": rig.uv,
              "joint positions": rig.tracks.joint_position, "bone scales": rig.tracks.bone_scale}
    for what, array in arrays.items():
        if not np.isfinite(array).all():
            raise ExportError(f"the rig's {what} are not all finite numbers; animate the character again")
    order, hull = _hull_first(rig.V, rig.F)
    layout = _BoneLayout(rig)
    bones = _bone_values(rig, layout)
    world = _world(layout.parents, *bones.runtime)
    data: dict[str, Any] = {
        "skeleton": _header(rig),
        "bones": layout.entries(bones.setup),
        "slots": [{"name": SLOT, "bone": layout.names[0], "attachment": ATTACHMENT}],
    }
    mesh, deform = _mesh(rig, layout, world, order, hull)
    data["skins"] = [{"name": SKIN, "attachments": {SLOT: {ATTACHMENT: mesh}}}]
    animation: dict[str, Any] = {"bones": bones.timelines(layout.names, rig.fps)}
    if deform:
        animation["attachments"] = {SKIN: {SLOT: {ATTACHMENT: {"deform": deform}}}}
    data["animations"] = {name: animation}
    try:
        file = SpineFile.model_validate(data)
    except ValidationError as error:  # only a rig that breaks its own invariants gets here
        text = describe(error.errors()[0])[0]
        raise ExportError(f"the rig cannot be written as Spine JSON: {text}") from None
    return SpineSkeleton(file=file, order=order)


# -- bones -------------------------------------------------------------------------------------


class _BoneLayout:
    """The Spine bones' names and parents: the root, the joints (parents first), the bones."""

    def __init__(self, rig: DrawingRig) -> None:
        tracks = rig.tracks
        k = len(rig.joint_names)
        root, suffix = ROOT, 0
        while root in rig.joint_names:
            suffix += 1
            root = f"{ROOT}_{suffix}"
        joints: list[int] = []  # joint indices, each after its parent
        while len(joints) < k:
            placed = set(joints)
            ready = [j for j in range(k)
                     if j not in placed and (tracks.parents[j] < 0 or tracks.parents[j] in placed)]
            if not ready:
                raise ExportError("the skeleton's parents form a loop; fix the skeleton")
            joints += ready
        self.joint_bone = np.empty(k, dtype=np.int64)
        self.joint_bone[joints] = 1 + np.arange(k)
        self.joints = np.array(joints, dtype=np.int64)
        self.bone_bone = 1 + k + np.arange(len(rig.bone_names))
        self.names = [root, *(rig.joint_names[j] for j in joints), *(BONE_PREFIX + n for n in rig.bone_names)]
        joint_parent = [0 if tracks.parents[j] < 0 else int(self.joint_bone[tracks.parents[j]])
                        for j in joints]
        self.parents = np.array([-1, *joint_parent, *self.joint_bone[tracks.bones[:, 0]]], dtype=np.int64)
        seen: set[str] = set()
        for bone in self.names:
            if bone in seen:
                raise ExportError(f"two Spine bones would be named {bone!r} (a joint's name and a bone's "
                                  f"{BONE_PREFIX!r} name clash); rename the joint")
            seen.add(bone)
        rest = tracks.rest_position[tracks.bones]
        self.lengths = np.hypot(*(rest[:, 1] - rest[:, 0]).T)

    def entries(self, setup: tuple[NDArray[np.float64], ...]) -> list[dict[str, Any]]:
        x, y, rotation, _, _ = (v.tolist() for v in setup)
        out = []
        for i, bone in enumerate(self.names):
            entry: dict[str, Any] = {"name": bone, "x": x[i], "y": y[i], "rotation": rotation[i]}
            if i:
                entry["parent"] = self.names[self.parents[i]]
            if i > len(self.joints):
                entry["length"] = float(self.lengths[i - 1 - len(self.joints)])
            out.append(entry)
        return out


@dataclass(frozen=True)
class _BoneValues:
    """Every Spine bone's local values: ``setup`` and ``frames`` ``(T, nb)`` each of x, y, rotation
    (degrees), scaleX, scaleY; ``runtime`` the same ``(T + 1, nb)`` (setup first) as the runtime
    computes them from the written setup pose plus the written keys."""

    setup: tuple[NDArray[np.float64], ...]
    frames: tuple[NDArray[np.float64], ...]
    keyed: dict[str, NDArray[np.bool_]]

    @property
    def runtime(self) -> tuple[NDArray[np.float64], ...]:
        x0, y0, r0, sx0, sy0 = self.setup
        x, y, r, sx, sy = self.frames
        moved, turned, scaled = self.keyed["translate"], self.keyed["rotate"], self.keyed["scale"]
        live = (
            np.where(moved, x0 + (x - x0), x0), np.where(moved, y0 + (y - y0), y0),
            np.where(turned, r0 + (r - r0), r0),
            np.where(scaled, sx * sx0, sx0), np.where(scaled, sy * sy0, sy0),
        )
        return tuple(np.concatenate([s[None], f]) for s, f in zip(self.setup, live, strict=True))

    def timelines(self, names: list[str], fps: float) -> dict[str, dict[str, list[dict[str, float]]]]:
        x0, y0, r0, _, _ = self.setup
        x, y, r, sx, sy = self.frames
        times = (np.arange(len(x)) / fps).tolist()
        out: dict[str, dict[str, list[dict[str, float]]]] = {}
        for i, bone in enumerate(names):
            timelines: dict[str, list[dict[str, float]]] = {}
            if self.keyed["translate"][i]:
                timelines["translate"] = [{"time": t, "x": a, "y": b} for t, a, b in
                                          zip(times, (x[:, i] - x0[i]).tolist(), (y[:, i] - y0[i]).tolist(),
                                              strict=True)]
            if self.keyed["rotate"][i]:
                timelines["rotate"] = [{"time": t, "value": v} for t, v in
                                       zip(times, (r[:, i] - r0[i]).tolist(), strict=True)]
            if self.keyed["scale"][i]:
                timelines["scale"] = [{"time": t, "x": a, "y": b} for t, a, b in
                                      zip(times, sx[:, i].tolist(), sy[:, i].tolist(), strict=True)]
            if timelines:
                out[bone] = timelines
        return out


def _bone_values(rig: DrawingRig, layout: _BoneLayout) -> _BoneValues:
    """The local x, y, rotation (degrees) and scale of every Spine bone at rest and per frame."""
    translation, joint_angle = rig.tracks.local_joints()
    bone_angle, bone_scale = rig.tracks.local_bones()
    rows, nb = translation.shape[0], len(layout.names)
    x, y, rotation = np.zeros((rows, nb)), np.zeros((rows, nb)), np.zeros((rows, nb))
    sx, sy = np.ones((rows, nb)), np.ones((rows, nb))
    j, b = layout.joint_bone, layout.bone_bone
    x[:, j], y[:, j], rotation[:, j] = translation[..., 0], translation[..., 1], np.degrees(joint_angle)
    rotation[:, b], sx[:, b], sy[:, b] = np.degrees(bone_angle), bone_scale[..., 0], bone_scale[..., 1]
    setup = (x[0], y[0], rotation[0], sx[0], sy[0])
    frames = (x[1:], y[1:], rotation[1:], sx[1:], sy[1:])
    keyed = {  # a timeline only where some frame leaves the setup value
        "translate": ((x[1:] != x[0]) | (y[1:] != y[0])).any(axis=0),
        "rotate": (rotation[1:] != rotation[0]).any(axis=0),
        "scale": ((sx[1:] != 1) | (sy[1:] != 1)).any(axis=0),
    }
    return _BoneValues(setup=setup, frames=frames, keyed=keyed)


def _world(parents: NDArray[np.int64], x: NDArray[np.float64], y: NDArray[np.float64],
           rotation: NDArray[np.float64], sx: NDArray[np.float64], sy: NDArray[np.float64],
           ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Spine's world transforms (``inherit: normal``, skeleton at the origin, unscaled) of bones
    with local values ``(rows, nb)`` each: linear parts ``(rows, nb, 2, 2)`` and origins ``(rows, nb, 2)``."""
    rx, ry = rotation * _DEG, (rotation + 90) * _DEG
    local = np.stack([np.stack([np.cos(rx) * sx, np.cos(ry) * sy], -1),
                      np.stack([np.sin(rx) * sx, np.sin(ry) * sy], -1)], -2)
    linear, origin = np.empty_like(local), np.empty(x.shape + (2,))
    for i, p in enumerate(parents):
        if p < 0:
            linear[:, i], origin[:, i] = local[:, i], np.stack([x[:, i], y[:, i]], -1)
        else:
            P = linear[:, p]
            origin[:, i, 0] = P[:, 0, 0] * x[:, i] + P[:, 0, 1] * y[:, i] + origin[:, p, 0]
            origin[:, i, 1] = P[:, 1, 0] * x[:, i] + P[:, 1, 1] * y[:, i] + origin[:, p, 1]
            linear[:, i] = P @ local[:, i]
    return linear, origin


# -- the mesh ----------------------------------------------------------------------------------


def _mesh(rig: DrawingRig, layout: _BoneLayout, world: tuple[NDArray[np.float64], NDArray[np.float64]],
          order: NDArray[np.int64], hull: int) -> tuple[dict[str, Any], list[dict[str, Any]]]:
    """The weighted mesh attachment and its deform keys (none when no frame offsets anything)."""
    V, uv, bone, weight, U = rig.V[order], rig.uv[order], rig.bone[order], rig.weight[order], rig.U[:, order]
    where = np.empty_like(order)
    where[order] = np.arange(len(order))
    linear, origin = world[0][:, layout.bone_bone], world[1][:, layout.bone_bone]  # the `bone:` bones
    Q = np.linalg.inv(linear[0])  # each bone's setup frame, undone
    t0 = origin[0]
    vertex, slot = np.nonzero(weight > 0)  # the weighted entries, vertex by vertex
    b = bone[vertex, slot]
    bind = np.einsum("eij,ej->ei", Q[b], V[vertex] - t0[b])
    counts = np.bincount(vertex, minlength=len(V))
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    vertices: list[int | float] = []
    spine_bone, bx, by, w = (layout.bone_bone[b].tolist(), bind[:, 0].tolist(), bind[:, 1].tolist(),
                             weight[vertex, slot].tolist())
    for v in range(len(V)):
        vertices.append(int(counts[v]))
        for e in range(starts[v], starts[v] + counts[v]):
            vertices += [spine_bone[e], bx[e], by[e], w[e]]
    height, width = rig.page.shape[:2]
    mesh = {"type": "mesh", "uvs": uv.reshape(-1).tolist(), "triangles": where[rig.F].reshape(-1).tolist(),
            "vertices": vertices, "hull": hull, "width": float(width), "height": float(height)}
    # Each frame's skin as the runtime builds it: M = W_t W_setup^-1 per bone.
    negligible = _NEGLIGIBLE * max(1.0, float(np.ptp(V, axis=0).max()))
    keys: list[dict[str, Any]] = []
    for t in range(rig.frame_count):
        L = linear[t + 1] @ Q
        M = np.concatenate([L, (origin[t + 1] - np.einsum("bij,bj->bi", L, t0))[:, :, None]], axis=2)
        missed = U[t] - skinned(V, bone, weight, M)
        missed[np.hypot(missed[:, 0], missed[:, 1]) < negligible] = 0.0
        posed = weight[vertex, slot][:, None, None] * linear[t + 1][b]
        offsets = _entry_offsets(missed, vertex, posed).reshape(-1)
        # Written to a millionth of a pixel: a third of the file's size, errors far below float32's.
        offsets = np.round(offsets, OFFSET_DECIMALS) + 0.0
        key: dict[str, Any] = {"time": t / rig.fps}
        nonzero = np.flatnonzero(offsets)
        if len(nonzero):
            key["offset"] = int(nonzero[0])
            key["vertices"] = offsets[nonzero[0]:nonzero[-1] + 1].tolist()
        keys.append(key)
    return mesh, keys if any("vertices" in key for key in keys) else []


def _entry_offsets(missed: NDArray[np.float64], vertex: NDArray[np.int64], A: NDArray[np.float64]
                   ) -> NDArray[np.float64]:
    """Each weighted entry's offset in its bone's frame, ``(e, 2)``: the smallest offsets (least
    squares over each vertex's entries) whose weighted, posed sum moves each vertex by ``missed``
    ``(n, 2)``. ``A`` ``(e, 2, 2)`` is each entry's weight times its bone's posed linear part.

    Solving ``sum_e A_e off_e = missed`` through ``G = sum_e A_e A_e^T`` rather than through the
    blended ``sum_e A_e`` matters where bones turned apart and squashed nearly cancel in the blend:
    there one offset for all the vertex's bones would run to millions of pixels, which Spine's
    float32 runtime cannot add back exactly, while these stay of the size of the move.
    """
    G = np.zeros((len(missed), 2, 2))
    np.add.at(G, vertex, A @ np.swapaxes(A, 1, 2))
    moved = np.flatnonzero(np.hypot(missed[:, 0], missed[:, 1]) > 0)
    y = np.zeros_like(missed)
    y[moved] = np.linalg.solve(G[moved], missed[moved][:, :, None])[:, :, 0]
    return np.einsum("eji,ej->ei", A, y[vertex])  # A_e^T y


def _header(rig: DrawingRig) -> dict[str, Any]:
    low, high = rig.V.min(axis=0), rig.V.max(axis=0)
    return {"spine": SPINE_VERSION, "x": float(low[0]), "y": float(low[1]), "width": float(high[0] - low[0]),
            "height": float(high[1] - low[1]), "fps": float(rig.fps), "images": "./"}


def _hull_first(V: NDArray[np.float64], F: NDArray[np.int64]) -> tuple[NDArray[np.int64], int]:
    """A vertex order with the outline loop of largest area first (clockwise, y up, from its
    lowest-numbered vertex), then every other vertex in its order; and that loop's length."""
    # Each counter-clockwise triangle's directed edges, to its third vertex.
    third: dict[tuple[int, int], int] = {}
    for a, b, c in np.asarray(F).tolist():
        for edge, opposite in (((a, b), c), ((b, c), a), ((c, a), b)):
            if edge in third:
                raise ExportError("the mesh has an edge shared by two triangles the same way round; "
                                  "rig the drawing again")
            third[edge] = opposite
    boundary = sorted(edge for edge in third if edge[::-1] not in third)
    if not boundary:
        raise ExportError("the mesh has no outline (no triangles); rig the drawing again")

    def after(edge: tuple[int, int]) -> tuple[int, int]:
        # The next outline edge: turn about edge's end through the triangles' fan.
        p, v = edge
        c = third[(p, v)]
        while (c, v) in third:
            c = third[(c, v)]
        return (v, c)

    loops, seen = [], set()
    for start in boundary:
        if start in seen:
            continue
        loop, edge = [], start
        while True:
            seen.add(edge)
            loop.append(edge[0])
            edge = after(edge)
            if edge == start:
                break
        loops.append(np.array(loop))
    area = [float(np.sum(V[L, 0] * V[np.roll(L, -1), 1] - V[np.roll(L, -1), 0] * V[L, 1])) for L in loops]
    outer = loops[int(np.argmax(area))][::-1]  # traced counter-clockwise: the triangles are
    outer = np.roll(outer, -int(np.argmin(outer)))
    rest = np.setdiff1d(np.arange(len(V)), outer)
    return np.concatenate([outer, rest]).astype(np.int64), len(outer)


# -- writing -----------------------------------------------------------------------------------


def _write_together(files: dict[Path, bytes]) -> None:
    """Write every file atomically, renaming none until all are written."""
    with ExitStack() as stack:
        staged = [(stack.enter_context(atomic_path(path)), data) for path, data in files.items()]
        for temporary, data in staged:
            temporary.write_bytes(data)
