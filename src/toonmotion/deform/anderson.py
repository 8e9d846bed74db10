"""Anderson acceleration of a fixed-point iteration (Walker and Ni 2011), for stage two's
local-global steps (:meth:`toonmotion.deform.joint_solve.JointSolver.solve`): each step is mixed
with the few before it, reaching the same minimum in fewer iterations."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


class Anderson:
    """Anderson acceleration of a fixed-point iteration ``x -> G(x)`` (type II, as Peng et al.
    2018 apply to local-global geometry solves): the next point is the combination of the last
    few steps whose residuals ``G(x) - x`` combine to the smallest, extrapolating where plain
    iterations creep along a long valley. Complex vectors are mixed as their real and imaginary
    parts (the local step is not complex-linear).

    >>> mixer = Anderson(3)
    >>> x = np.array([1.0 + 0j])
    >>> for _ in range(3):  # G(x) = x / 2 + 1, fixed point 2: exact after two mixed steps
    ...     x = mixer.mix(x, x / 2 + 1)
    >>> np.round(x, 12).tolist()
    [(2+0j)]
    """

    def __init__(self, depth: int) -> None:
        self.size = depth
        self.restart()

    def restart(self, *, plain: bool = False) -> None:
        """Forget the past steps (after a mixed point was refused, or gained too little to go on
        with); ``plain``: the next step is to be a plain one (:attr:`depth` is 0 until then)."""
        self.depth = 0 if plain else self.size
        self._last: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._df: list[NDArray[np.float64]] = []
        self._dg: list[NDArray[np.float64]] = []

    def mix(self, x: NDArray[np.complex128], step: NDArray[np.complex128]) -> NDArray[np.complex128]:
        """The next point after ``x``, whose plain step is ``step``."""
        g = np.ascontiguousarray(step).view(np.float64)
        f = g - np.ascontiguousarray(x).view(np.float64)
        if self._last is not None:
            self._df.append(f - self._last[0])
            self._dg.append(g - self._last[1])
            if len(self._df) > self.depth:
                del self._df[0], self._dg[0]
        self._last = (f, g)
        if not self._df:
            return np.array(step)
        DF = np.stack(self._df, axis=1)
        gram = DF.T @ DF
        gram[np.diag_indices_from(gram)] *= 1 + 1e-10
        try:
            gamma = np.linalg.solve(gram, DF.T @ f)
        except np.linalg.LinAlgError:
            self.restart()
            return np.array(step)
        return (g - np.stack(self._dg, axis=1) @ gamma).view(np.complex128)
