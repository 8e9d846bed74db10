"""The outcome of one stage-two solve (:meth:`toonmotion.deform.joint_solve.JointSolver.solve`)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from toonmotion.geometry.arrays import frozen_array


@dataclass(frozen=True, eq=False)
class SolveResult:
    """Outcome of one stage-two solve.

    Attributes
    ----------
    U : (n, 2) float
        All vertices: the free ones solved, the rest as given.
    iterations : int
        Gauss-Newton iterations run.
    energy_start, energy : float
        Eq. 3.8 at the starting positions and at the result (pixels squared).
    converged : bool
        The last iteration lowered the energy by less than the tolerance (a fraction).

    Construction copies ``U`` (read-only) and raises ``ValueError`` unless it is ``(n, 2)``,
    the iteration count a whole number >= 0 and the energies numbers.
    """

    U: NDArray[np.float64]
    iterations: int
    energy_start: float
    energy: float
    converged: bool

    _what = "a stage-two result"  # how errors name it

    def __post_init__(self) -> None:
        what, iterations = self._what, self.iterations
        if isinstance(iterations, bool) or not isinstance(iterations, int | np.integer) or iterations < 0:
            raise ValueError(f"{what}'s iterations must be a whole number >= 0, got {iterations!r}")
        for name in ("energy_start", "energy"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number):
                raise ValueError(f"{what}'s {name} must be a number, got {value!r}")
            object.__setattr__(self, name, float(value))
        U = frozen_array(self.U, dtype=np.float64, shape=(None, 2), name=f"{what}'s U")
        object.__setattr__(self, "U", U)
        object.__setattr__(self, "iterations", int(iterations))
        object.__setattr__(self, "converged", bool(self.converged))
