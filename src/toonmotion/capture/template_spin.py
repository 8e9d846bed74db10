"""Looking for a joint at turns all round at once, where no bone gives its rectangle's angle.

:func:`~toonmotion.capture.coarse_search.locate` turns the search window for each turn it tries
and matches the anchor's coarse template in each (``cv2.matchTemplate``, which transforms the
template anew every call): 18 turns cost 18 searches. Here the *template* turns instead: the disc
inscribed in the anchor's coarse template, turned by each of the turns all round
(:attr:`~toonmotion.capture.match_tuning.MatchTuning.spin_turns`), is transformed once per window size
(:class:`TurnedDiscs`, made once per joint), the window, not turned, once per search, and every
turn's sums of squared differences come from one product of spectra and one batch of inverse
transforms (``scipy.fft``): the 18 turns in about a fifth of the time (130-350 us against
640-1700 us for windows 15-45 px round).

The cost per cell is :func:`~toonmotion.capture.coarse_search.locate`'s (eq. 4.6's mixed cost
with the joint's colour weight, ``w_beta = 1 / radius^2``, plain cells first, off-figure cells
left out) over the disc's pixels only: the part of the rectangle every turn keeps in view (a
square's corners turn out of it).
"""

from __future__ import annotations

import math

import cv2
import numpy as np
import scipy.fft as sp_fft
from numpy.typing import NDArray

from toonmotion.capture.coarse_search import coarse_geometric
from toonmotion.capture.joint_plan import JointPlan
from toonmotion.capture.match_tuning import MatchTuning
from toonmotion.capture.patches import Patch, confidence, sample, ssd_at
from toonmotion.capture.track_figure import figure_cells

_SUM = np.ones((1, 3), np.float32)  # cv2.transform by it sums the channels


class TurnedDiscs:
    """The disc inscribed in a coarse template ``(h, w, 3)``, turned by each of ``turns`` (radians;
    default :class:`~toonmotion.capture.match_tuning.MatchTuning`'s ``spin_turns``), and its
    spectra per window size, made when first asked for.

    Attributes
    ----------
    coarse : (h, w, 3) float32
        The template.
    turns : tuple of float
        Radians; a disc turned by ``a`` is the template's look where its rectangle is turned by
        ``a`` (:func:`~toonmotion.capture.patches.sample`'s convention).
    side : int
        The disc's diameter, coarse pixels: the template's shorter side.
    discs : (n, side, side, 3) float32
        The turned templates, 0 off the disc.
    mask : (side, side) float32
        1 on the disc, 0 off it.
    area : float
        The disc's pixels.
    squares : (n,) float
        Each turned disc's sum of squares.
    """

    def __init__(self, coarse: Patch, turns: tuple[float, ...] | None = None) -> None:
        turns = MatchTuning().spin_turns if turns is None else turns
        h, w = coarse.shape[:2]
        side = min(h, w)
        r = (side - 1) / 2
        y, x = np.mgrid[:side, :side]
        self.coarse, self.turns, self.side = coarse, tuple(turns), side
        self.mask = ((x - r) ** 2 + (y - r) ** 2 <= (side / 2) ** 2).astype(np.float32)
        self.area = float(self.mask.sum())
        middle = np.array([(w - 1) / 2, (h - 1) / 2])
        # Template pixel (x, y) turned by a shows the rectangle's pixel rotation(-a) (x, y): the
        # window, not turned, then matches the template as a window turned by a would.
        self.discs = np.stack([sample(coarse, middle, -a, (side, side)) * self.mask[..., None]
                               for a in self.turns])
        self.squares = np.einsum("kijc,kijc->k", self.discs, self.discs, dtype=np.float64).astype(np.float32)
        self._spectra: dict[int, NDArray[np.complex64]] = {}

    def spectra(self, n: int) -> NDArray[np.complex64]:
        """The conjugate spectra of the turned discs' channels in an ``n x n`` transform
        (``scipy.fft.rfft2``), ``(3, turns, n, n // 2 + 1)``: a product with a window's spectrum
        transforms back to their correlation."""
        if n not in self._spectra:
            self._spectra[n] = np.conj(sp_fft.rfft2(np.moveaxis(self.discs, 3, 0), s=(n, n)))
        return self._spectra[n]


