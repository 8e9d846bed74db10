"""Binary glTF (``.glb``) export of an animated drawing: a skinned, textured mesh that replays it.

One file, one scene, one animation with a LINEAR key per frame at ``frame / fps`` seconds. The
frame is :mod:`~toonmotion.io.exchange.drawing_rig`'s with ``unit = PIXELS_PER_METRE``: the
drawing stands on the XY plane's x axis, y up, facing +Z, 100 pixels to the metre.

- ``<joint>``: a node per skeleton joint, a child of its parent joint's node (roots at the
  scene's top), with the translation and rotation of :mod:`toonmotion.animate.skin_tracks`'s
  joint frames; turning one in an editor swings what hangs below it.
- ``bone:<joint>``: a node per bone, a child of its start joint's node, turned along the bone
  and scaled ``(sigma, rho, 1)``: stage one's stretch along the bone and thinning across it.
- ``drawing``: the mesh, textured with the drawing (``KHR_materials_unlit``, alpha blended,
  double sided; triangles back to front in the character's depth order) and skinned to the
  ``bone:`` nodes: one bone per vertex, or up to four with the weighted skinning. The skin's
  joints list the joint nodes too (with no vertex weighted to them), so importers that build an
  armature from a skin keep the whole hierarchy. Inverse bind matrices are the rest pose's.
- Stage two (and fine-tuning edits): a **morph target per frame** that has any, holding each
  vertex's offset in the rest frame (sparse: only vertices that move), with a weight track that
  is 1 on its own frame and 0 elsewhere. The offsets are computed against the skin a reader
  builds from the stored float32 numbers, so a reader that evaluates the file in double
  precision lands on toonmotion's vertices to within :data:`MORPH_FLOOR_PX` (offsets smaller
  than that are left out); rotations, scales and translations are not resampled or approximated.
  Where a bone is squashed to a small fraction of its length, the skin thickens it across by
  the reciprocal, which magnifies the float32 rounding of a large offset (to 0.03 px when a
  bone is at 1/40 of its length): a second target on that frame, ``frame <n> (fine)``, carries
  what the first one's rounding lost.

Every frame is a key, rather than only the key-frames: the thesis's in-betweens turn bones at a
steady rate but stretch them so that their thickness goes as ``1 / sigma``, and interpolate
stage two in each bone's frame, neither of which glTF's interpolation can express exactly.
"""

from __future__ import annotations

from io import BytesIO
from pathlib import Path

import numpy as np
import pygltflib as gl
from numpy.typing import NDArray
from PIL import Image

from toonmotion.animate.skin_tracks import bind_offsets, skinned
from toonmotion.errors import ExportError
from toonmotion.io.atomic import write_bytes
from toonmotion.io.exchange.drawing_rig import DrawingRig
from toonmotion.io.exchange.glb import GlbDocument

PIXELS_PER_METRE = 100.0
# Vertices whose offset is below this many pixels are left out of a frame's morph target: the
# float32 rounding of the skin alone reaches 2e-5 px on a 300-pixel figure, and a frame of stage
# one alone should carry no target.
MORPH_FLOOR_PX = 5e-5


def save_animation_glb(path: str | Path, rig: DrawingRig) -> None:
    """Write ``rig`` (from :func:`~toonmotion.io.exchange.drawing_rig.drawing_rig` with
    ``unit=PIXELS_PER_METRE``) as one binary glTF file, atomically (contents: the module docstring).

    Raises
    ------
    ExportError
        ``path`` does not end in ``.glb``.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.sample_animation import sample_animated
    >>> from toonmotion.io.exchange.drawing_rig import drawing_rig
    >>> hero, animation = sample_animated()
    >>> path = Path(tempfile.mkdtemp()) / "hero.glb"
    >>> save_animation_glb(path, drawing_rig(hero, animation, unit=PIXELS_PER_METRE))
    >>> glb = gl.GLTF2.load_binary(path)
    >>> len(glb.skins[0].joints) == len(hero.skeleton) + len(hero.skeleton.bones)
    True
    """
    if Path(path).suffix.lower() != ".glb":
        raise ExportError(f"a glTF export is a binary .glb file, not {Path(path).name}")
    write_bytes(path, animation_glb_bytes(rig))


def animation_glb_bytes(rig: DrawingRig) -> bytes:
    """The ``.glb`` file :func:`save_animation_glb` writes, as bytes."""
    doc = GlbDocument(np.arange(rig.frame_count) / rig.fps, name="animation", error=ExportError,
                      units="drawing's size and the animation's joint positions")
    joints, bones, locals_ = _nodes(doc, rig)
    mesh_node = _mesh(doc, rig, joints, bones, locals_)
    roots = [joints[j] for j in np.flatnonzero(rig.tracks.parents < 0)]
    return doc.finish([*roots, mesh_node])


# -- the skeleton ------------------------------------------------------------------------------


