"""Cartoon capture by affine motion and key-shapes (Bregler et al. 2002, "Turning to the Masters").

A shape is N points in correspondence, ``(N, 2)`` float, drawing pixels. The motion model
(:mod:`~toonmotion.keyshape.model`) warps a weighted sum of key-shapes by an affine map;
:mod:`~toonmotion.keyshape.arap` makes as-rigid-as-possible in-betweens of two shapes;
:mod:`~toonmotion.keyshape.space` builds the extended linear space of key-shapes (PCA over the
keys and their in-betweens); :mod:`~toonmotion.keyshape.contour` captures affine motion and
key weights from contours. See docs/keyshapes.md.
"""
