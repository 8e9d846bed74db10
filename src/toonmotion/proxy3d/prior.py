"""The motion prior (section 3.1.2): a motion-capture segment's joints matched to the markers.

A :class:`Prior` is the 3D counterpart of :class:`~toonmotion.proxy3d.markers.Markers`: the
same names, in the same order, with 3D positions ``(T, N, 3)`` and the marker hierarchy read from
the mocap skeleton (each marker's parent is the nearest of its joint's ancestors that is also a
marker). It is built from a BVH clip (:func:`prior_from_bvh`), whose joints are matched to
the markers by name: a marker called after one of the package's standard joints (``hips``,
``left_elbow``, ..., :data:`~toonmotion.capture.mocap.STANDARD_JOINTS`) finds its joint through
the CMU, FAIR, Mixamo and Rokoko naming conventions (:func:`~toonmotion.capture.mocap.pick_joints`);
any other marker must be named like a joint of the clip or mapped to one explicitly.

Frames: positions are turned so that the clip's up axis is +Y (a rotation; right-handed, like
BVH), in the clip's own units; :func:`prior_in_metres` converts them and puts the ground at
Y = 0. :func:`resample_prior` brings a prior to the drawing's frame rate by linear interpolation
of positions between frames, and of the joints' turns by normalised quaternion interpolation (at
mocap rates of 30-120 fps a frame's chord is short and the error small).
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

from toonmotion import limits
from toonmotion.capture.bvh_kinematics import BvhClip, forward_kinematics, world_rotations
from toonmotion.capture.mocap import STANDARD_JOINTS, pick_joints
from toonmotion.errors import MotionError, ProxyError
from toonmotion.geometry.arrays import frame_rate, frozen_array

_AXES = {"x": 0, "y": 1, "z": 2}
# Rotations taking each signed world axis to +Y (row vectors: p @ M.T); proper rotations only.
_TO_Y_UP = {
    "+y": np.eye(3),
    "-y": np.diag([1.0, -1.0, -1.0]),                               # 180 degrees about X
    "+z": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),          # -90 degrees about X
    "-z": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),          # +90 degrees about X
    "+x": np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]),          # +90 degrees about Z
    "-x": np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]]),          # -90 degrees about Z
}


@dataclass(frozen=True, eq=False)
class Prior:
    """A 3D motion prior matched to the markers.

    Attributes
    ----------
    names : tuple of str
        The markers' names, in the markers' column order.
    parents : (N,) int
        Each marker's parent marker (index into ``names``), -1 for a root; from the mocap
        skeleton's hierarchy.
    positions : (T, N, 3) float
        World positions, right-handed, +Y up, in the mocap's units.
    fps : float
        Frames per second.
    joints : tuple of str
        The mocap joint each marker was matched to (for reports).
    turns : (T, N, 4) float or None
        For each marker, the world rotation (a unit quaternion ``(x, y, z, w)``) of the mocap
        joint that turns it: its joint's parent joint, or a root's own. It carries the twist
        about a limb that positions cannot show (the skeleton proxy's yaw, 3.4.3). None for a
        prior built from positions alone.

    Construction copies the arrays (read-only) and raises :class:`ProxyError` unless the
    positions are finite ``(T, N, 3)`` with ``T >= 1`` and the parents a forest over the names.
    """

    names: tuple[str, ...]
    parents: NDArray[np.int64]
    positions: NDArray[np.float64]
    fps: float
    joints: tuple[str, ...] = ()
    turns: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        names = tuple(self.names)
        N = len(names)
        if N == 0 or len(set(names)) != N:
            raise ProxyError("a prior needs distinct marker names, at least one")
        parents = frozen_array(self.parents, dtype=np.int64, shape=(N,), name="the prior's parents",
                               error=ProxyError)
        if np.any((parents < -1) | (parents >= N)) or np.any(parents == np.arange(N)):
            raise ProxyError("the prior's parents must be -1 or the index of another marker")
        _depths(parents)  # refuses a cycle
        positions = frozen_array(self.positions, dtype=np.float64, name="the prior's positions",
                                 error=ProxyError, finite=True)
        if positions.ndim != 3 or positions.shape[1:] != (N, 3) or len(positions) == 0:
            raise ProxyError(f"a prior needs positions of shape (frames, {N}, 3), got {positions.shape}")
        joints = tuple(self.joints) or names
        if len(joints) != N:
            raise ProxyError(f"a prior needs one mocap joint name per marker, got {len(joints)} for {N}")
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "fps", frame_rate(self.fps, name="the prior's fps", error=ProxyError))
        object.__setattr__(self, "joints", joints)
        if self.turns is not None:
            turns = frozen_array(self.turns, dtype=np.float64, name="the prior's turns", error=ProxyError,
                                 finite=True)
            if turns.shape != positions.shape[:2] + (4,):
                raise ProxyError(f"a prior's turns must have shape {positions.shape[:2] + (4,)}, got "
                                 f"{turns.shape}")
            object.__setattr__(self, "turns", turns)

    @property
    def frame_count(self) -> int:
        """Number of frames, ``T``."""
        return len(self.positions)

    @property
    def limbs(self) -> NDArray[np.int64]:
        """Limbs as ``(parent, child)`` marker indices, ``(K, 2)``, parents before children.

        A limb is a marker with its parent; the order is by depth from the roots, so a limb's
        parent limb comes before it.
        """
        child = [int(c) for c in _parents_first(self.parents) if self.parents[c] >= 0]
        return np.array([[self.parents[c], c] for c in child], dtype=np.int64).reshape(-1, 2)


def prior_from_bvh(
    clip: BvhClip,
    names: Sequence[str],
    *,
    joint_map: Mapping[str, str] | None = None,
    up: str | None = None,
    start: int = 0,
    stop: int | None = None,
) -> Prior:
    """Match a BVH clip's joints to markers and read their 3D positions.

    Parameters
    ----------
    clip : BvhClip
        From :func:`toonmotion.io.bvh.load_bvh`.
    names : sequence of str
        The markers' names (``Markers.names``): each is looked up in ``joint_map``, else, when it
        is a standard joint name, by the naming conventions, else as a joint name of the clip.
    joint_map : dict, optional
        Marker name -> mocap joint name, for markers named otherwise.
    up : {"x", "y", "z", "-x", "-y", "-z"}, optional
        The clip's up axis. Default: the axis along which the head is farthest above the feet
        (when the clip's standard joints can be found), else +Y, BVH's usual.
    start, stop : int
        The segment of the clip to use, as a slice of its frames (CMU clips open with a
        T-pose frame: ``start=1`` leaves it out).

    Returns
    -------
    Prior
        At the clip's frame rate; resample it with :func:`resample_prior`.

    Raises
    ------
    ProxyError
        Some markers have no joint in the clip (the message names them and lists the joints),
        two markers map to one joint, the map names a joint the clip lacks or a marker that is not
        among ``names`` (either with the closest name, if any), or the segment is empty.

    Examples
    --------
    >>> clip = BvhClip(names=("Hips", "Knee", "Knee_end"), parents=np.array([-1, 0, 1]),
    ...                offsets=np.array([[0.0, 0, 0], [0, -5, 0], [0, -5, 0]]),
    ...                channels=(("Xposition", "Yposition", "Zposition"), ("Xrotation",), ()),
    ...                motion=np.array([[0, 10, 0, 0], [1, 10, 0, 90]]), frame_time=0.1)
    >>> prior = prior_from_bvh(clip, ["pelvis", "foot"], joint_map={"pelvis": "Hips", "foot": "Knee_end"})
    >>> prior.parents.tolist(), prior.positions[1].round(9).tolist()
    ([-1, 0], [[1.0, 10.0, 0.0], [1.0, 5.0, -5.0]])
    """
    names = [str(n) for n in names]
    joint_map = dict(joint_map or {})
    strays = [m for m in joint_map if m not in names]
    if strays:  # a misspelt marker would otherwise be mapped to nothing, silently
        raise ProxyError(f"the joint map (--map) names the marker {strays[0]!r}, which is not one of the "
                         f"markers{_did_you_mean(strays[0], names)}; the markers are: {', '.join(names)}")
    unknown = [j for j in joint_map.values() if j not in clip.names]
    if unknown:
        raise ProxyError(f"the joint map names {unknown[0]!r}, which the mocap clip does not have"
                         f"{_did_you_mean(unknown[0], clip.names)}; its joints are: {', '.join(clip.names)}")
    standard = _standard_picks(clip)
    found: list[int | None] = []
    for name in names:
        if name in joint_map:
            found.append(clip.names.index(joint_map[name]))
        elif name in standard:
            found.append(standard[name])
        elif name in clip.names:
            found.append(clip.names.index(name))
        else:
            found.append(None)
    missing = [n for n, j in zip(names, found, strict=True) if j is None]
    if missing:
        raise ProxyError(
            f"the motion prior lacks the marker{'s' if len(missing) > 1 else ''} {_some(missing)}: name "
            f"markers after standard joints ({_some(STANDARD_JOINTS)}) or the clip's joints "
            f"({_some(clip.names)}), or map them to joints (--map MARKER=JOINT)"
        )
    index = [int(j) for j in found if j is not None]
    if len(set(index)) != len(index):
        twice = next(j for j in index if index.count(j) > 1)
        both = [n for n, j in zip(names, index, strict=True) if j == twice]
        raise ProxyError(f"markers {both[0]!r} and {both[1]!r} both match the mocap joint "
                         f"{clip.names[twice]!r}; map each marker to its own joint")
    segment = range(clip.frame_count)[start:stop]
    if len(segment) == 0:
        raise ProxyError(f"the prior's segment {start}:{stop} holds none of the clip's {clip.frame_count} "
                         "frames")
    every = forward_kinematics(clip)
    axis = _auto_up(every, standard) if up is None else _axis(up)
    to_up = _TO_Y_UP[axis]
    positions = every[segment.start:segment.stop][:, index] @ to_up.T
    turning = [int(clip.parents[j]) if clip.parents[j] >= 0 else j for j in index]
    world = world_rotations(clip)[segment.start:segment.stop][:, turning]
    turns = Rotation.from_matrix(to_up @ world.reshape(-1, 3, 3)).as_quat().reshape(world.shape[:2] + (4,))
    return Prior(names=tuple(names), parents=_marker_parents(clip.parents, index), positions=positions,
                 fps=clip.fps, joints=tuple(clip.names[j] for j in index), turns=turns)


def resample_prior(prior: Prior, fps: float) -> Prior:
    """The prior at another frame rate, by linear interpolation of positions between frames.

    Frame ``k`` of the result is the prior at time ``k / fps``, for every such time within the
    prior's duration ``(T - 1) / prior.fps``.

    Examples
    --------
    >>> p = Prior(("a",), [-1], np.array([[[0.0, 0, 0]], [[1.0, 0, 0]], [[2.0, 0, 0]]]), fps=4)
    >>> r = resample_prior(p, 8)
    >>> r.positions[:, 0, 0].tolist(), r.fps
    ([0.0, 0.5, 1.0, 1.5, 2.0], 8.0)
    """
    rate = frame_rate(fps, name="the drawing's fps", error=ProxyError)
    duration = (prior.frame_count - 1) / prior.fps
    count = int(np.floor(duration * rate + 1e-9)) + 1
    limits.check("frames", count, "the resampled prior's frame count")
    times = np.arange(count) * (prior.fps / rate)  # in the prior's frames
    return at_times(prior, times, rate)


def at_times(prior: Prior, times: ArrayLike, fps: float) -> Prior:
    """The prior at fractional frame numbers ``times``, as a prior at ``fps``.

    Positions are interpolated linearly, turns by normalised linear interpolation of quaternions
    (each frame's taken on the same side as the previous one's).

    >>> p = Prior(("a",), [-1], np.array([[[0.0, 0, 0]], [[2.0, 0, 0]]]), fps=4)
    >>> at_times(p, [0.5], 4).positions.tolist()
    [[[1.0, 0.0, 0.0]]]
    """
    turns = None
    if prior.turns is not None:
        q = prior.turns.copy()
        for t in range(1, len(q)):  # q and -q are one rotation: keep neighbours on one side
            q[t] *= np.where((q[t] * q[t - 1]).sum(-1) < 0, -1.0, 1.0)[:, None]
        turns = sample_frames(q, times)
        turns /= np.linalg.norm(turns, axis=-1, keepdims=True)
    return Prior(prior.names, prior.parents, sample_frames(prior.positions, times), fps, prior.joints, turns)


def sample_frames(positions: ArrayLike, times: ArrayLike) -> NDArray[np.float64]:
    """``positions`` ``(T, ...)`` at fractional frame numbers ``times`` ``(n,)``, linearly.

    Times are clamped to ``[0, T - 1]``.

    >>> sample_frames(np.array([0.0, 10.0, 20.0]), [0.25, 1.5, 9]).tolist()
    [2.5, 15.0, 20.0]
    """
    P = np.asarray(positions, dtype=float)
    t = np.clip(np.asarray(times, dtype=float), 0, len(P) - 1)
    below = np.minimum(np.floor(t).astype(np.int64), len(P) - 1)
    above = np.minimum(below + 1, len(P) - 1)
    w = (t - below).reshape((-1,) + (1,) * (P.ndim - 1))
    return P[below] * (1 - w) + P[above] * w


# -- helpers ---------------------------------------------------------------------------------


def _standard_picks(clip):
    try:
        return pick_joints(clip.names, clip.parents)
    except MotionError:
        return {}  # the clip does not follow a known convention: only its own names match


def _auto_up(world, standard):
    """The signed axis along which the head is farthest above the feet over the clip (as
    :func:`toonmotion.capture.mocap.project_orthographic` finds it); +Y without standard joints."""
    if not standard:
        return "+y"
    feet = world[:, [standard["left_foot"], standard["right_foot"]]].mean(axis=1)
    rise = (world[:, standard["head"]] - feet).mean(axis=0)
    axis = int(np.argmax(np.abs(rise)))
    return ("+" if rise[axis] >= 0 else "-") + "xyz"[axis]


def _axis(value):
    text = str(value).strip().lower()
    if text.lstrip("+-") not in _AXES or text.count("-") + text.count("+") > 1:
        raise ProxyError(f"up must be one of x, y, z, -x, -y, -z, got {value!r}")
    return ("-" if text.startswith("-") else "+") + text.lstrip("+-")


def _marker_parents(joint_parents, index):
    """Each marker's nearest ancestor joint that is also a marker (as a marker index), or -1."""
    marker_of = {j: m for m, j in enumerate(index)}
    parents = []
    for j in index:
        p = int(joint_parents[j])
        while p >= 0 and p not in marker_of:
            p = int(joint_parents[p])
        parents.append(marker_of.get(p, -1))
    return np.array(parents, dtype=np.int64)


def _depths(parents):
    """Each marker's number of ancestors; ProxyError on a cycle."""
    depth = np.full(len(parents), -1)
    for m in range(len(parents)):
        chain, p = [m], int(parents[m])
        while p >= 0 and depth[p] < 0:
            if p in chain:
                raise ProxyError("the prior's parents form a cycle; a marker cannot be its own ancestor")
            chain.append(p)
            p = int(parents[p])
        base = depth[p] if p >= 0 else -1
        for k, c in enumerate(reversed(chain)):
            depth[c] = base + 1 + k
    return depth


def _parents_first(parents):
    """Marker indices ordered by depth (stable), so every parent comes before its children."""
    return np.argsort(_depths(parents), kind="stable")


# Metres per unit of the units motion-capture files are written in; "cmu" is the CMU database's
# BVH unit (its ASF length scale 0.45: 1/0.45 inch).
UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254, "cmu": 0.0254 / 0.45}
# What a standing adult's markers span from the lowest to the highest (ankle to head joint),
# metres: the height the unit guess aims at.
STANDING_SPAN = 1.5


def prior_in_metres(prior: Prior, units: float | str | None = None) -> tuple[Prior, float]:
    """The prior in metres with its ground at Y = 0, and the metres per unit used.

    BVH files do not say their unit. ``units`` gives it: metres per unit, or a name from
    :data:`UNITS`. Without it, the unit is guessed from the markers' vertical span (the median over
    frames of the highest minus the lowest marker): the named unit that makes that span
    nearest :data:`STANDING_SPAN` metres, if within 25 % of it; otherwise the prior is scaled to
    that span exactly (a figure of unknown units, or not a standing human -- give ``units``).
    The ground is the lowest marker over the whole clip, moved to Y = 0.

    Examples
    --------
    >>> p = Prior(("foot", "head"), [-1, 0], [[[0.0, 10, 0], [0, 160, 0]]], fps=12)
    >>> m, unit = prior_in_metres(p)
    >>> unit, m.positions[0].round(9).tolist()
    (0.01, [[0.0, 0.0, 0.0], [0.0, 1.5, 0.0]])
    >>> prior_in_metres(p, "inch")[1]
    0.0254
    """
    if units is None:
        span = float(np.median(np.ptp(prior.positions[..., 1], axis=1)))
        if not span > 0:
            raise ProxyError("the prior's markers have no height to guess its units from; give the units")
        unit, fit = min(((u, abs(np.log(span * u / STANDING_SPAN))) for u in UNITS.values()),
                        key=lambda a: a[1])
        scale = unit if fit <= np.log(1.25) else STANDING_SPAN / span
    elif isinstance(units, str):
        if units not in UNITS:
            raise ProxyError(f"unknown units {units!r}; give metres per unit or one of {', '.join(UNITS)}")
        scale = UNITS[units]
    else:
        scale = float(units)
        if not (np.isfinite(scale) and scale > 0):
            raise ProxyError(f"units must be a positive number of metres per unit, got {units!r}")
    positions = prior.positions * scale
    positions[..., 1] -= positions[..., 1].min()
    return Prior(prior.names, prior.parents, positions, prior.fps, prior.joints, prior.turns), scale


def _did_you_mean(name, choices):
    """``" (did you mean 'x'?)"`` for the choice closest to a misspelt name, else ``""``.

    >>> _did_you_mean("left_hnd", ["left_hand", "right_hand"]), _did_you_mean("ghost", ["hips"])
    (" (did you mean 'left_hand'?)", '')
    """
    close = difflib.get_close_matches(name, [str(c) for c in choices], n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def _some(names, shown=4):
    """The first ``shown`` of ``names`` and how many there are, for a message that fits a line."""
    names = list(names)
    if len(names) <= shown + 1:
        return ", ".join(names)
    return f"{', '.join(names[:shown])}, ... ({len(names)} in all)"
