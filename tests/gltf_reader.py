"""Reading a .glb back for the tests: accessors (sparse ones too) as arrays, node transforms and
skinning evaluated independently of the exporters, and the Khronos validator's report."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib as gl
import pytest
from scipy.spatial.transform import Rotation

ROOT = Path(__file__).resolve().parents[1]
VALIDATE = Path(__file__).with_name("validate_gltf.mjs")


DTYPES = {5126: np.float32, 5121: np.uint8, 5123: np.uint16, 5125: np.uint32}
WIDTHS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


class Scene:
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
            assert sampler.interpolation == "LINEAR"
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
        assert view.byteStride is None
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




def validator_installed():
    """True when node and node_modules/gltf-validator are there; skip (fail under CI=true) if not."""
    missing = None
    if shutil.which("node") is None:
        missing = "node is not installed"
    elif not (ROOT / "node_modules" / "gltf-validator").is_dir():
        missing = "node_modules/gltf-validator is not installed (make test runs npm ci)"
    if missing is None:
        return True
    if os.environ.get("CI") == "true":
        pytest.fail(f"the glTF validator is missing under CI: {missing}")
    return False


def validator_report(path):
    done = subprocess.run(["node", str(VALIDATE), str(path)], cwd=ROOT, capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)
