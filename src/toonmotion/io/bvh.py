"""Biovision ``.bvh`` motion capture files: a joint hierarchy and one row of channels per frame.

Glossary: ``J`` joints (End Sites included), ``T`` frames, ``C`` channels in all. World
coordinates are the file's own: its units (often inches or centimetres) and its up axis
(usually +Y, sometimes +Z); nothing is converted.

Conventions, as BVH means them:

- Angles are degrees. A joint with channels ``Zrotation Yrotation Xrotation`` has the local
  rotation ``R = Rz @ Ry @ Rx`` (intrinsic, composed in the order listed) acting on column
  vectors; any order of the three is allowed, per joint.
- A joint sits at its OFFSET in its parent's frame. Position channels, on any joint, replace
  the matching OFFSET component, so a root's ``Xposition Yposition Zposition`` are where it is.
- ``End Site`` blocks are joints with no channels, named ``<parent>_end``. A joint with no
  OFFSET line sits at its parent.

The loader only reads; :func:`forward_kinematics` turns a clip into joint positions.
"""

import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from toonmotion.errors import MotionError

AXES = "XYZ"
CHANNEL_NAMES = tuple(f"{a}{kind}" for kind in ("position", "rotation") for a in AXES)
_CANONICAL = {name.lower(): name for name in CHANNEL_NAMES}
_FRAMES = re.compile(r"frames\s*:\s*(.*)", re.IGNORECASE)
_FRAME_TIME = re.compile(r"frame\s*time\s*:\s*(.*)", re.IGNORECASE)


@dataclass(frozen=True, eq=False)
class BvhClip:
    """A BVH file's contents, as plain arrays.

    Attributes
    ----------
    names : tuple of str
        Joint names in file order, parents first; End Sites are named ``<parent>_end``.
    parents : (J,) int
        Index of each joint's parent, -1 for a root (a file may have several ROOTs).
    offsets : (J, 3) float
        Rest offset of each joint from its parent, in the parent's frame (a root's own OFFSET).
    channels : tuple of tuple of str
        Each joint's channel names in file order, e.g. ``("Zrotation", "Yrotation",
        "Xrotation")``; ``()`` for End Sites.
    motion : (T, C) float
        The MOTION section: one row per frame, the joints' channels in file order.
    frame_time : float
        Seconds per frame.
    """

    names: tuple
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple
    motion: np.ndarray
    frame_time: float

    def __post_init__(self):
        channels = tuple(tuple(c) for c in self.channels)
        arrays = {
            "parents": np.array(self.parents, dtype=np.int64),
            "offsets": np.array(self.offsets, dtype=float),
            "motion": np.array(self.motion, dtype=float),
        }
        J, width = len(self.names), sum(len(c) for c in channels)
        if arrays["parents"].shape != (J,) or arrays["offsets"].shape != (J, 3) or len(channels) != J:
            raise MotionError(f"a BVH clip of {J} joints needs {J} parents, offsets and channel lists")
        if np.any((arrays["parents"] < -1) | (arrays["parents"] >= np.arange(J))):
            raise MotionError("a BVH clip lists parents first: each parent index must be -1 or smaller")
        if arrays["motion"].ndim != 2 or arrays["motion"].shape[1] != width:
            raise MotionError(
                f"a BVH clip with {width} channels needs motion of shape (frames, {width}), "
                f"got {arrays['motion'].shape}"
            )
        object.__setattr__(self, "names", tuple(self.names))
        object.__setattr__(self, "channels", channels)
        for field, array in arrays.items():
            array.setflags(write=False)
            object.__setattr__(self, field, array)
        object.__setattr__(self, "frame_time", float(self.frame_time))

    @property
    def fps(self):
        """Frames per second, ``1 / frame_time``."""
        return 1.0 / self.frame_time

    @property
    def frame_count(self):
        return len(self.motion)


