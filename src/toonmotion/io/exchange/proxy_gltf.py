"""Binary glTF (``.glb``) export of a 3D proxy: skeleton, collision volumes, points and camera.

One file, one scene, one animation: a LINEAR key per frame at ``t / fps`` seconds on every
animated property. 3D is the proxy's, right-handed, +Y up, metres, which is glTF's own frame and
unit, so nothing is converted; values are stored as float32. Node names come from the markers.

- ``skeleton``: the skeleton proxy as the joint-per-limb tree of
  :mod:`toonmotion.proxy3d.skeleton_bvh` (the same joints, names and offsets as its BVH clip),
  under one group node that is their common root. Root joints animate their translation, limb
  joints their rotation (relative to the parent limb). These nodes are the joints of a skin
  used by ``skeleton mesh``: a thin octahedron along each limb's rest vector, bound wholly to
  the limb's joint, with inverse bind matrices at the rest pose (every rotation the identity,
  the roots where they are on frame 0).
- ``collision`` (only when the proxy has radii): per limb ``cylinder/<p>-<c>``, a unit tapered
  cylinder along +Y from y = 0 to y = 1 whose rings have radius 0, with two morph targets that
  push the bottom ring (target 0) and the top ring (target 1) out to radius 1. The node's
  translation is the parent marker's point, its rotation the shortest turn from +Y to the limb,
  its scale ``(1, h, 1)`` with ``h`` the limb's length, and its morph weights the two radii.
  The scale stretches only the local Y axis while the targets move the rings in local XZ, so
  the rings keep radius = weight exactly and sit at both markers' points. Per marker
  ``sphere/<name>``: a unit sphere at its point, uniform scale = the joint sphere's radius.
- ``points``: ``point/<name>``, an empty node per marker following its point.
- ``camera``: a glTF perspective camera (``yfov = 2 atan(height / (2 focal))``,
  ``aspectRatio = width / height``) on a node at the camera's centre. glTF cameras look down
  their -Z with +Y up, so the node's rotation is ``R^T diag(1, -1, -1)``, with ``R`` the
  proxy camera's world-to-camera rotation (rows: image x, image y down, forward); a world point
  then lands on the same pixel as :meth:`PerspectiveCamera.project
  <toonmotion.proxy3d.camera.PerspectiveCamera.project>`.

Rotation tracks are kept on one hemisphere from frame to frame, so interpolation between two
keys takes the short way.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pygltflib as gl
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

from toonmotion.errors import ProxyError
from toonmotion.io.atomic import write_bytes
from toonmotion.io.exchange.glb import GlbDocument, continuous
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton_bvh import LimbTree, limb_tree

# Segments around a cylinder or a sphere, and rings from pole to pole of a sphere.
SEGMENTS, SPHERE_RINGS = 16, 8
# The camera's near plane, metres.
ZNEAR = 0.01


def save_proxy_glb(path: str | Path, proxy: Proxy) -> None:
    """Write ``proxy`` as one binary glTF file, atomically (contents: the module docstring).

    Parameters
    ----------
    path : str or Path
        The ``.glb`` file to write.
    proxy : Proxy

    Raises
    ------
    ProxyError
        A value does not fit a 32-bit float (beyond about 3.4e38).

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> X = [[[0, 1, 0], [0, 1.5, 0]], [[0, 1, 0], [0.5, 1, 0]]]
    >>> turn = Rotation.from_euler("z", -90, degrees=True).as_quat().tolist()
    >>> camera = PerspectiveCamera(500.0, 64, 48, [[0, 0, 0, 0, 1, 5]] * 2)
    >>> proxy = Proxy(("hips", "head"), [-1, 0], 2, camera, points=X, radii=[[[0.1, 0.05]]] * 2,
    ...               skeleton=X, rest=[[0, 0.5, 0]], limb_rotations=[[[0, 0, 0, 1]], [turn]])
    >>> path = Path(tempfile.mkdtemp()) / "proxy.glb"
    >>> save_proxy_glb(path, proxy)
    >>> glb = gl.GLTF2.load_binary(path)
    >>> [node.name for node in glb.nodes]  # doctest: +NORMALIZE_WHITESPACE
    ['skeleton', 'hips', 'head', 'head_end', 'skeleton mesh', 'collision', 'cylinder/hips-head',
     'sphere/hips', 'sphere/head', 'points', 'point/hips', 'point/head', 'camera']
    """
    write_bytes(path, proxy_glb_bytes(proxy))


def proxy_glb_bytes(proxy: Proxy) -> bytes:
    """The ``.glb`` file :func:`save_proxy_glb` writes, as bytes."""
    doc = GlbDocument(np.arange(proxy.frame_count) / proxy.fps, name="proxy", error=ProxyError,
                      units="proxy's units (metres)")
    group, joints, tree = _skeleton(doc, proxy)
    scene = [group]
    skinned = _skin(doc, proxy, group, joints, tree)
    if skinned is not None:
        scene.append(skinned)
    radii, sphere_radii = proxy.radii, proxy.sphere_radii
    if radii is not None and sphere_radii is not None:
        scene.append(_collision(doc, proxy, radii, sphere_radii))
    scene.append(_points(doc, proxy))
    scene.append(_camera(doc, proxy))
    return doc.finish(scene)


# -- the parts ---------------------------------------------------------------------------------


def _skeleton(doc: GlbDocument, proxy: Proxy) -> tuple[int, list[int], LimbTree]:
    """The joint nodes under a ``skeleton`` group node: the group's index, the joints' and the tree."""
    tree = limb_tree(proxy)
    local = continuous(tree.local_rotations(proxy.limb_rotations))
    group = doc.node("skeleton")
    root_marker = {int(tree.markers[m]): int(m) for m in np.flatnonzero(proxy.parents < 0)}
    nodes: list[int] = []
    for j, name in enumerate(tree.names):
        if j in root_marker:
            node = doc.node(name, translation=proxy.skeleton[0, root_marker[j]])
            doc.track(node, "translation", proxy.skeleton[:, root_marker[j]])
        elif tree.limbs[j] >= 0:
            node = doc.node(name, translation=tree.offsets[j], rotation=local[0, j])
            doc.track(node, "rotation", local[:, j])
        else:  # an End Site: where a limb ends
            node = doc.node(name, translation=tree.offsets[j])
        doc.child(group if tree.parents[j] < 0 else nodes[tree.parents[j]], node)
        nodes.append(node)
    return group, nodes, tree


def _skin(doc: GlbDocument, proxy: Proxy, group: int, nodes: list[int], tree: LimbTree) -> int | None:
    """The skinned mesh node (an octahedron per limb), or None for a proxy without limbs."""
    if not np.any(tree.limbs >= 0):
        return None
    # Rest pose: every rotation the identity, the roots where they are on frame 0.
    bind = np.zeros((len(nodes), 3))
    for j, parent in enumerate(tree.parents):
        if parent < 0:
            bind[j] = proxy.skeleton[0, int(np.flatnonzero(tree.markers == j)[0])]
        else:
            bind[j] = bind[parent] + tree.offsets[j]
    ibm = np.tile(np.eye(4), (len(nodes) + 1, 1, 1))
    ibm[1:, :3, 3] = -bind
    # Six vertices per limb joint, in the tree's order, each bound to its joint (the skin lists
    # the group node first, so joint j is skin joint j + 1).
    limb_joints = np.flatnonzero(tree.limbs >= 0)
    octahedra = [_octahedron(bind[j], proxy.rest[tree.limbs[j]]) for j in limb_joints]
    V = np.concatenate([V for V, _ in octahedra])
    triangles = np.concatenate([F + 6 * i for i, (_, F) in enumerate(octahedra)])
    joint_index = np.zeros((len(V), 4), dtype=np.uint16)
    joint_index[:, 0] = np.repeat(limb_joints + 1, 6)
    weights = np.zeros((len(V), 4), dtype=np.float32)
    weights[:, 0] = 1
    attributes = gl.Attributes(POSITION=doc.vertices(V, bounds=True), JOINTS_0=doc.vertices(joint_index),
                               WEIGHTS_0=doc.vertices(weights))
    mesh = doc.mesh("skeleton mesh", doc.primitive(attributes, triangles))
    # Column-major 4x4 matrices, as glTF stores them.
    matrices = doc.accessor(np.transpose(ibm, (0, 2, 1)).reshape(-1, 16))
    doc.gltf.skins.append(gl.Skin(name="skeleton", inverseBindMatrices=matrices, skeleton=group,
                                  joints=[group, *nodes]))
    return doc.node("skeleton mesh", mesh=mesh, skin=len(doc.gltf.skins) - 1)


def _collision(doc: GlbDocument, proxy: Proxy, radii: NDArray[np.float64], sphere_radii: NDArray[np.float64]
               ) -> int:
    """Cylinder and sphere nodes under a ``collision`` group node; the radii are the proxy's."""
    group = doc.node("collision")
    if len(proxy.limbs):
        cylinder = _cylinder_primitive(doc)
        ends = proxy.cylinders
        axis = ends[:, :, 1] - ends[:, :, 0]
        height = np.linalg.norm(axis, axis=-1)
        for k, (p, c) in enumerate(proxy.limbs):
            turn = continuous(_turn_from_y(axis[:, k]))
            scale = np.stack([np.ones_like(height[:, k]), height[:, k], np.ones_like(height[:, k])], axis=1)
            name = f"cylinder/{proxy.names[p]}-{proxy.names[c]}"
            # A mesh per limb, sharing the cylinder's data: its weights are the radii on frame 0
            # (pygltflib's nodes have no weights), for viewers that show no animation.
            mesh = doc.mesh(name, cylinder, weights=radii[0, k])
            node = doc.node(name, mesh=mesh, translation=ends[0, k, 0], rotation=turn[0], scale=scale[0])
            doc.track(node, "translation", ends[:, k, 0])
            doc.track(node, "rotation", turn)
            doc.track(node, "scale", scale)
            doc.track(node, "weights", radii[:, k])
            doc.child(group, node)
    sphere = _sphere_mesh(doc)
    for n, name in enumerate(proxy.names):
        scale = np.repeat(sphere_radii[:, n, None], 3, axis=1)
        node = doc.node(f"sphere/{name}", mesh=sphere, translation=proxy.points[0, n], scale=scale[0])
        doc.track(node, "translation", proxy.points[:, n])
        doc.track(node, "scale", scale)
        doc.child(group, node)
    return group


