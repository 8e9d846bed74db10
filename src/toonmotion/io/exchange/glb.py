"""Building one binary glTF (``.glb``) document: its JSON objects, its binary blob and one animation.

The exporters (:mod:`~toonmotion.io.exchange.proxy_gltf`, :mod:`~toonmotion.io.exchange.drawing_gltf`)
say what goes in; this module keeps the bookkeeping of buffer views, accessors and samplers in
one place. Floats are stored as float32; every animation track has one LINEAR key per frame at
``frame / fps`` seconds.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pygltflib as gl
from numpy.typing import NDArray

from toonmotion.errors import ToonmotionError

FLOAT, UBYTE, USHORT, UINT = 5126, 5121, 5123, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
_KINDS = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4", 16: "MAT4"}
_COMPONENTS = {np.dtype(np.float32): FLOAT, np.dtype(np.uint8): UBYTE, np.dtype(np.uint16): USHORT,
               np.dtype(np.uint32): UINT}


class GlbDocument:
    """A glTF document being built: its JSON objects, binary blob and one animation.

    Parameters
    ----------
    times : (T,) float
        The animation's key times in seconds, shared by every track.
    name : str
        The animation's and the scene's name.
    error : type of ToonmotionError
        Raised, with ``units`` named, when a value does not fit a 32-bit float.
    units : str
        What the values are measured in, for that message.
    """

    def __init__(self, times: NDArray[np.float64], *, name: str, error: type[ToonmotionError],
                 units: str) -> None:
        self.gltf = gl.GLTF2(asset=gl.Asset(generator="toonmotion", version="2.0"))
        self.blob = bytearray()
        self.name, self.error, self.units = name, error, units
        self.animation = gl.Animation(name=name)
        self.times = self.accessor(times, bounds=True)

    def view(self, array: NDArray[Any], *, target: int | None = None) -> int:
        """A new buffer view holding ``array``'s bytes (floats as float32), 4-byte aligned."""
        a = self._stored(array)
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=a.nbytes,
                                                   target=target))
        self.blob += a.tobytes()
        self.blob += bytes(-len(self.blob) % 4)
        return len(self.gltf.bufferViews) - 1

    def accessor(self, array: NDArray[Any], *, target: int | None = None, bounds: bool = False,
                 normalized: bool = False) -> int:
        """An accessor over a new buffer view holding ``array`` ``(count,)`` or ``(count, width)``.

        Floats are stored as float32, integers as they come (uint8, uint16 or uint32).
        """
        a = self._stored(array)
        rows = a.reshape(len(a), -1)
        accessor = gl.Accessor(bufferView=self.view(a, target=target), componentType=_COMPONENTS[a.dtype],
                               count=len(a), type=_KINDS[rows.shape[1]], normalized=normalized or None)
        if bounds:
            accessor.min = [_number(v) for v in rows.min(axis=0)]
            accessor.max = [_number(v) for v in rows.max(axis=0)]
        self.gltf.accessors.append(accessor)
        return len(self.gltf.accessors) - 1

    def sparse(self, count: int, indices: NDArray[np.integer], values: NDArray[np.float64]) -> int:
        """A float accessor of ``count`` rows that are zero except ``values`` ``(m, width)`` at
        ``indices`` (increasing), stored sparse, with the bounds glTF asks of morph targets."""
        v = self._stored(values)
        width = v.shape[1]
        low = np.minimum(v.min(axis=0), 0.0) if len(v) < count else v.min(axis=0)
        high = np.maximum(v.max(axis=0), 0.0) if len(v) < count else v.max(axis=0)
        rows = self.view(np.asarray(indices, np.uint32))
        at = gl.AccessorSparseIndices(bufferView=rows, componentType=UINT)
        sparse = gl.Sparse(count=len(v), indices=at, values=gl.AccessorSparseValues(bufferView=self.view(v)))
        self.gltf.accessors.append(gl.Accessor(componentType=FLOAT, count=count, type=_KINDS[width],
                                               byteOffset=None, sparse=sparse, min=[_number(x) for x in low],
                                               max=[_number(x) for x in high]))
        return len(self.gltf.accessors) - 1

    def vertices(self, array: NDArray[Any], *, bounds: bool = False) -> int:
        """A vertex attribute accessor."""
        return self.accessor(array, target=ARRAY_BUFFER, bounds=bounds)

    def primitive(self, attributes: gl.Attributes, triangles: NDArray[Any],
                  targets: list[gl.Attributes] | None = None, material: int | None = None) -> gl.Primitive:
        flat = np.asarray(triangles, dtype=np.uint32).reshape(-1)
        indices = self.accessor(flat, target=ELEMENT_ARRAY_BUFFER)
        return gl.Primitive(attributes=attributes, indices=indices, targets=targets or [], material=material)

    def mesh(self, name: str, primitive: gl.Primitive, *, weights: NDArray[np.float64] | None = None) -> int:
        """A mesh of one primitive; ``weights``: its morph targets' default weights."""
        default = [] if weights is None else [float(w) for w in weights]
        self.gltf.meshes.append(gl.Mesh(name=name, primitives=[primitive], weights=default))
        return len(self.gltf.meshes) - 1

    def node(self, name: str, **fields: Any) -> int:
        """A node; array fields (translation, rotation, scale) become lists of floats."""
        for key in ("translation", "rotation", "scale"):
            if key in fields:
                fields[key] = [float(v) for v in np.asarray(fields[key], dtype=float)]
        self.gltf.nodes.append(gl.Node(name=name, **fields))
        return len(self.gltf.nodes) - 1

    def child(self, parent: int, node: int) -> None:
        self.gltf.nodes[parent].children.append(node)

    def track(self, node: int, path: str, values: NDArray[np.float64]) -> None:
        """A LINEAR track of ``values`` ``(T, width)``, one key per frame."""
        v = np.asarray(values, dtype=float)
        if path == "rotation":  # unit length after the cast to float32 too
            v = v / np.linalg.norm(v, axis=-1, keepdims=True)
        output = self.accessor(v.reshape(-1) if path == "weights" else v)
        self.animation.samplers.append(gl.AnimationSampler(input=self.times, output=output,
                                                           interpolation="LINEAR"))
        self.animation.channels.append(gl.AnimationChannel(
            sampler=len(self.animation.samplers) - 1, target=gl.AnimationChannelTarget(node=node, path=path)))

    def png_texture(self, png: bytes) -> int:
        """A texture of an embedded PNG image, sampled linearly and clamped at its edges."""
        self.gltf.bufferViews.append(gl.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=len(png)))
        self.blob += png
        self.blob += bytes(-len(self.blob) % 4)
        self.gltf.images.append(gl.Image(bufferView=len(self.gltf.bufferViews) - 1, mimeType="image/png"))
        self.gltf.samplers.append(gl.Sampler(magFilter=gl.LINEAR, minFilter=gl.LINEAR,
                                             wrapS=gl.CLAMP_TO_EDGE, wrapT=gl.CLAMP_TO_EDGE))
        self.gltf.textures.append(gl.Texture(source=len(self.gltf.images) - 1,
                                             sampler=len(self.gltf.samplers) - 1))
        return len(self.gltf.textures) - 1

    def finish(self, scene: list[int]) -> bytes:
        """The ``.glb`` bytes of the document with ``scene`` as its one scene's root nodes."""
        gltf = self.gltf
        gltf.scenes = [gl.Scene(name=self.name, nodes=scene)]
        gltf.scene = 0
        if self.animation.channels:
            gltf.animations = [self.animation]
        gltf.buffers = [gl.Buffer(byteLength=len(self.blob))]
        gltf.set_binary_blob(bytes(self.blob))
        return b"".join(gltf.save_to_bytes())

    def _stored(self, array: NDArray[Any]) -> NDArray[Any]:
        """``array`` as it is stored: contiguous, floats as float32 (checked to fit)."""
        a = np.ascontiguousarray(array)
        if a.dtype.kind == "f":
            if a.size and not np.abs(a).max() <= np.finfo(np.float32).max:
                raise self.error(f"a value is too large for glTF's 32-bit floats (beyond 3.4e38); "
                                 f"check the {self.units}")
            a = a.astype(np.float32)
        return a


def continuous(quaternions: NDArray[np.float64]) -> NDArray[np.float64]:
    """Quaternions ``(T, ..., 4)`` with signs flipped so that each frame's is near the last's."""
    q = np.array(quaternions, dtype=float)
    for t in range(1, len(q)):
        flip = np.sum(q[t] * q[t - 1], axis=-1) < 0
        q[t][flip] *= -1
    return q


def _number(value: Any) -> float | int:
    """An accessor bound as JSON: the stored value exactly (a float32 widens to float64 exactly)."""
    return int(value) if isinstance(value, np.integer) else float(value)