class _Locals:
    """Every node's local transform as a reader sees it, rest (row 0) and per frame: animated
    values as stored (float32), still ones as written in the JSON (float64)."""

    def __init__(self) -> None:
        self.values: dict[tuple[int, str], NDArray[np.float64]] = {}

    def add(self, doc: GlbDocument, node: int, path: str, values: NDArray[np.float64]) -> None:
        """Set ``node``'s ``path`` to ``values`` ``(T + 1, width)`` (rest, then each frame): the rest
        value on the node, and a track when the frames' values change."""
        setattr(doc.gltf.nodes[node], path, [float(v) for v in values[0]])
        frames = values[1:]
        if np.all(frames == values[0]):
            self.values[node, path] = np.broadcast_to(values[0], values.shape)
            return
        doc.track(node, path, frames)
        stored = frames / np.linalg.norm(frames, axis=-1, keepdims=True) if path == "rotation" else frames
        self.values[node, path] = np.concatenate([values[:1], stored.astype(np.float32).astype(float)])

    def matrix(self, node: int) -> NDArray[np.float64]:
        """``node``'s local transforms ``(T + 1, 3, 3)``, 2D affine (every turn is about Z)."""
        t = self.values.get((node, "translation"))
        q = self.values.get((node, "rotation"))
        s = self.values.get((node, "scale"))
        count = len(next(v for (n, _), v in self.values.items() if n == node))
        M = np.tile(np.eye(3), (count, 1, 1))
        if q is not None:
            # A turn about Z by quaternion (0, 0, z, w), normalised as a reader does.
            z, w = q[:, 2], q[:, 3]
            norm = z * z + w * w
            c, s_ = (w * w - z * z) / norm, 2 * z * w / norm
            M[:, 0, 0], M[:, 0, 1], M[:, 1, 0], M[:, 1, 1] = c, -s_, s_, c
        if s is not None:
            M[:, :2, :2] *= s[:, None, :2]
        if t is not None:
            M[:, :2, 2] = t[:, :2]
        return M


def _nodes(doc: GlbDocument, rig: DrawingRig) -> tuple[list[int], list[int], _Locals]:
    """The joint and bone nodes (module docstring) and their local transforms."""
    tracks = rig.tracks
    translation, joint_angle = tracks.local_joints()
    bone_angle, scale = tracks.local_bones()
    locals_ = _Locals()
    joints: list[int] = []
    for j, name in enumerate(rig.joint_names):
        node = doc.node(name)
        locals_.add(doc, node, "translation", _xyz(translation[:, j], 0.0))
        locals_.add(doc, node, "rotation", _turn(joint_angle[:, j]))
        if tracks.parents[j] >= 0:
            doc.child(joints[tracks.parents[j]], node)
        joints.append(node)
    bones: list[int] = []
    for b, (start, _) in enumerate(tracks.bones):
        node = doc.node(f"bone:{rig.bone_names[b]}")
        locals_.add(doc, node, "rotation", _turn(bone_angle[:, b]))
        locals_.add(doc, node, "scale", _xyz(scale[:, b], 1.0))
        doc.child(joints[start], node)
        bones.append(node)
    return joints, bones, locals_


def _worlds(doc: GlbDocument, rig: DrawingRig, joints: list[int], bones: list[int], locals_: _Locals
            ) -> NDArray[np.float64]:
    """Every skin joint's world transform ``(T + 1, k + b, 3, 3)``: joints, then bones."""
    tracks = rig.tracks
    world: list[NDArray[np.float64]] = []
    for j, node in enumerate(joints):
        local = locals_.matrix(node)
        world.append(local if tracks.parents[j] < 0 else world[tracks.parents[j]] @ local)
    for b, node in enumerate(bones):
        world.append(world[tracks.bones[b, 0]] @ locals_.matrix(node))
    return np.stack(world, axis=1)


# -- the mesh ----------------------------------------------------------------------------------


