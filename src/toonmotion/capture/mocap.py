"""From 3D motion capture to 2D joints: pick a standard skeleton, project it, fit it to a frame.

No file IO here. With a BVH clip (read by ``toonmotion.io.bvh.load_bvh``, forward kinematics in
:mod:`toonmotion.capture.bvh_kinematics`)::

    clip = load_bvh(path)
    picks = pick_joints(clip.names, clip.parents)            # standard name -> joint index
    P = forward_kinematics(clip)[:, list(picks.values())]    # (T, 16, 3), STANDARD_JOINTS order
    xy = fit_to_frame(project_orthographic(P), (640, 480))   # (T, 16, 2) pixels, y down

Frames: 3D positions are in the mocap's world frame (its units, its up axis, right-handed as
BVH is); 2D points are ``(x, y)`` with x right and y DOWN, like image pixels.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import Literal, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.errors import MotionError, SettingsError

STANDARD_JOINTS = (
    "hips", "spine", "neck", "head",
    "left_shoulder", "left_elbow", "left_hand",
    "right_shoulder", "right_elbow", "right_hand",
    "left_hip", "left_knee", "left_foot",
    "right_hip", "right_knee", "right_foot",
)
_PARENTS = {
    "hips": None, "spine": "hips", "neck": "spine", "head": "neck",
    "left_shoulder": "neck", "left_elbow": "left_shoulder", "left_hand": "left_elbow",
    "right_shoulder": "neck", "right_elbow": "right_shoulder", "right_hand": "right_elbow",
    "left_hip": "hips", "left_knee": "left_hip", "left_foot": "left_knee",
    "right_hip": "hips", "right_knee": "right_hip", "right_foot": "right_knee",
}

# Limb joints by their usual names (after the side is taken off), best first. "arm" is the
# upper-arm joint (CMU, Mixamo, FAIR, Rokoko), so it wins over "shoulder", which there is the
# clavicle; where no "arm" exists, "shoulder" is the shoulder joint (older CMU: LeftCollar,
# LeftShoulder, LeftElbow, LeftWrist). Likewise "leg" is the knee beside "upleg".
_LIMBS = {
    "shoulder": ("arm", "upperarm", "uparm", "humerus", "shoulder"),
    "elbow": ("forearm", "lowerarm", "elbow", "loarm"),
    "hand": ("wrist", "hand"),
    "hip": ("upleg", "upperleg", "thigh", "hip", "femur"),
    "knee": ("leg", "lowerleg", "knee", "shin", "calf", "loleg"),
    "foot": ("ankle", "foot"),
}
_LIMB_WORDS = frozenset(w for words in _LIMBS.values() for w in words)
_CHAINS = (("shoulder", "elbow"), ("elbow", "hand"), ("hip", "knee"), ("knee", "foot"))
# Rig prefixes: "mixamorig:" (any namespace before ':'), "mixamorig_", "Bip01 ", "Character1_".
_PREFIX = re.compile(r"^(mixamorig\d*_|bip\d+[\s_]*|character\d*_)", re.IGNORECASE)
_AXES = {"x": 0, "y": 1, "z": 2}


def standard_skeleton_parents() -> dict[str, str | None]:
    """Each of the :data:`STANDARD_JOINTS` and its parent's name (None for ``hips``).

    Examples
    --------
    >>> parents = standard_skeleton_parents()
    >>> parents["left_hand"], parents["left_shoulder"], parents["hips"]
    ('left_elbow', 'neck', None)
    """
    return dict(_PARENTS)


def find_joints(names: Sequence[str], parents: ArrayLike) -> dict[str, int | None]:
    """Find the 16 :data:`STANDARD_JOINTS` among a skeleton's joints, by name, as far as they go.

    Names are matched case-insensitively, with rig prefixes (``mixamorig:``, ``Bip01 ``) and
    separators ignored, and the side read from ``Left``/``Right``/``L``/``R`` before or after
    the name (``LeftForeArm``, ``l_elbow``, ``lowerarm_l``, ``ElbowLeft``). Conventions:

    - shoulder: the upper-arm joint (``LeftArm``, ``UpperArm``), else ``LeftShoulder``;
      elbow: ``ForeArm``/``LowerArm``/``Elbow``; hand: ``Wrist``, else ``Hand``.
    - hip: ``UpLeg``/``Thigh``/``Hip``; knee: ``Leg``/``Knee``/``Calf``; foot: ``Ankle``,
      else ``Foot``.
    - hips: ``Hips``/``Pelvis``; neck: ``Neck`` (not ``Neck1``); head: ``Head``.
    - spine: the middle joint of the chain strictly between hips and neck (``Spine``, ``Spine1``,
      ... or ``Chest``), skipping neck joints; so about halfway up the back.

    Parameters
    ----------
    names : sequence of str
        The joints' names, e.g. :attr:`BvhClip.names`.
    parents : (J,) int
        Each joint's parent index, -1 for a root.

    Returns
    -------
    dict
        Standard name -> joint index, or None where no joint matches, in
        :data:`STANDARD_JOINTS` order.

    Raises
    ------
    MotionError
        A limb's picks do not form a chain (an elbow not below its shoulder).
    """
    names = [str(n) for n in names]
    parents = np.asarray(parents, dtype=np.int64)
    if parents.shape != (len(names),):
        raise MotionError(f"give one parent per joint: {len(names)} names, parents of shape {parents.shape}")
    keys = [_side_and_word(n) for n in names]

    def find(side, words):
        for word in words:
            for j, key in enumerate(keys):
                if key == (side, word):
                    return j
        return None

    def find_like(test):
        return next((j for j, (side, word) in enumerate(keys) if not side and test(word)), None)

    picks = {}
    for side, prefix in (("l", "left_"), ("r", "right_")):
        for part, words in _LIMBS.items():
            picks[prefix + part] = find(side, words)
    picks["hips"] = find("", ("hips", "pelvis", "hip"))
    picks["neck"] = _first(find("", ("neck",)), find_like(lambda w: "neck" in w))
    picks["head"] = _first(
        find("", ("head",)),
        find_like(lambda w: w.startswith("head") and not w.endswith(("end", "top", "nub", "site"))),
    )
    picks["spine"] = _spine(picks["hips"], picks["neck"], parents, keys)

    for prefix in ("left_", "right_"):
        for upper, lower in _CHAINS:
            a, b = picks[prefix + upper], picks[prefix + lower]
            if a is not None and b is not None and not _is_below(parents, b, a):
                raise MotionError(
                    f"{prefix + lower} was matched to {names[b]!r}, which is not below "
                    f"{prefix + upper} ({names[a]!r}); the joint names do not follow a known convention"
                )
    return {n: picks[n] for n in STANDARD_JOINTS}


def pick_joints(names: Sequence[str], parents: ArrayLike) -> dict[str, int]:
    """Find the 16 :data:`STANDARD_JOINTS` among a mocap skeleton's joints, by name.

    As :func:`find_joints`, but every standard joint must be found.

    Raises
    ------
    MotionError
        Some standard joints have no match (the message names them and lists the joints), or
        a limb's picks do not form a chain (an elbow not below its shoulder).
    """
    picks = find_joints(names, parents)
    missing = [n for n in STANDARD_JOINTS if picks[n] is None]
    if missing:
        raise MotionError(
            f"cannot find the standard joint{'s' if len(missing) > 1 else ''} {', '.join(missing)} "
            f"among the mocap joints: {', '.join(str(n) for n in names)}"
        )
    return {n: int(j) for n, j in picks.items() if j is not None}


@overload
def project_orthographic(
    positions: ArrayLike, *, joints: Mapping[str, int] | None = None, up: ArrayLike | None = None,
    facing: ArrayLike | None = None, with_depth: Literal[False] = False,
) -> NDArray[np.float64]: ...


@overload
def project_orthographic(
    positions: ArrayLike, *, joints: Mapping[str, int] | None = None, up: ArrayLike | None = None,
    facing: ArrayLike | None = None, with_depth: Literal[True],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


def project_orthographic(
    positions: ArrayLike,
    *,
    joints: Mapping[str, int] | None = None,
    up: ArrayLike | None = None,
    facing: ArrayLike | None = None,
    with_depth: bool = False,
) -> NDArray[np.float64] | tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Look at 3D joints from in front of the character, orthographically.

    The camera looks at the character's chest from the side it faces, so nothing is
    mirrored: the character's left hand appears on the image's right, as a viewer facing them
    sees it. Image x runs along the character's left (the horizontal part of its shoulder
    line), image y runs down ``up``; depth is dropped. The origin is the world origin's
    projection: use :func:`fit_to_frame` to place the result.

    Parameters
    ----------
    positions : (T, J, 3) float
        World positions, any units.
    joints : dict, optional
        Standard joint name -> index along J (from :func:`pick_joints` when ``positions`` holds
        every mocap joint). Default: ``positions`` holds the :data:`STANDARD_JOINTS` in order.
        Used only to find ``up`` and ``facing`` when they are not given.
    up : {"x", "y", "z", "-x", "-y", "-z"} or (3,) float, optional
        The world's up direction. Default: the world axis along which the head is farthest
        above the feet, averaged over the clip (snapped to an axis, so a character who leans
        does not tilt the camera). BVH is usually +Y up; some files are +Z up.
    facing : same choices as ``up``, optional
        The direction the character faces (from it towards the camera). Default: horizontal
        and perpendicular to the shoulder line in the first frame, on the side where the
        shoulders read left-to-right as the viewer's right-to-left.
    with_depth : bool
        Also return each joint's distance from the camera along its view (larger is farther,
        world units, relative to the world origin), for drawing far to near.

    Returns
    -------
    (T, J, 2) float
        ``(x, y)``, x right and y down, in the world's units.
    depth : (T, J) float
        Only with ``with_depth``.

    Examples
    --------
    A Y-up character facing +Z; its left (+X) lands on the image's right, its head up top:

    >>> P = np.array([[[1.0, 1.0, 0.0], [0.0, 2.0, 0.0]]])
    >>> project_orthographic(P, up="y", facing="z").tolist()
    [[[1.0, -1.0], [0.0, -2.0]]]
    """
    P = np.asarray(positions, dtype=float)
    if P.ndim != 3 or P.shape[2] != 3 or len(P) == 0:
        raise MotionError(f"project_orthographic needs (frames, joints, 3) positions, got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise MotionError("project_orthographic: some joint positions are not finite")
    if up is None or facing is None:
        index = _standard_index(joints, P.shape[1])
    up_axis = _auto_up(P, index) if up is None else _direction(up, "up")
    if facing is None:
        # The character's left, in the first frame: the shoulder line, else the hip line.
        left = P[0, index["left_shoulder"]] - P[0, index["right_shoulder"]]
        if np.linalg.norm(np.cross(left, up_axis)) < 1e-9 * max(1.0, np.abs(P).max()):
            left = P[0, index["left_hip"]] - P[0, index["right_hip"]]
    else:
        # facing = left x up, so left = up x facing.
        left = np.cross(up_axis, _direction(facing, "facing"))
    across = left - (left @ up_axis) * up_axis
    norm = np.linalg.norm(across)
    if norm < 1e-9 * max(1.0, np.abs(P).max()):
        raise MotionError(
            "cannot tell which way the character faces: its shoulders and hips line up with the up "
            "axis in the first frame (or facing is parallel to up); give facing="
        )
    across /= norm
    points = np.stack([P @ across, -(P @ up_axis)], axis=-1)
    if not with_depth:
        return points
    toward_camera = np.cross(across, up_axis)  # facing = left x up
    return points, -(P @ toward_camera)


def fit_to_frame(
    points2d: ArrayLike, size: Sequence[float] = (640, 480), *, margin: float = 0.1
) -> NDArray[np.float64]:
    """Scale and move 2D points so that the whole clip fits inside a frame.

    One uniform scale (aspect kept) and one translation for every frame, so the motion itself
    is unchanged: the bounding box of all joints over all frames is centred in the frame and
    made as large as fits inside the frame less ``margin`` on each side. Y stays down.

    Parameters
    ----------
    points2d : (T, J, 2) float
        ``(x, y)`` points, y down, any units.
    size : (width, height)
        The frame, in pixels.
    margin : float
        Space kept clear on each side, as a fraction of the frame's width (left and right) and
        height (top and bottom); in ``[0, 0.5)``.

    Returns
    -------
    (T, J, 2) float
        Pixels, inside ``[margin * width, (1 - margin) * width]`` by ``[margin * height,
        (1 - margin) * height]``.

    Examples
    --------
    >>> fit_to_frame(np.array([[[0.0, 0.0], [1.0, 2.0]]]), (100, 100), margin=0.1).tolist()
    [[[30.0, 10.0], [70.0, 90.0]]]
    """
    P = np.asarray(points2d, dtype=float)
    if P.ndim != 3 or P.shape[2] != 2 or P.size == 0:
        raise MotionError(f"fit_to_frame needs (frames, joints, 2) points, got {P.shape}")
    if not np.all(np.isfinite(P)):
        raise MotionError("fit_to_frame: some points are not finite")
    try:
        frame = np.array([float(size[0]), float(size[1])])
    except (TypeError, ValueError, IndexError):
        raise SettingsError(f"size must be (width, height) in pixels, got {size!r}") from None
    if len(size) != 2 or not np.all(np.isfinite(frame) & (frame > 0)):
        raise SettingsError(f"size must be two numbers > 0 (width, height), got {size!r}")
    if not (isinstance(margin, (int, float, np.number)) and 0 <= margin < 0.5):
        raise SettingsError(f"margin must be a fraction in [0, 0.5), got {margin!r}")
    lo = P.min(axis=(0, 1))
    hi = P.max(axis=(0, 1))
    extent = hi - lo
    room = frame * (1 - 2 * margin)
    spread = extent > 0
    scale = float(np.min(room[spread] / extent[spread])) if spread.any() else 1.0
    return (P - (lo + hi) / 2) * scale + frame / 2


# -- helpers ---------------------------------------------------------------------------------


def _first(*candidates):
    return next((c for c in candidates if c is not None), None)


def _side_and_word(name):
    """``(side, word)`` of a joint name: side ``"l"``, ``"r"`` or ``""``; word lower-case,
    letters and digits only. ``"mixamorig:LeftForeArm"`` -> ``("l", "forearm")``."""
    s = _PREFIX.sub("", name.rsplit(":", 1)[-1].strip()).strip().lower()

    def squash(text):
        return re.sub(r"[\W_]+", "", text)

    for pattern in (r"(left|right)[\W_]*(.+)", r"([lr])[\W_]+(.+)"):
        if m := re.fullmatch(pattern, s):
            return m.group(1)[0], squash(m.group(2))
    for pattern in (r"(.+?)[\W_]*(left|right)", r"(.+?)[\W_]+([lr])"):
        if m := re.fullmatch(pattern, s):
            return m.group(2)[0], squash(m.group(1))
    word = squash(s)
    # A glued single letter only before a known limb word ("lhand", "RHip"), not "leg".
    if word[:1] in ("l", "r") and word[1:] in _LIMB_WORDS:
        return word[0], word[1:]
    return "", word


def _is_below(parents, joint, ancestor):
    """True when ``ancestor`` is a proper ancestor of ``joint``."""
    j = parents[joint]
    while j >= 0:
        if j == ancestor:
            return True
        j = parents[j]
    return False


def _spine(hips, neck, parents, keys):
    """The middle joint strictly between hips and neck, neck joints left out; else the middle
    one of the joints named like a spine."""
    chain = []
    if hips is not None and neck is not None and _is_below(parents, neck, hips):
        j = parents[neck]
        while j != hips:
            chain.append(j)
            j = parents[j]
        chain = [j for j in reversed(chain) if "neck" not in keys[j][1]]
    if not chain:
        chain = [j for j, (side, word) in enumerate(keys)
                 if not side and any(w in word for w in ("spine", "chest", "torso", "back"))]
    return chain[len(chain) // 2] if chain else None


def _standard_index(joints, count):
    if joints is None:
        if count != len(STANDARD_JOINTS):
            raise MotionError(
                f"positions have {count} joints, not the {len(STANDARD_JOINTS)} standard ones; pass "
                "joints= (from pick_joints) or give both up= and facing="
            )
        return {n: i for i, n in enumerate(STANDARD_JOINTS)}
    needed = ("head", "left_shoulder", "right_shoulder", "left_hip", "right_hip", "left_foot", "right_foot")
    absent = [n for n in needed if n not in joints or not 0 <= int(joints[n]) < count]
    if absent:
        raise MotionError(f"joints= has no valid index for {', '.join(absent)} among {count} joints")
    return {n: int(joints[n]) for n in needed}


def _auto_up(P, index):
    """The signed world axis along which the head is farthest above the feet, over the clip."""
    feet = (P[:, index["left_foot"]] + P[:, index["right_foot"]]) / 2
    rise = (P[:, index["head"]] - feet).mean(axis=0)
    axis = int(np.argmax(np.abs(rise)))
    if rise[axis] == 0:
        raise MotionError("cannot tell the up axis: the head is never away from the feet; give up=")
    up = np.zeros(3)
    up[axis] = np.sign(rise[axis])
    return up


def _direction(value, what):
    """A unit (3,) vector from ``"x"``, ``"-z"``, ... or three numbers."""
    if isinstance(value, str):
        text = value.strip().lower()
        sign = -1.0 if text.startswith("-") else 1.0
        axis = _AXES.get(text.lstrip("+-"))
        if axis is None or text.count("-") + text.count("+") > 1:
            raise SettingsError(f"{what} must be one of x, y, z, -x, -y, -z or three numbers, got {value!r}")
        vector = np.zeros(3)
        vector[axis] = sign
        return vector
    try:
        vector = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        vector = np.zeros(0)
    norm = np.linalg.norm(vector) if vector.shape == (3,) else 0.0
    if not (np.isfinite(norm) and norm > 0):
        raise SettingsError(f"{what} must be one of x, y, z, -x, -y, -z or three numbers, got {value!r}")
    return vector / norm