def _points(doc: GlbDocument, proxy: Proxy) -> int:
    group = doc.node("points")
    for n, name in enumerate(proxy.names):
        node = doc.node(f"point/{name}", translation=proxy.points[0, n])
        doc.track(node, "translation", proxy.points[:, n])
        doc.child(group, node)
    return group


def _camera(doc: GlbDocument, proxy: Proxy) -> int:
    camera = proxy.camera
    yfov = 2 * np.arctan(camera.height / (2 * camera.focal))
    doc.gltf.cameras.append(gl.Camera(name="camera", type="perspective", perspective=gl.Perspective(
        yfov=float(yfov), aspectRatio=camera.width / camera.height, znear=ZNEAR)))
    # Columns: glTF's camera axes in the world: +X image right, +Y image up, +Z backwards.
    to_world = np.transpose(camera.rotations, (0, 2, 1)) @ np.diag([1.0, -1, -1])
    turn = continuous(Rotation.from_matrix(to_world).as_quat())
    node = doc.node("camera", camera=len(doc.gltf.cameras) - 1, translation=camera.centres[0],
                    rotation=turn[0])
    doc.track(node, "translation", camera.centres)
    doc.track(node, "rotation", turn)
    return node


# -- meshes ------------------------------------------------------------------------------------


def _octahedron(base: NDArray[np.float64], limb: NDArray[np.float64]) -> tuple[NDArray[Any], NDArray[Any]]:
    """A thin octahedron from ``base`` to ``base + limb``: 6 vertices, 8 triangles."""
    length = float(np.linalg.norm(limb))
    axis = limb / length if length > 0 else np.array([0.0, 1.0, 0.0])
    side = np.cross(axis, [1.0, 0, 0] if abs(axis[0]) < 0.9 else [0.0, 0, 1])
    side /= np.linalg.norm(side)
    other = np.cross(axis, side)
    width = min(max(0.08 * length, 0.005), 0.05)
    waist = base + 0.2 * limb
    V = np.array([base, waist + width * side, waist + width * other, waist - width * side,
                  waist - width * other, base + limb])
    ring = [1, 2, 3, 4]
    F = [[0, ring[(i + 1) % 4], ring[i]] for i in range(4)]
    F += [[5, ring[i], ring[(i + 1) % 4]] for i in range(4)]
    return V, np.array(F)