def load_bvh(path):
    """Read a ``.bvh`` file.

    Tokens may be separated by any whitespace (tabs, CRLF line ends); channel orders may
    differ from joint to joint.

    Returns
    -------
    BvhClip

    Raises
    ------
    MotionError
        The file is missing or unreadable, is not BVH, or is malformed: unbalanced braces, an
        unknown channel, a ``Frames:`` count that disagrees with the rows, a row with the wrong
        number of values or a value that is not a number, a missing or non-positive
        ``Frame Time``. The message names the file and, where it helps, the line.
    """
    path = Path(path)
    try:
        text = path.read_bytes().decode("utf-8-sig")
    except FileNotFoundError:
        raise MotionError(f"cannot read {path}: no such file") from None
    except IsADirectoryError:
        raise MotionError(f"cannot read {path}: it is a folder, not a BVH file") from None
    except OSError as error:
        raise MotionError(f"cannot read {path}: {error.strerror or error}") from None
    except UnicodeDecodeError:
        raise MotionError(f"{path} is not a BVH file: it is not text") from None
    return _parse(text.splitlines(), str(path))


def forward_kinematics(clip):
    """World positions of every joint at every frame.

    Vectorised over frames: one pass over the joints, parents first, each step a batch of
    ``(T, 3, 3)`` matrix products.

    Parameters
    ----------
    clip : BvhClip

    Returns
    -------
    (T, J, 3) float
        Joint positions in the file's world frame and units.

    Examples
    --------
    A root turned 90 degrees about Z carries its child's offset from +X to +Y:

    >>> clip = BvhClip(names=("root", "root_end"), parents=np.array([-1, 0]),
    ...                offsets=np.array([[0.0, 0, 0], [1, 0, 0]]),
    ...                channels=(("Zrotation",), ()), motion=np.array([[90.0]]), frame_time=0.04)
    >>> forward_kinematics(clip).round(12)[0].tolist()
    [[0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    """
    T = clip.frame_count
    starts = np.cumsum([0] + [len(c) for c in clip.channels])
    world_R, world_p = [], []
    for j, channels in enumerate(clip.channels):
        values = clip.motion[:, starts[j]:starts[j + 1]]
        local_R, local_t = _local_transform(channels, values, clip.offsets[j], T)
        p = clip.parents[j]
        if p < 0:
            R = np.broadcast_to(np.eye(3), (T, 3, 3)) if local_R is None else local_R
            position = np.broadcast_to(local_t, (T, 3))
        else:
            R = world_R[p] if local_R is None else world_R[p] @ local_R
            # (T,3,3) @ (3,) or (T,3,3) @ (T,3,1): the offset turned into the world frame.
            turned = world_R[p] @ local_t if local_t.ndim == 1 else (world_R[p] @ local_t[..., None])[..., 0]
            position = world_p[p] + turned
        world_R.append(R)
        world_p.append(position)
    if not world_p:
        return np.zeros((T, 0, 3))
    return np.stack(world_p, axis=1)


def _local_transform(channels, values, offset, T):
    """A joint's local rotation ``(T, 3, 3)`` (None if it has none) and translation ``(3,)`` or
    ``(T, 3)``, from its channel names and ``(T, n)`` channel values."""
    R = None
    t = offset
    for k, name in enumerate(channels):
        axis = AXES.index(name[0])
        if name.endswith("position"):
            if t.ndim == 1:
                t = np.repeat(offset[None], T, axis=0)
            t[:, axis] = values[:, k]
        else:
            step = _axis_rotation(axis, np.radians(values[:, k]))
            R = step if R is None else R @ step
    return R, t


def _axis_rotation(axis, angle):
    """``(T, 3, 3)`` rotations by ``angle`` (T,) radians about ``axis`` (0, 1, 2 = X, Y, Z)."""
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    R = np.zeros((len(angle), 3, 3))
    R[:, axis, axis] = 1.0
    R[:, i, i] = c
    R[:, j, j] = c
    R[:, i, j] = -s
    R[:, j, i] = s
    return R


# -- parsing ---------------------------------------------------------------------------------


