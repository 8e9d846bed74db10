"""Proxy files: a lifted 3D proxy (:class:`~toonmotion.proxy3d.proxy.Proxy`) as versioned JSON.

One array per key, and one frame per line for the arrays that run over frames::

    {"format": "toonmotion.proxy", "version": 1, "fps": 12.0,
     "names": ["hips", "spine", ...],
     "parents": [null, "hips", ...],
     "camera": {"focal": 800.0, "width": 640, "height": 480, "extrinsics": [
      [azimuth, elevation, roll, cx, cy, cz],
      ...]},
     "rest": [[x, y, z], ...],
     "points": [
      [[x, y, z], ...],
      ...],
     "skeleton": [...],
     "limb_rotations": [
      [[qx, qy, qz, qw], ...],
      ...],
     "radii": null or [
      [[r_parent, r_child], ...],
      ...]}

``parents`` names each marker's parent marker (``null`` for a root). ``rest``, ``limb_rotations``
and ``radii`` are per limb in the order of :attr:`Proxy.limbs <toonmotion.proxy3d.proxy.Proxy.limbs>`
(markers with a parent, parents before children), which the names and parents determine.
3D is right-handed, +Y up, metres; the camera's angles are radians (see
:mod:`toonmotion.proxy3d.camera`).

Numbers are written in full precision (``repr``), so a save followed by a load gives back the
same arrays bit for bit. The file model checks types; the loader checks that every frame has
every marker and limb, then :class:`~toonmotion.proxy3d.proxy.Proxy` checks the rest (finite
values, unit quaternions, radii not negative).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field, StrictStr

from toonmotion import limits
from toonmotion.errors import ProxyError
from toonmotion.io.atomic import write_text
from toonmotion.io.schema import Float, Int, JsonFormat, Model, Name, explained, read_versioned
from toonmotion.proxy3d.camera import PerspectiveCamera
from toonmotion.proxy3d.proxy import Proxy

FORMAT = "toonmotion.proxy"
VERSION = 1

Vec3 = tuple[Float, Float, Float]
Quat = tuple[Float, Float, Float, Float]
_Frames = Field(min_length=1)


class CameraEntry(Model):
    """The ``camera`` object of a proxy file."""

    focal: Float
    width: Int
    height: Int
    extrinsics: Annotated[list[tuple[Float, Float, Float, Float, Float, Float]], _Frames,
                          explained("'extrinsics' must list one [azimuth, elevation, roll, cx, cy, cz] "
                                    "per frame")]


class ProxyFile(Model):
    """A proxy file (see the module docstring)."""

    format: Literal["toonmotion.proxy"]
    version: Literal[1]
    fps: Float
    names: Annotated[list[Name], Field(min_length=1), explained("'names' must list at least one marker name")]
    parents: Annotated[list[StrictStr | None],
                       explained("'parents' must list each marker's parent name, or null for a root")]
    camera: CameraEntry
    rest: Annotated[list[Vec3], explained("'rest' must list one [x, y, z] per limb")]
    points: Annotated[list[list[Vec3]], _Frames,
                      explained("'points' must list one frame of [x, y, z] per marker")]
    skeleton: Annotated[list[list[Vec3]], _Frames,
                        explained("'skeleton' must list one frame of [x, y, z] per marker")]
    limb_rotations: Annotated[list[list[Quat]], _Frames,
                              explained("'limb_rotations' must list one frame of [qx, qy, qz, qw] per limb")]
    radii: Annotated[list[list[tuple[Float, Float]]] | None,
                     explained("'radii' must be null or list one frame of [parent, child] radii per limb")]


PROXY = JsonFormat(models={FORMAT: ProxyFile}, version=VERSION, error=ProxyError,
                   title="proxy file", label="proxy format")


def load_proxy(path: str | Path) -> Proxy:
    """Read a proxy file written by :func:`save_proxy`.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    Proxy

    Raises
    ------
    ProxyError
        The file is missing or unreadable, is another format or version, or its arrays do not
        fit together (a frame missing a marker or a limb, a parent that is not a marker, a value
        that is not finite, a quaternion that is not unit length); one line naming the file.

    Examples
    --------
    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "proxy.json"
    >>> camera = PerspectiveCamera(800.0, 640, 480, [[0.0, 0.0, 0.0, 0.0, 1.0, 5.0]])
    >>> proxy = Proxy(("hips", "head"), [-1, 0], 12, camera, points=[[[0, 1, 0], [0, 1.5, 0.1]]],
    ...               radii=None, skeleton=[[[0, 1, 0], [0, 1.5, 0]]], rest=[[0, 0.5, 0]],
    ...               limb_rotations=[[[0, 0, 0, 1]]])
    >>> save_proxy(path, proxy)
    >>> back = load_proxy(path)
    >>> back.names, back.limbs.tolist(), back.points[0, 1].tolist(), back.radii
    (('hips', 'head'), [[0, 1]], [0.0, 1.5, 0.1], None)
    """
    path = Path(path)
    model = read_versioned(path, PROXY)
    names = tuple(model.names)
    N = len(names)
    limits.check("joints", N, f"{path.name}'s marker count")
    limits.check("frames", len(model.points), f"{path.name}'s frame count")
    if len(model.parents) != N:
        raise ProxyError(f"{path}: 'parents' has {len(model.parents)} entries for the {N} names; give one "
                         "parent name (or null) per marker")
    if len(set(names)) != N:
        twice = next(name for name in names if names.count(name) > 1)
        raise ProxyError(f"{path}: marker name {twice!r} is used twice; the names must be distinct")
    index = {name: n for n, name in enumerate(names)}
    unknown = [p for p in model.parents if p is not None and p not in index]
    if unknown:
        raise ProxyError(f"{path}: parent {unknown[0]!r} is not one of the marker names")
    parents = np.array([-1 if p is None else index[p] for p in model.parents], dtype=np.int64)
    _check_forest(path, names, parents)
    K = int(np.count_nonzero(parents >= 0))
    T = len(model.camera.extrinsics)
    rows: dict[str, Any] = {"points": model.points, "skeleton": model.skeleton,
                            "limb_rotations": model.limb_rotations}
    if model.radii is not None:
        rows["radii"] = model.radii
    arrays = {key: _frames(path, key, value, T, K if key in ("limb_rotations", "radii") else N)
              for key, value in rows.items()}
    if len(model.rest) != K:
        raise ProxyError(f"{path}: 'rest' has {len(model.rest)} vectors for the {K} limbs; give one "
                         "[x, y, z] per marker that has a parent")
    # A unit quaternion's components lie in [-1, 1]: refuse others before any norm can overflow.
    if K and np.abs(arrays["limb_rotations"]).max() > 1 + 1e-6:
        raise ProxyError(f"{path}: the limb rotations must be unit quaternions [qx, qy, qz, qw]")
    try:
        camera = PerspectiveCamera(model.camera.focal, model.camera.width, model.camera.height,
                                   np.array(model.camera.extrinsics, dtype=float))
        return Proxy(names, parents, model.fps, camera, points=arrays["points"], radii=arrays.get("radii"),
                     skeleton=arrays["skeleton"], rest=np.array(model.rest, dtype=float).reshape(K, 3),
                     limb_rotations=arrays["limb_rotations"])
    except ProxyError as error:
        raise ProxyError(f"{path}: {error}") from None


def save_proxy(path: str | Path, proxy: Proxy) -> None:
    """Write ``proxy`` to ``path`` atomically, as the module docstring shows.

    Every number is written by ``repr``, so :func:`load_proxy` gives back the same arrays bit
    for bit.

    >>> import tempfile
    >>> path = Path(tempfile.mkdtemp()) / "proxy.json"
    >>> camera = PerspectiveCamera(800.0, 640, 480, [[0.0, 0.0, 0.0, 0.0, 1.0, 5.0]])
    >>> X = [[[0.1, 1e-17, 1 / 3]]]
    >>> proxy = Proxy(("hips",), [-1], 24, camera, points=X, radii=np.zeros((1, 0, 2)), skeleton=X,
    ...               rest=np.zeros((0, 3)), limb_rotations=np.zeros((1, 0, 4)))
    >>> save_proxy(path, proxy)
    >>> print(path.read_text(), end="")
    {"format": "toonmotion.proxy", "version": 1, "fps": 24.0,
     "names": ["hips"],
     "parents": [null],
     "camera": {"focal": 800.0, "width": 640, "height": 480, "extrinsics": [
     [0.0,0.0,0.0,0.0,1.0,5.0]]},
     "rest": [],
     "points": [
     [[0.1,1e-17,0.3333333333333333]]],
     "skeleton": [
     [[0.1,1e-17,0.3333333333333333]]],
     "limb_rotations": [
     []],
     "radii": [
     []]}
    >>> load_proxy(path).points.tolist()
    [[[0.1, 1e-17, 0.3333333333333333]]]
    """
    names = list(proxy.names)
    parents = [None if p < 0 else names[p] for p in proxy.parents]
    camera = proxy.camera
    head = json.dumps({"format": FORMAT, "version": VERSION, "fps": proxy.fps})[:-1]
    cam = json.dumps({"focal": camera.focal, "width": camera.width, "height": camera.height})[:-1]
    parts = [
        f"{head},\n",
        f' "names": {json.dumps(names)},\n',
        f' "parents": {json.dumps(parents)},\n',
        f' "camera": {cam}, "extrinsics": [\n{_rows(camera.extrinsics)}]}},\n',
        f' "rest": {_dump(proxy.rest)},\n',
        f' "points": [\n{_rows(proxy.points)}],\n',
        f' "skeleton": [\n{_rows(proxy.skeleton)}],\n',
        f' "limb_rotations": [\n{_rows(proxy.limb_rotations)}],\n',
        ' "radii": null}\n' if proxy.radii is None else f' "radii": [\n{_rows(proxy.radii)}]}}\n',
    ]
    write_text(path, "".join(parts))


def _check_forest(path: Path, names: tuple[str, ...], parents: NDArray[np.int64]) -> None:
    """Refuse parents that loop (a marker its own ancestor), naming a marker on the loop."""
    depth = np.zeros(len(names), dtype=np.int64)  # 0: not yet known to reach a root
    for start in range(len(names)):
        chain: list[int] = []
        seen: set[int] = set()
        n = start
        while n >= 0 and depth[n] == 0:
            if n in seen:
                raise ProxyError(f"{path}: the parents loop through marker {names[n]!r}; every chain of "
                                 "parents must end at a root (null)")
            chain.append(n)
            seen.add(n)
            n = int(parents[n])
        reached = 0 if n < 0 else int(depth[n])
        for step, m in enumerate(reversed(chain), start=1):
            depth[m] = reached + step


def _dump(array: NDArray[np.float64]) -> str:
    # tolist() gives Python floats, whose JSON form is their repr: the shortest exact digits.
    return json.dumps(array.tolist(), separators=(",", ":"))


def _rows(array: NDArray[np.float64]) -> str:
    """One line per frame (the first axis)."""
    return ",\n".join(" " + _dump(frame) for frame in array)


def _frames(path: Path, key: str, frames: list[list[tuple[float, ...]]], T: int, count: int
            ) -> NDArray[np.float64]:
    """A per-frame list as a ``(T, count, width)`` array, after checking its lengths."""
    if len(frames) != T:
        raise ProxyError(f"{path}: '{key}' has {len(frames)} frames but the camera has {T}; give one "
                         "row per frame")
    what = "markers" if key in ("points", "skeleton") else "limbs"
    for t, frame in enumerate(frames):
        if len(frame) != count:
            raise ProxyError(f"{path}: '{key}' frame {t} has {len(frame)} entries for the {count} {what}")
    width = {"limb_rotations": 4, "radii": 2}.get(key, 3)
    return np.array(frames, dtype=float).reshape(T, count, width)