def _cylinder_primitive(doc: GlbDocument) -> gl.Primitive:
    """The unit tapered cylinder with its two ring targets (module docstring)."""
    a = 2 * np.pi * np.arange(SEGMENTS) / SEGMENTS
    ring = np.stack([np.cos(a), np.zeros_like(a), np.sin(a)], axis=1)
    S = SEGMENTS
    # Vertices: bottom ring 0..S-1, top ring S..2S-1, bottom centre 2S, top centre 2S+1.
    V = np.zeros((2 * S + 2, 3))
    V[S:2 * S, 1] = V[2 * S + 1, 1] = 1
    bottom, top = np.zeros_like(V), np.zeros_like(V)
    bottom[:S], top[S:2 * S] = ring, ring
    i, j = np.arange(S), (np.arange(S) + 1) % S
    F = np.concatenate([np.stack([i, S + i, j], 1), np.stack([j, S + i, S + j], 1),  # the side, outwards
                        np.stack([np.full(S, 2 * S), i, j], 1),                      # bottom cap, -Y
                        np.stack([np.full(S, 2 * S + 1), S + j, S + i], 1)])          # top cap, +Y
    targets = [gl.Attributes(POSITION=doc.vertices(bottom, bounds=True)),
               gl.Attributes(POSITION=doc.vertices(top, bounds=True))]
    return doc.primitive(gl.Attributes(POSITION=doc.vertices(V, bounds=True)), F, targets=targets)