def _parse(lines, where):
    """A :class:`BvhClip` from the file's lines; ``where`` names the file in errors."""
    tokens, motion_at = _hierarchy_tokens(lines, where)
    names, parents, offsets, channels = _hierarchy(tokens, where)
    motion, frame_time = _motion(lines, motion_at, sum(len(c) for c in channels), where)
    return BvhClip(
        names=tuple(names),
        parents=np.array(parents, dtype=np.int64),
        offsets=np.array(offsets, dtype=float).reshape(-1, 3),
        channels=tuple(channels),
        motion=motion,
        frame_time=frame_time,
    )


def _hierarchy_tokens(lines, where):
    """``(token, line number)`` pairs from HIERARCHY up to MOTION, and MOTION's line index."""
    tokens = []
    started = False
    for i, line in enumerate(lines):
        words = line.split()
        if not words:
            continue
        if not started:
            if words[0].upper() != "HIERARCHY":
                raise MotionError(f"{where} is not a BVH file: it does not start with HIERARCHY")
            started = True
            words = words[1:]
        if words and words[0].upper() == "MOTION":
            return tokens, i
        tokens.extend((word, i + 1) for word in words)
    if not started:
        raise MotionError(f"{where} is not a BVH file: it is empty")
    raise MotionError(f"{where} has no MOTION section after its HIERARCHY")


def _hierarchy(tokens, where):
    """Joint names (None for End Sites, named later), parents, offsets and channels."""
    names, parents, offsets, channels, opened_at = [], [], [], [], []
    stack = []  # indices of the joints whose braces are open
    k = 0

    def take(what):
        nonlocal k
        if k >= len(tokens):
            line = tokens[-1][1] if tokens else 1
            raise MotionError(f"{where}, line {line}: the HIERARCHY ends where {what} was expected")
        k += 1
        return tokens[k - 1]

    def number(what):
        word, line = take(what)
        try:
            value = float(word)
        except ValueError:
            raise MotionError(f"{where}, line {line}: {what} must be a number, got {word!r}") from None
        if not np.isfinite(value):
            raise MotionError(f"{where}, line {line}: {what} must be finite, got {word!r}")
        return value

    while k < len(tokens):
        word, line = take("a keyword")
        key = word.upper()
        if key in ("ROOT", "JOINT") or (key == "END" and k < len(tokens) and tokens[k][0].upper() == "SITE"):
            if key == "ROOT" and stack:
                raise MotionError(f"{where}, line {line}: ROOT inside another joint; is a '}}' missing?")
            if key != "ROOT" and not stack:
                raise MotionError(f"{where}, line {line}: {word} outside any ROOT; is a '{{' missing?")
            if stack and names[stack[-1]] is None:
                raise MotionError(f"{where}, line {line}: an End Site cannot have children")
            if key == "END":
                take("Site")
                name = None
            else:
                # A name is the rest of its line (names may hold spaces), up to a '{'.
                name_words = []
                while k < len(tokens) and tokens[k][1] == line and tokens[k][0] != "{":
                    name_words.append(take("a name")[0])
                if not name_words:
                    raise MotionError(f"{where}, line {line}: {word} has no joint name")
                name = " ".join(name_words)
                if name in names:
                    raise MotionError(
                        f"{where}, line {line}: joint name {name!r} is used twice; names must be unique"
                    )
            brace, brace_line = take("'{'")
            if brace != "{":
                raise MotionError(f"{where}, line {brace_line}: expected '{{' after {word}, got {brace!r}")
            names.append(name)
            parents.append(stack[-1] if stack else -1)
            offsets.append((0.0, 0.0, 0.0))
            channels.append(())
            opened_at.append(brace_line)
            stack.append(len(names) - 1)
        elif key == "}":
            if not stack:
                raise MotionError(f"{where}, line {line}: unbalanced braces: a '}}' closes nothing")
            stack.pop()
        elif key == "OFFSET":
            if not stack:
                raise MotionError(f"{where}, line {line}: OFFSET outside any joint")
            offsets[stack[-1]] = tuple(number(f"OFFSET {a}") for a in AXES)
        elif key == "CHANNELS":
            if not stack or names[stack[-1]] is None:
                raise MotionError(f"{where}, line {line}: CHANNELS outside a joint (End Sites have none)")
            count, count_line = take("the channel count")
            if not count.isdigit():
                raise MotionError(
                    f"{where}, line {count_line}: CHANNELS must be followed by a count, got {count!r}"
                )
            listed = []
            for _ in range(int(count)):
                channel, channel_line = take(f"{count} channel names")
                if channel.lower() not in _CANONICAL:
                    raise MotionError(
                        f"{where}, line {channel_line}: unknown channel {channel!r}; BVH channels are "
                        f"{', '.join(CHANNEL_NAMES)}"
                    )
                listed.append(_CANONICAL[channel.lower()])
            if len(set(listed)) != len(listed):
                raise MotionError(f"{where}, line {line}: a channel is listed twice in {' '.join(listed)}")
            channels[stack[-1]] = tuple(listed)
        else:
            raise MotionError(f"{where}, line {line}: unexpected {word!r} in the HIERARCHY")
    if stack:
        raise MotionError(
            f"{where}: unbalanced braces: the '{{' of {names[stack[-1]] or 'an End Site'} "
            f"(line {opened_at[stack[-1]]}) is never closed"
        )
    if not names:
        raise MotionError(f"{where}: the HIERARCHY has no ROOT joint")
    return _name_end_sites(names, parents), parents, offsets, channels


