"""Playing exported files back, independently of the exporters, for tests and benchmarks.

Each reads only the file and follows the format's own documented evaluation: glTF 2.0's node
hierarchy (``T R S`` from the root; quaternions through scipy), skins (joint world matrix times
inverse bind matrix, weighted) and morph targets at their animated weights (sparse accessors
too); Spine 4.2's bone world transforms for ``inherit: normal`` (``Bone.updateWorldTransformWith``),
timelines relative to the setup pose, and weighted vertices plus deform offsets
(``VertexAttachment.computeWorldVertices``). So a bug in an exporter cannot hide in a shared
reading of it.
"""

from __future__ import annotations

import math

import numpy as np
import pygltflib as gl
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

DTYPES = {5126: np.float32, 5121: np.uint8, 5123: np.uint16, 5125: np.uint32}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class GlbScene:
    """A .glb read back: accessors as arrays, and the nodes' world matrices at each keyframe."""

    def __init__(self, path):
        self.gltf = gl.GLTF2.load_binary(path)
        self.blob = self.gltf.binary_blob()
        self.by_name = {}
        for i, node in enumerate(self.gltf.nodes):
            self.by_name.setdefault(node.name, []).append(i)
        (animation,) = self.gltf.animations
        self.tracks = {}
        for channel in animation.channels:
            sampler = animation.samplers[channel.sampler]
            if sampler.interpolation != "LINEAR":
                raise ValueError(f"only LINEAR tracks are played back, not {sampler.interpolation}")
            self.times = self.read(sampler.input)[:, 0]
            self.tracks[channel.target.node, channel.target.path] = self.read(sampler.output)
        self.parent = {c: i for i, node in enumerate(self.gltf.nodes) for c in node.children}

    def read(self, index):
        accessor = self.gltf.accessors[index]
        dtype = DTYPES[accessor.componentType]
        width = WIDTHS[accessor.type]
        if accessor.bufferView is None:
            data = np.zeros((accessor.count, width))
        else:
            data = self._view(accessor.bufferView, accessor.byteOffset, dtype, accessor.count * width)
            data = data.reshape(accessor.count, width).astype(np.float64 if dtype == np.float32 else np.int64)
        sparse = accessor.sparse
        if sparse is not None:
            at = self._view(sparse.indices.bufferView, sparse.indices.byteOffset,
                            DTYPES[sparse.indices.componentType], sparse.count)
            values = self._view(sparse.values.bufferView, sparse.values.byteOffset, dtype,
                                sparse.count * width)
            data[at.astype(np.int64)] = values.reshape(sparse.count, width)
        return data

    def _view(self, index, offset, dtype, count):
        view = self.gltf.bufferViews[index]
        if view.byteStride is not None:
            raise ValueError("interleaved buffer views are not read")
        return np.frombuffer(self.blob, dtype=dtype, count=count, offset=view.byteOffset + (offset or 0))

    def node(self, name):
        (index,) = self.by_name[name]
        return index

    def value(self, node, path, t):
        if (node, path) in self.tracks:
            track = self.tracks[node, path]
            return track.reshape(len(self.times), -1)[t]
        static = getattr(self.gltf.nodes[node], path)
        default = {"translation": [0, 0, 0], "rotation": [0, 0, 0, 1], "scale": [1, 1, 1]}[path]
        return np.array(default if static is None else static, dtype=float)

    def local(self, node, t):
        M = np.eye(4)
        turn = Rotation.from_quat(self.value(node, "rotation", t)).as_matrix()
        M[:3, :3] = turn * self.value(node, "scale", t)  # R @ diag(scale)
        M[:3, 3] = self.value(node, "translation", t)
        return M

    def world(self, node, t):
        M = self.local(node, t)
        while node in self.parent:
            node = self.parent[node]
            M = self.local(node, t) @ M
        return M

    def at(self, name, t, local_point=(0, 0, 0)):
        return (self.world(self.node(name), t) @ [*local_point, 1])[:3]

    def weights(self, node, t):
        return self.tracks[node, "weights"].reshape(len(self.times), -1)[t]