def _mesh(doc: GlbDocument, rig: DrawingRig, joints: list[int], bones: list[int], locals_: _Locals) -> int:
    """The skinned, textured mesh node with its morph targets and their weight track."""
    k = len(joints)
    world = _worlds(doc, rig, joints, bones, locals_)
    inverse_bind = np.linalg.inv(world[0]).astype(np.float32).astype(float)
    ibm = np.tile(np.eye(4), (len(inverse_bind), 1, 1))
    ibm[:, :2, :2], ibm[:, :2, 3] = inverse_bind[:, :2, :2], inverse_bind[:, :2, 2]
    columns = np.transpose(ibm, (0, 2, 1)).reshape(-1, 16)  # column-major, as glTF stores them
    doc.gltf.skins.append(gl.Skin(name="skeleton", joints=joints + bones,
                                  inverseBindMatrices=doc.accessor(columns)))
    V32 = rig.V.astype(np.float32).astype(float)
    slots, weight = _joint_slots(rig, k)
    attributes = gl.Attributes(POSITION=doc.vertices(np.column_stack([V32, np.zeros(len(V32))]), bounds=True),
                               TEXCOORD_0=doc.vertices(rig.uv), JOINTS_0=doc.vertices(slots),
                               WEIGHTS_0=doc.vertices(weight))
    # The skin a reader builds, from the numbers as stored: bone b's matrix is world @ inverse bind.
    skin = world[1:, k:] @ inverse_bind[k:]
    w = weight.astype(float)[:, :rig.bone.shape[1]]
    targets: list[gl.Attributes] = []
    names: list[str] = []
    on: list[tuple[int, int]] = []  # (frame, target) pairs weighted 1

    def target(rows: NDArray[np.int64], values: NDArray[np.float64], t: int, name: str) -> None:
        on.append((t, len(targets)))
        padded = np.column_stack([values, np.zeros(len(rows))])
        targets.append(gl.Attributes(POSITION=doc.sparse(len(V32), rows, padded)))
        names.append(name)

    for t in range(rig.frame_count):
        matrices = skin[t][:, :2]
        offset = bind_offsets(V32, rig.bone, w, matrices, rig.U[t])
        # What the skin alone misses, in the frame's own pixels (a stretched bone enlarges an offset).
        missed = rig.U[t] - skinned(V32, rig.bone, w, matrices)
        moved = np.flatnonzero(np.hypot(missed[:, 0], missed[:, 1]) * rig.unit > MORPH_FLOOR_PX)
        if not len(moved):
            continue
        stored = offset[moved].astype(np.float32).astype(float)
        target(moved, stored, t, f"frame {t}")
        # Under a bone squashed to a small fraction of its length the skin thins it across by the
        # same factor's reciprocal, which magnifies the float32 rounding of a large offset; a
        # second target carries what the first's rounding lost there.
        kept = offset.copy()
        kept[moved] = stored
        lost = rig.U[t] - skinned(V32 + kept, rig.bone, w, matrices)
        fine = np.flatnonzero(np.hypot(lost[:, 0], lost[:, 1]) * rig.unit > MORPH_FLOOR_PX)
        if len(fine):
            target(fine, (offset - kept)[fine], t, f"frame {t} (fine)")
    material = _material(doc, rig)
    primitive = doc.primitive(attributes, rig.F, targets=targets, material=material)
    mesh = doc.mesh("drawing", primitive, weights=np.zeros(len(targets)) if targets else None)
    if names:
        doc.gltf.meshes[mesh].extras = {"targetNames": names}
    node = doc.node("drawing", mesh=mesh, skin=len(doc.gltf.skins) - 1)
    if targets:
        weights = np.zeros((rig.frame_count, len(targets)))
        weights[tuple(np.array(on).T)] = 1.0
        doc.track(node, "weights", weights)
    return node


def _joint_slots(rig: DrawingRig, k: int) -> tuple[NDArray[np.uint16], NDArray[np.float32]]:
    """JOINTS_0 and WEIGHTS_0 ``(n, 4)``: each vertex's bones (skin joint ``k + bone``); unused
    slots hold joint 0 with weight 0, as glTF asks."""
    n, used = rig.bone.shape
    if used > 4:
        raise ExportError(f"a glTF vertex follows at most 4 bones; this skin has {used}")
    slots = np.zeros((n, 4), dtype=np.uint16)
    weight = np.zeros((n, 4), dtype=np.float32)
    live = rig.weight > 0
    slots[:, :used] = np.where(live, k + rig.bone, 0)
    weight[:, :used] = np.where(live, rig.weight, 0.0)
    return slots, weight / weight.sum(axis=1, keepdims=True, dtype=np.float32)


def _material(doc: GlbDocument, rig: DrawingRig) -> int:
    """The drawing as an unlit, alpha-blended, double-sided material."""
    png = BytesIO()
    Image.fromarray(rig.page).save(png, format="PNG")
    texture = doc.png_texture(png.getvalue())
    doc.gltf.materials.append(gl.Material(
        name="drawing", alphaMode="BLEND", doubleSided=True,
        pbrMetallicRoughness=gl.PbrMetallicRoughness(baseColorTexture=gl.TextureInfo(index=texture),
                                                     metallicFactor=0.0, roughnessFactor=1.0),
        extensions={"KHR_materials_unlit": {}}))
    doc.gltf.extensionsUsed = ["KHR_materials_unlit"]
    return len(doc.gltf.materials) - 1


def _turn(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Quaternions ``(..., 4)`` (x, y, z, w) turning by ``angle`` about +Z."""
    half = np.asarray(angle) / 2
    zero = np.zeros_like(half)
    return np.stack([zero, zero, np.sin(half), np.cos(half)], axis=-1)


def _xyz(xy: NDArray[np.float64], z: float) -> NDArray[np.float64]:
    return np.concatenate([xy, np.full((*xy.shape[:-1], 1), z)], axis=-1)
