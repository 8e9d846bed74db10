"""What tests and benchmarks of posing by sketching share: poses to draw, and strokes drawn
through them as a hand would."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from toonmotion.rig.pose import rotate_about
from toonmotion.rig.skeleton import Skeleton


def turned(skeleton: Skeleton, rng: np.random.Generator, *, turns: int = 2, most: float = 0.6
           ) -> NDArray[np.float64]:
    """A pose: ``turns`` joints other than the first root, each turned up to ``most`` radians."""
    positions = skeleton.positions.copy()
    for _ in range(turns):
        joint = skeleton.names[rng.integers(1, len(skeleton))]
        positions = rotate_about(skeleton, positions, joint, rng.uniform(-most, most))
    return positions


def strokes_through(positions: NDArray[np.float64], chains: Sequence[Sequence[int]], rng: np.random.Generator,
                    *, noise: float = 0.8) -> list[NDArray[np.float64]]:
    """A hand-drawn stroke along each chain of joints: a point every 4 px, jittered by ``noise``
    px, about half drawn backwards, in shuffled order."""
    strokes = []
    for chain in chains:
        corners = positions[list(chain)]
        dense = [a + (b - a) * np.linspace(0, 1, max(2, int(np.hypot(*(b - a)) / 4)), endpoint=False)[:, None]
                 for a, b in zip(corners, corners[1:], strict=False)]
        line = np.concatenate([*dense, corners[-1:]])
        line = line + rng.normal(0, noise, line.shape) if noise > 0 else line
        strokes.append(line[::-1] if rng.random() < 0.5 else line)
    order = rng.permutation(len(strokes))
    return [strokes[i] for i in order]


def figure_size(positions: NDArray[np.float64]) -> float:
    """The diagonal of the joints' bounding box."""
    return float(np.hypot(*np.ptp(positions, axis=0)))
