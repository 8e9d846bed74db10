"""Hilditch's thinning of a binary image to a one-pixel-wide curve skeleton (thesis 3.3).

Neighbours of a pixel P1 are named as in the thesis (fig. 3.4)::

    P3 P2 P0
    P4 P1 P8
    P5 P6 P7

``B(P)`` is the number of foreground neighbours and ``A(P)`` the number of 0 -> 1 patterns in
the cyclic sequence P2, P3, ..., P8, P0, P2. A foreground pixel is deleted when

1. ``2 <= B(P1) <= 6``,
2. ``A(P1) = 1``,
3. ``P2 * P4 * P8 = 0`` or ``A(P2) != 1``,
4. ``P2 * P4 * P6 = 0`` or ``A(P4) != 1``.

(The thesis's text lost the "not" of conditions 3 and 4 in conversion; this is the standard
algorithm.) Each iteration evaluates the conditions on the whole image at once, so the shape
is peeled one layer at a time from every side and the skeleton stays centred. Deleting all
those pixels at once can break a shape apart (a 2x2 block vanishes), so the deletions of an
iteration are applied in four interleaved subfields (pixels of equal row and column parity,
never neighbours of each other), each re-checking conditions 1 and 2; deleting non-adjacent
pixels that satisfy them never changes connectivity or holes. A last pass removes the corner
pixels of 4-connected staircases, which Hilditch keeps, so the result is 8-connected and
one pixel wide: no pixel but an end point can be removed without changing the topology.

The work is vectorised with lookup tables over the 256 neighbourhood codes and only touches the
current border pixels, so its cost grows with the shape's area, not the image's.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

# (row, col) offsets of P2, P3, P4, P5, P6, P7, P8, P0: the thesis's cyclic order.
_RING = np.array([(-1, 0), (-1, -1), (0, -1), (1, -1), (1, 0), (1, 1), (0, 1), (-1, 1)])
_P2, _P4, _P6, _P8 = 0, 2, 4, 6


def _tables():
    codes = np.arange(256)
    bits = (codes[:, None] >> np.arange(8)) & 1  # bits[c, k] = value of ring position k
    B = bits.sum(axis=1)
    A = np.sum((bits == 0) & (np.roll(bits, -1, axis=1) == 1), axis=1)
    # Yokoi's 8-connectivity number over the ring (4-neighbours are the even positions).
    x = 1 - bits
    N8 = sum(x[:, k] - x[:, k] * x[:, (k + 1) % 8] * x[:, (k + 2) % 8] for k in (0, 2, 4, 6))
    removable = (B >= 2) & (B <= 6) & (A == 1)
    simple = (N8 == 1) & (B >= 2)
    return A.astype(np.int8), removable, simple


_A, _REMOVABLE, _SIMPLE_NOT_END = _tables()


def hilditch_thin(mask: ArrayLike) -> NDArray[np.bool_]:
    """Thin a binary image to its curve skeleton.

    Parameters
    ----------
    mask : (h, w) bool
        Foreground.

    Returns
    -------
    (h, w) bool
        One-pixel-wide, 8-connected skeleton with the same 8-connected components and the same
        holes as ``mask``.

    Examples
    --------
    >>> bar = np.zeros((7, 12), bool); bar[2:5, 1:11] = True
    >>> hilditch_thin(bar).astype(int)[3].tolist()
    [0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0]
    """
    mask = np.asarray(mask, dtype=bool)
    out = np.zeros_like(mask)
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return out
    r0, r1, c0, c1 = rows.min(), rows.max() + 1, cols.min(), cols.max() + 1
    image = np.pad(mask[r0:r1, c0:c1], 1).astype(np.uint8)
    _thin(image)
    out[r0:r1, c0:c1] = image[1:-1, 1:-1].astype(bool)
    return out


def _thin(image):
    """Thin a zero-padded uint8 image in place."""
    width = image.shape[1]
    flat = image.ravel()
    ring = _RING[:, 0] * width + _RING[:, 1]
    four = ring[[_P2, _P4, _P6, _P8]]
    parity = (np.arange(flat.size) // width % 2) * 2 + np.arange(flat.size) % 2

    def codes(at):
        bits = flat[at[:, None] + ring[None, :]]
        return np.packbits(bits, axis=1, bitorder="little")[:, 0].astype(np.int32)

    def border(at):
        at = at[flat[at] == 1]
        return at[np.any(flat[at[:, None] + four[None, :]] == 0, axis=1)]

    slot = np.zeros(flat.size, dtype=np.int64)  # scratch space for removing duplicates

    def distinct(at):
        slot[at] = np.arange(len(at))
        return at[slot[at] == np.arange(len(at))]

    candidates = border(np.flatnonzero(flat))
    while True:
        code = codes(candidates)
        ok = _REMOVABLE[code]
        p2, p4 = (code >> _P2) & 1, (code >> _P4) & 1
        guard3 = ok & (p2 & p4 & (code >> _P8)).astype(bool)
        guard4 = ok & (p2 & p4 & (code >> _P6)).astype(bool)
        ok[guard3] = _A[codes(candidates[guard3] + ring[_P2])] != 1
        ok[guard4] &= _A[codes(candidates[guard4] + ring[_P4])] != 1
        marked = candidates[ok]
        if len(marked) == 0:
            break
        deleted = _delete_in_subfields(flat, marked, parity, codes, _REMOVABLE)
        if len(deleted) == 0:
            break
        exposed = (deleted[:, None] + four[None, :]).ravel()
        candidates = border(distinct(np.concatenate([candidates, exposed])))
    # Strip staircase corners: simple pixels that are not end points.
    while True:
        at = np.flatnonzero(flat)
        if len(_delete_in_subfields(flat, at, parity, codes, _SIMPLE_NOT_END)) == 0:
            break


def _delete_in_subfields(flat, marked, parity, codes, table):
    """Delete marked pixels that pass ``table``, one subfield of mutual non-neighbours at a time."""
    deleted = []
    for field in range(4):
        at = marked[parity[marked] == field]
        at = at[table[codes(at)]]
        flat[at] = 0
        deleted.append(at)
    return np.concatenate(deleted)