def _name_end_sites(names, parents):
    """Name each End Site ``<parent>_end``, with a number added if that name is taken."""
    taken = {n for n in names if n is not None}
    out = []
    for name, parent in zip(names, parents, strict=True):
        if name is None:
            base = f"{out[parent]}_end"
            name, n = base, 1
            while name in taken:
                n += 1
                name = f"{base}{n}"
            taken.add(name)
        out.append(name)
    return out


def _motion(lines, motion_at, width, where):
    """The ``(T, width)`` MOTION rows and the frame time, checked against the header."""
    frames = frame_time = None
    i = motion_at + 1
    while i < len(lines) and (frames is None or frame_time is None):
        line = lines[i].strip()
        if line:
            if m := _FRAMES.fullmatch(line):
                frames = _header_number(m.group(1), "Frames:", int, where, i + 1)
            elif m := _FRAME_TIME.fullmatch(line):
                frame_time = _header_number(m.group(1), "Frame Time:", float, where, i + 1)
            else:
                break
        i += 1
    if frames is None:
        raise MotionError(f"{where}, line {motion_at + 1}: MOTION is not followed by a 'Frames: N' line")
    if frame_time is None:
        raise MotionError(f"{where}, line {motion_at + 1}: MOTION has no 'Frame Time: seconds' line")
    if frames < 0:
        raise MotionError(f"{where}: Frames: {frames} is negative")
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise MotionError(f"{where}: Frame Time: {frame_time:g} must be a number of seconds > 0")

    numbered = [(n + 1, line.split()) for n, line in enumerate(lines[i:], start=i) if line.strip()]
    for line_number, row in numbered:
        if len(row) != width:
            raise MotionError(
                f"{where}, line {line_number}: {len(row)} values in a frame, but the HIERARCHY "
                f"has {width} channels"
            )
    if len(numbered) != frames and width > 0:
        raise MotionError(
            f"{where}: the header says Frames: {frames} but {len(numbered)} rows of values follow"
        )
    try:
        motion = np.array([v for _, row in numbered for v in row], dtype=float)
    except ValueError:
        for line_number, row in numbered:
            for v in row:
                try:
                    float(v)
                except ValueError:
                    raise MotionError(f"{where}, line {line_number}: {v!r} is not a number") from None
        raise  # pragma: no cover - some value above failed
    motion = motion.reshape(frames, width)
    if not np.all(np.isfinite(motion)):
        row = int(np.flatnonzero(~np.isfinite(motion).all(axis=1))[0])
        raise MotionError(f"{where}, line {numbered[row][0]}: a value is not finite (nan or inf)")
    return motion, frame_time


def _header_number(text, label, kind, where, line):
    try:
        return kind(text.strip())
    except ValueError:
        raise MotionError(
            f"{where}, line {line}: {label} must be followed by a number, not {text!r}"
        ) from None