def glb_mesh(scene: GlbScene, frame: int) -> NDArray[np.float64]:
    """The skinned mesh of ``scene`` (its one skinned node) at ``frame``, with its morph targets at
    their animated weights: ``(n, 3)`` in the file's units."""
    gltf = scene.gltf
    (mesh_node,) = [i for i, node in enumerate(gltf.nodes) if node.skin is not None]
    node = gltf.nodes[mesh_node]
    primitive = gltf.meshes[node.mesh].primitives[0]
    skin = gltf.skins[node.skin]
    P = scene.read(primitive.attributes.POSITION)
    if primitive.targets:
        for weight, target in zip(scene.weights(mesh_node, frame), primitive.targets, strict=True):
            P = P + weight * scene.read(target["POSITION"])
    joints = scene.read(primitive.attributes.JOINTS_0).astype(int)
    weights = scene.read(primitive.attributes.WEIGHTS_0)
    inverse_bind = scene.read(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    M = np.stack([scene.world(j, frame) @ inverse_bind[i] for i, j in enumerate(skin.joints)])
    return np.einsum("ns,nsij,nj->ni", weights, M[joints], np.column_stack([P, np.ones(len(P))]))[:, :3]


# -- Spine --------------------------------------------------------------------------------------


def spine_world(bones, local):
    """World ``(a, b, c, d, x, y)`` per bone from local ``(x, y, rotation, scaleX, scaleY)`` by name,
    ``inherit: normal`` (the only kind written), skeleton at the origin, unscaled."""
    world = {}
    for bone in bones:
        x, y, rotation, sx, sy = local[bone["name"]]
        la, lb = math.cos(math.radians(rotation)) * sx, math.cos(math.radians(rotation + 90)) * sy
        lc, ld = math.sin(math.radians(rotation)) * sx, math.sin(math.radians(rotation + 90)) * sy
        if "parent" not in bone:
            world[bone["name"]] = (la, lb, lc, ld, x, y)
            continue
        pa, pb, pc, pd, px, py = world[bone["parent"]]
        world[bone["name"]] = (pa * la + pb * lc, pa * lb + pb * ld, pc * la + pd * lc, pc * lb + pd * ld,
                               pa * x + pb * y + px, pc * x + pd * y + py)
    return world


def key_value(keys, time, fields, default):
    """A linear timeline's values at ``time`` (Spine's default curve)."""
    times = [key.get("time", 0.0) for key in keys]
    i = max(k for k, t in enumerate(times) if t <= time)
    values = [keys[i].get(f, default) for f in fields]
    if i + 1 == len(keys):
        return values
    after = [keys[i + 1].get(f, default) for f in fields]
    share = (time - times[i]) / (times[i + 1] - times[i])
    return [v + share * (w - v) for v, w in zip(values, after, strict=True)]


def spine_mesh(doc: dict, animation: str, time: float) -> NDArray[np.float64]:
    """The ``drawing`` mesh's world vertices ``(n, 2)`` at ``time`` seconds of ``animation`` in a
    Spine JSON document ``doc`` (deform keys are read at their own times only)."""
    bones = doc["bones"]
    timelines = doc["animations"][animation].get("bones", {})
    local = {}
    for bone in bones:
        x, y, rotation = bone.get("x", 0.0), bone.get("y", 0.0), bone.get("rotation", 0.0)
        sx, sy = bone.get("scaleX", 1.0), bone.get("scaleY", 1.0)
        keyed = timelines.get(bone["name"], {})
        if "rotate" in keyed:  # relative to the setup pose
            rotation = rotation + key_value(keyed["rotate"], time, ["value"], 0.0)[0]
        if "translate" in keyed:
            dx, dy = key_value(keyed["translate"], time, ["x", "y"], 0.0)
            x, y = x + dx, y + dy
        if "scale" in keyed:  # multiplies the setup scale
            kx, ky = key_value(keyed["scale"], time, ["x", "y"], 1.0)
            sx, sy = kx * sx, ky * sy
        local[bone["name"]] = (x, y, rotation, sx, sy)
    world = spine_world(bones, local)
    table = np.array([world[bone["name"]] for bone in bones])  # (bones, 6): a, b, c, d, x, y
    mesh = doc["skins"][0]["attachments"]["drawing"]["drawing"]
    vertex, bone, bind, weight = weighted_entries(mesh)
    deform = np.zeros((len(bone), 2))
    keys = doc["animations"][animation].get("attachments", {}).get("default", {}).get("drawing", {}) \
        .get("drawing", {}).get("deform", [])
    if keys:
        times = [key.get("time", 0.0) for key in keys]
        if time not in times:
            raise ValueError(f"deform keys are read at their own times only, not at {time}")
        key = keys[times.index(time)]
        if "vertices" in key:  # offsets from 'offset' on, zeros elsewhere
            flat = deform.reshape(-1)
            start = key.get("offset", 0)
            flat[start:start + len(key["vertices"])] = key["vertices"]
    a, b, c, d, wx, wy = table[bone].T
    vx, vy = bind[:, 0] + deform[:, 0], bind[:, 1] + deform[:, 1]
    out = np.zeros((len(mesh["uvs"]) // 2, 2))
    np.add.at(out, vertex, np.stack([(vx * a + vy * b + wx) * weight, (vx * c + vy * d + wy) * weight], -1))
    return out


def weighted_entries(mesh):
    """A weighted mesh's entries: vertex, bone index, bind x, y and weight of each, vertex by vertex."""
    numbers, n = mesh["vertices"], len(mesh["uvs"]) // 2
    if len(numbers) == 2 * n:  # Spine's own test for an unweighted mesh
        raise ValueError("the mesh is not weighted")
    rows, i = [], 0
    for v in range(n):
        count = numbers[i]
        rows += [(v, *numbers[i + 1 + 4 * k:i + 5 + 4 * k]) for k in range(count)]
        i += 1 + 4 * count
    if i != len(numbers):
        raise ValueError(f"the weighted vertices take {i} numbers, not the {len(numbers)} given")
    table = np.array(rows)
    return table[:, 0].astype(int), table[:, 1].astype(int), table[:, 2:4], table[:, 4]
