"""Biovision ``.bvh`` motion capture files: a joint hierarchy and one row of channels per frame.

:func:`load_bvh` returns a :class:`~toonmotion.capture.bvh_kinematics.BvhClip` of plain arrays,
and :func:`toonmotion.capture.bvh_kinematics.forward_kinematics` turns that into joint
positions (the module states what the channels mean). :func:`save_bvh` writes a clip back.

Reading conventions:

- Channel names are matched case-insensitively; any order of the six is allowed, per joint.
- ``End Site`` blocks are joints with no channels, named ``<parent>_end``. A joint with no
  OFFSET line sits at its parent.

Writing conventions: joints depth first (each joint's children in the clip's order), one tab of
indent per level; a childless joint without channels whose name is the one the reader would give
an End Site there is written as an End Site, any other joint as ROOT or JOINT with its CHANNELS
line (``CHANNELS 0`` when it has none). Every number is written by ``repr``, the shortest text
that reads back as the same float, so a clip in depth-first order (every clip :func:`load_bvh`
returns is) reads back bit for bit.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from toonmotion import limits
from toonmotion.capture.bvh_kinematics import BvhClip, name_end_sites
from toonmotion.errors import MotionError
from toonmotion.io.atomic import write_text

AXES = "XYZ"
CHANNEL_NAMES = tuple(f"{a}{kind}" for kind in ("position", "rotation") for a in AXES)
_CANONICAL = {name.lower(): name for name in CHANNEL_NAMES}
_FRAMES = re.compile(r"frames\s*:\s*(.*)", re.IGNORECASE)
_FRAME_TIME = re.compile(r"frame\s*time\s*:\s*(.*)", re.IGNORECASE)


def load_bvh(path: str | os.PathLike[str]) -> BvhClip:
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
        limits.check("file_bytes", path.stat().st_size, f"{path.name}'s size in bytes")
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


def save_bvh(path: str | os.PathLike[str], clip: BvhClip) -> None:
    """Write ``clip`` to ``path`` as a ``.bvh`` file, atomically.

    Several roots, End Sites and any channel order per joint are kept; :func:`load_bvh` reads
    back the same names, parents, offsets, channels, motion and frame time, bit for bit, when the
    clip lists its joints depth first (a joint's subtree right after it), as every file does.
    Another order is written depth first and reads back in that order.

    Raises
    ------
    MotionError
        No joints, a name BVH cannot hold (empty, used twice, with whitespace other than single
        spaces inside, or a ``{`` word), an unknown or repeated channel, a value that is not finite, or
        a frame time that is not a positive number of seconds.

    Examples
    --------
    >>> import tempfile
    >>> clip = BvhClip(names=("hips", "knee", "knee_end"), parents=np.array([-1, 0, 1]),
    ...                offsets=np.array([[0.0, 0, 0], [0, -0.4, 0], [0, -0.45, 1e-17]]),
    ...                channels=(("Xposition", "Yposition", "Zposition"), ("Xrotation",), ()),
    ...                motion=np.array([[0.0, 0.9, 0.0, 12.5], [0.1, 0.9, 0.0, 1 / 3]]), frame_time=1 / 30)
    >>> path = Path(tempfile.mkdtemp()) / "clip.bvh"
    >>> save_bvh(path, clip)
    >>> print(path.read_text(), end="")  # doctest: +NORMALIZE_WHITESPACE
    HIERARCHY
    ROOT hips
    {
    \tOFFSET 0.0 0.0 0.0
    \tCHANNELS 3 Xposition Yposition Zposition
    \tJOINT knee
    \t{
    \t\tOFFSET 0.0 -0.4 0.0
    \t\tCHANNELS 1 Xrotation
    \t\tEnd Site
    \t\t{
    \t\t\tOFFSET 0.0 -0.45 1e-17
    \t\t}
    \t}
    }
    MOTION
    Frames: 2
    Frame Time: 0.03333333333333333
    0.0 0.9 0.0 12.5
    0.1 0.9 0.0 0.3333333333333333
    >>> back = load_bvh(path)
    >>> back.names == clip.names and np.array_equal(back.motion, clip.motion)
    True
    """
    write_text(path, _bvh_text(clip))


def _bvh_text(clip):
    """The text of a BVH file holding ``clip``."""
    names, J = clip.names, len(clip.names)
    if J == 0:
        raise MotionError("a BVH clip to write has no joints; BVH needs at least one ROOT")
    for name in names:
        if not isinstance(name, str) or name != " ".join(name.split()) or not name or "{" in name.split():
            raise MotionError(f"joint name {name!r} cannot be written to BVH: a name must be words separated "
                              "by single spaces, none of them '{'")
    if len(set(names)) != J:
        twice = next(n for n in names if names.count(n) > 1)
        raise MotionError(f"joint name {twice!r} is used twice; BVH joint names must be unique")
    for name, channels in zip(names, clip.channels, strict=True):
        if any(c not in CHANNEL_NAMES for c in channels) or len(set(channels)) != len(channels):
            raise MotionError(f"joint {name!r} has channels {' '.join(channels)}; BVH channels are "
                              f"{', '.join(CHANNEL_NAMES)}, each at most once per joint")
    if not (np.isfinite(clip.offsets).all() and np.isfinite(clip.motion).all()):
        raise MotionError("a BVH clip to write has an offset or a channel value that is not finite")
    if not (np.isfinite(clip.frame_time) and clip.frame_time > 0):
        raise MotionError(f"a BVH clip's frame time must be a number of seconds > 0, got {clip.frame_time!r}")
    children = [[] for _ in range(J)]
    for j, p in enumerate(clip.parents):
        if p >= 0:
            children[p].append(j)
    order, depth = [], {}
    for root in np.flatnonzero(clip.parents < 0):
        stack = [(int(root), 0)]
        while stack:
            j, d = stack.pop()
            order.append(j)
            depth[j] = d
            stack.extend((c, d + 1) for c in reversed(children[j]))
    ends = _end_sites(clip, order, children)
    lines = ["HIERARCHY"]
    closing = []  # (depth, joint) of the open blocks
    for j in order:
        d = depth[j]
        while closing and closing[-1] >= d:
            lines.append("\t" * closing.pop() + "}")
        tab = "\t" * d
        head = "End Site" if j in ends else ("ROOT " if clip.parents[j] < 0 else "JOINT ") + names[j]
        lines += [tab + head, tab + "{", tab + "\tOFFSET " + " ".join(map(repr, clip.offsets[j].tolist()))]
        if j not in ends:
            listed = "".join(f" {c}" for c in clip.channels[j])
            lines.append(f"{tab}\tCHANNELS {len(clip.channels[j])}{listed}")
        closing.append(d)
    lines += ["\t" * d + "}" for d in reversed(closing)]
    starts = np.cumsum([0] + [len(c) for c in clip.channels])
    columns = [k for j in order for k in range(starts[j], starts[j + 1])]
    lines += ["MOTION", f"Frames: {clip.frame_count}", f"Frame Time: {clip.frame_time!r}"]
    lines += [" ".join(map(repr, row)) for row in clip.motion[:, columns].tolist()]
    return "\n".join(lines) + "\n"


def _end_sites(clip, order, children):
    """The joints to write as End Sites: childless, without channels, and named as the reader
    would name them there (``<parent>_end``, a number added if taken)."""
    ends = {j for j in order if clip.parents[j] >= 0 and not children[j] and not clip.channels[j]}
    place = {j: n for n, j in enumerate(order)}
    while True:  # each pass drops the joints the reader would name otherwise; names settle
        read = name_end_sites([None if j in ends else clip.names[j] for j in order],
                               [place[clip.parents[j]] if clip.parents[j] >= 0 else -1 for j in order])
        wrong = {j for j, name in zip(order, read, strict=True) if j in ends and name != clip.names[j]}
        if not wrong:
            return ends
        ends -= wrong


# -- parsing ---------------------------------------------------------------------------------


def _parse(lines, where):
    """A :class:`BvhClip` from the file's lines; ``where`` names the file in errors."""
    tokens, motion_at = _hierarchy_tokens(lines, where)
    names, parents, offsets, channels = _hierarchy(tokens, where)
    limits.check("joints", len(names), f"{where}'s joint count (End Sites included)")
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
    return name_end_sites(names, parents), parents, offsets, channels


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
    limits.check("frames", frames, f"{where}'s frame count")
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
