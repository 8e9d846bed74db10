"""Key-frames that swing any character's bones: drawings animated into footage whose true joints
are known, for measuring the joint tracker on deformed drawings (``benchmarks/track_footage.py``).

Every bone two or more levels below a root (an upper arm, a shin; not the hips' or the spine's
first bone) turns about its parent by ``A sin(2 pi k / (n - 1) + phi)`` at key ``k`` of ``n``,
on top of its parent's turn, with ``A`` drawn from ``amplitude`` (degrees) and ``phi`` at random
per bone; the roots sway sideways and bob up by fractions of the figure's height. A whole cycle
over the keys: the last key is the first. Nothing here knows joint names, so it animates any
skeleton the same way.

Points are ``(x, y)`` pixels, y down.
"""

from __future__ import annotations

import math

import numpy as np

from toonmotion.animate.timeline import Keyframe, Timeline, make_timeline
from toonmotion.rig.pose import Pose
from toonmotion.rig.skeleton import Skeleton

# The roots' sideways sway and upward bob, at most, as fractions of the figure's height.
SWAY = 0.12
BOB = 0.1


def swinging_keys(skeleton: Skeleton, *, seed: int = 0, keys: int = 9, step: int = 6,
                  amplitude: tuple[float, float] = (8.0, 30.0), fps: float = 12.0) -> Timeline:
    """``keys`` key-frames ``step`` frames apart swinging ``skeleton``'s bones (module docstring),
    eased in and out, at ``fps``.

    >>> skeleton = Skeleton.from_joints([("hip", None, (50, 50)), ("knee", "hip", (50, 80)),
    ...                                  ("foot", "knee", (50, 110))])
    >>> timeline = swinging_keys(skeleton, seed=1)
    >>> timeline.frame_count, np.allclose(timeline.keys[0].pose.positions, timeline.keys[-1].pose.positions)
    (49, True)
    >>> bones = [np.hypot(*np.diff(key.pose.positions, axis=0).T) for key in timeline.keys]
    >>> np.allclose(bones, [30.0, 30.0])  # the bones turn, and keep their lengths
    True
    """
    rng = np.random.default_rng(seed)
    rest = skeleton.positions
    parents = skeleton.parents
    depth = np.zeros(len(skeleton), int)
    for m, p in enumerate(parents):  # parents come before their children
        depth[m] = 0 if p < 0 else depth[p] + 1
    swing = np.where(depth >= 2, np.radians(rng.uniform(*amplitude, len(skeleton))), 0.0)
    phase = rng.uniform(0.0, 2 * math.pi, len(skeleton))
    height = float(np.ptp(rest[:, 1])) or 1.0
    sway, bob = rng.uniform(0.0, SWAY) * height, rng.uniform(0.0, BOB) * height
    frames = []
    for k in range(keys):
        w = 2 * math.pi * k / max(keys - 1, 1)
        turn = np.zeros(len(skeleton))
        at = np.empty_like(rest)
        for m, p in enumerate(parents):
            if p < 0:
                at[m] = rest[m] + [sway * math.sin(w), -bob * abs(math.sin(w))]
                continue
            turn[m] = turn[p] + swing[m] * math.sin(w + phase[m])
            c, s = math.cos(turn[m]), math.sin(turn[m])
            bone = rest[m] - rest[p]
            at[m] = at[p] + [c * bone[0] - s * bone[1], s * bone[0] + c * bone[1]]
        frames.append(Keyframe(k * step, Pose(at)))
    return make_timeline(skeleton, frames, fps=fps, ease="in-out")