def _sphere_mesh(doc: GlbDocument) -> int:
    """A unit UV sphere: poles on Y, ``SPHERE_RINGS`` bands of ``SEGMENTS`` quads, outwards."""
    polar = np.pi * np.arange(1, SPHERE_RINGS) / SPHERE_RINGS
    a = 2 * np.pi * np.arange(SEGMENTS) / SEGMENTS
    ring = np.stack([np.outer(np.sin(polar), np.cos(a)), np.repeat(np.cos(polar)[:, None], SEGMENTS, 1),
                     np.outer(np.sin(polar), np.sin(a))], axis=-1).reshape(-1, 3)
    V = np.concatenate([[[0.0, 1, 0]], ring, [[0.0, -1, 0]]])
    S, R = SEGMENTS, SPHERE_RINGS - 1
    i, j = np.arange(S), (np.arange(S) + 1) % S
    faces = [np.stack([np.zeros(S, dtype=int), 1 + j, 1 + i], 1)]
    for r in range(R - 1):
        up, down = 1 + r * S, 1 + (r + 1) * S
        faces += [np.stack([up + i, up + j, down + i], 1), np.stack([up + j, down + j, down + i], 1)]
    last = 1 + (R - 1) * S
    faces.append(np.stack([np.full(S, len(V) - 1), last + i, last + j], 1))
    return doc.mesh("sphere", doc.primitive(gl.Attributes(POSITION=doc.vertices(V, bounds=True)),
                                            np.concatenate(faces)))


# -- rotations ---------------------------------------------------------------------------------


def _turn_from_y(direction: NDArray[np.float64]) -> NDArray[np.float64]:
    """The shortest rotations taking +Y to each direction ``(T, 3)``, quaternions ``(T, 4)``.

    A zero direction gets the identity; a direction along -Y a half turn about X.
    """
    length = np.linalg.norm(direction, axis=1, keepdims=True)
    u = np.where(length > 0, direction / np.where(length > 0, length, 1), [0.0, 1, 0])
    axis = np.stack([u[:, 2], np.zeros(len(u)), -u[:, 0]], axis=1)  # +Y cross u
    sine = np.linalg.norm(axis, axis=1, keepdims=True)
    unit = np.where(sine > 1e-12, axis / np.where(sine > 1e-12, sine, 1), [1.0, 0, 0])
    angle = np.arctan2(sine[:, 0], u[:, 1])
    return Rotation.from_rotvec(unit * angle[:, None]).as_quat()