def locate_all_round(small: NDArray[np.uint8], discs: TurnedDiscs, centre: NDArray[np.float64],
                     joint: JointPlan, radius: float, figure: NDArray[np.uint8] | None = None
                     ) -> tuple[NDArray[np.float64], float, float]:
    """Look for a joint at half resolution, up to ``radius`` pixels (full resolution) from
    ``centre``, its rectangle turned by each of ``discs.turns``, as
    :func:`~toonmotion.capture.coarse_search.locate` does at turns of the rectangle's angle.

    Returns
    -------
    xy : (2,) float
        The best place, full-resolution (x, y) pixels, to about a pixel.
    confidence : float
        The coarse match's confidence over the disc (0 if no cell could be taken).
    angle : float
        The rectangle's angle there, radians: the best turn.

    Examples
    --------
    A smooth texture turned by 100 degrees (the rectangle's angle by -100) is found where it is:

    >>> from toonmotion.capture.joint_plan import Templates, plan_joint
    >>> noise = np.random.default_rng(1).uniform(0, 255, (200, 200, 3)).astype(np.float32)
    >>> image = cv2.normalize(cv2.GaussianBlur(noise, (0, 0), 3), None, 0, 255, cv2.NORM_MINMAX)
    >>> anchor = Templates.cut(image.astype(np.uint8), np.array([99.5, 99.5]), 0.0, (30, 30))
    >>> turned = cv2.warpAffine(image, cv2.getRotationMatrix2D((99.5, 99.5), 100, 1.0), (200, 200))
    >>> joint = plan_joint((30, 30), 15, 1 / 255**2, 1 / 15**2, 0, 0)
    >>> small, discs = cv2.pyrDown(turned.astype(np.uint8)), TurnedDiscs(anchor.coarse)
    >>> xy, confidence, angle = locate_all_round(small, discs, np.array([104.0, 95.0]), joint, 15)
    >>> bool(np.abs(xy - 99.5).max() <= 2.5), round(math.degrees(angle)), confidence > 0.8
    (True, 260, True)
    """
    side = discs.side
    R = max(1, int(math.ceil(radius / 2)))
    size, cells = side + 2 * R, 2 * R + 1
    n = sp_fft.next_fast_len(size, real=True)
    turned = discs.spectra(n)
    centre = np.asarray(centre, dtype=float)
    # Pixel centres: full-resolution x is half-resolution 2 x + 0.5.
    window = sample(small, (centre - 0.5) / 2, 0.0, (size, size))
    spectrum = sp_fft.rfft2(np.moveaxis(window, 2, 0), s=(n, n))
    # Per cell, the window's sum of squares over the disc there, minus twice its correlation with
    # each turned disc, plus the disc's: the sum of squared differences, every turn at once.
    energy = cv2.matchTemplate(cv2.transform(window * window, _SUM), discs.mask, cv2.TM_CCORR)
    product = turned[0] * spectrum[0]
    for c in (1, 2):
        product += turned[c] * spectrum[c]
    ssd = sp_fft.irfft2(product, s=(n, n))[:, :cells, :cells]
    ssd *= -2.0
    ssd += energy
    ssd += discs.squares[:, None, None]
    np.maximum(ssd, 0.0, out=ssd)
    area = discs.area
    prior = coarse_geometric(R, radius)
    if figure is not None:
        prior = np.where(figure_cells(figure, centre, 0.0, R, step=2.0), prior, np.inf)
    cost = joint.w_alpha * joint.size[0] * joint.size[1] / area * ssd + prior
    # As in the fine search, plain cells first (per turn); per turn the cell of least cost, and of
    # the turns the one whose cell matches best.
    plain = (ssd <= ssd_at(joint.tuning.update_confidence, (1, 1), joint.tuning) * area) & np.isfinite(cost)
    some_plain = np.asarray(plain.any(axis=(1, 2)))
    cost[some_plain[:, None, None] & ~plain] = np.inf
    every = np.arange(len(cost))
    chosen = np.argmin(cost.reshape(len(cost), -1), axis=1)
    turn_cost = cost.reshape(len(cost), -1)[every, chosen]
    turn_ssd = np.where(np.isfinite(turn_cost), ssd.reshape(len(ssd), -1)[every, chosen], np.inf)
    k = int(np.argmin(turn_ssd))
    if not math.isfinite(turn_ssd[k]):
        return centre, 0.0, 0.0
    i, j = divmod(int(chosen[k]), cells)
    xy = centre + [2.0 * (j - R), 2.0 * (i - R)]
    return xy, confidence(float(turn_ssd[k]) / area, (1, 1), joint.tuning), discs.turns[k]
