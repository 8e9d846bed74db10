"""Built-in key-frames for the bundled sample character: crouch, hop, land and wave.

The poses are built from the character's own skeleton by turning limbs about their joints, so
they fit it at any scale. 36 frames at 12 fps: three seconds.
"""

from __future__ import annotations

import numpy as np

from toonmotion.animate.animation import Animation, animate_timeline
from toonmotion.animate.timeline import Keyframe, Timeline, make_timeline
from toonmotion.deform.deformer import Deformer
from toonmotion.rig.character import Character
from toonmotion.rig.pose import Pose, descendants, rotate_about
from toonmotion.rig.skeleton import Skeleton

_LEGS = ("right_knee", "right_foot", "left_knee", "left_foot")


def sample_keyframes(skeleton: Skeleton, *, fps: float = 12.0, ease: str = "in-out") -> Timeline:
    """Key-frames for the sample character's skeleton (see ``samples.sample_character``).

    Returns
    -------
    Timeline
        Keys at frames 0 (rest), 6 (crouch), 12 (in the air, arms up), 18 (landing crouch),
        24 and 30 (waving) and 36 (rest).

    Examples
    --------
    >>> from toonmotion.samples import sample_character
    >>> timeline = sample_keyframes(sample_character()[1])
    >>> [k.frame for k in timeline.keys], timeline.frame_count
    ([0, 6, 12, 18, 24, 30, 36], 37)
    """
    rest = skeleton.positions
    size = np.ptp(rest[:, 1])  # the figure's height, to scale every move
    crouch = _crouch(skeleton, rest, 0.08 * size)
    crouch = _arms(skeleton, crouch, -0.35)
    hop = _arms(skeleton, rest, 1.15)
    hop = _shift(skeleton, hop, -0.12 * size, legs_too=True)
    hop = rotate_about(skeleton, hop, "right_knee", 0.5)
    hop = rotate_about(skeleton, hop, "left_knee", -0.5)
    wave_a = rotate_about(skeleton, rest, "right_shoulder", 1.25)
    wave_a = rotate_about(skeleton, wave_a, "right_elbow", 0.5)
    wave_b = rotate_about(skeleton, wave_a, "right_elbow", -0.9)
    poses = {0: rest, 6: crouch, 12: hop, 18: crouch, 24: wave_a, 30: wave_b, 36: rest}
    keys = [Keyframe(frame, Pose(p)) for frame, p in poses.items()]
    return make_timeline(skeleton, keys, fps=fps, ease=ease)


def sample_animated() -> tuple[Character, Animation]:
    """The bundled character (``samples.sample_rig()``) animated through :func:`sample_keyframes`:
    a whole animation in one call, for trying an export or a renderer.

    Examples
    --------
    >>> hero, animation = sample_animated()
    >>> len(animation.meshes), animation.meshes[0][1].shape == hero.mesh.V.shape
    (37, True)
    """
    from toonmotion.samples import sample_rig

    hero = sample_rig()
    return hero, animate_timeline(Deformer(hero), sample_keyframes(hero.skeleton))


def _shift(skeleton, positions, dy, *, legs_too=False):
    out = np.array(positions, dtype=float)
    legs = {skeleton.index(n) for n in _LEGS}
    for j in range(len(skeleton)):
        if legs_too or j not in legs:
            out[j, 1] += dy
    return out


def _crouch(skeleton, positions, depth):
    """Lower the body by ``depth`` with the feet planted, bending the knees outwards."""
    out = _shift(skeleton, positions, depth)
    for side, outward in (("right", -1.0), ("left", 1.0)):
        hip, knee, foot = (skeleton.index(f"{side}_{j}") for j in ("hip", "knee", "foot"))
        thigh = np.linalg.norm(positions[knee] - positions[hip])
        shin = np.linalg.norm(positions[foot] - positions[knee])
        out[knee] = _knee(out[hip], out[foot], thigh, shin, outward)
        below = descendants(skeleton, foot)
        out[below] += out[foot] - positions[foot]
    return out


def _knee(hip, foot, thigh, shin, outward):
    """Where a knee goes between a hip and a foot (two-bone IK), bending towards ``outward`` x."""
    d = foot - hip
    reach = np.linalg.norm(d)
    along = (thigh**2 - shin**2 + reach**2) / (2 * reach)
    across = np.sqrt(max(thigh**2 - along**2, 0.0))
    u = d / reach
    n = np.array([-u[1], u[0]])
    if n[0] * outward < 0:
        n = -n
    return hip + along * u + across * n


def _arms(skeleton, positions, lift):
    """Swing both arms about the shoulders, ``lift`` radians upwards (mirrored left/right)."""
    out = rotate_about(skeleton, positions, "right_shoulder", lift)
    return rotate_about(skeleton, out, "left_shoulder", -lift)
