"""Key-shape retargeting (Bregler et al. 2002, section 4): a captured cartoon's weights replayed on
new key-shapes, on a drawing's outline, on a rigged character's key poses, or by its line of
action; capture itself is :mod:`toonmotion.api.keyshapes`."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.motion import Motion
from toonmotion.animate.timeline import Timeline
from toonmotion.errors import KeyShapeError
from toonmotion.keyshape.arap import triangulate_shape
from toonmotion.keyshape.contour import ContourCapture
from toonmotion.keyshape.line_of_action import capture_lines, captured_lines, retarget_line
from toonmotion.keyshape.model import check_shapes
from toonmotion.keyshape.parts import retarget_parts as _retarget_parts
from toonmotion.keyshape.retarget import pin as pin_point
from toonmotion.keyshape.retarget import retarget_poses, retarget_shapes
from toonmotion.render.shape_warp import warp_sequence
from toonmotion.rig.skeleton import Skeleton


def retarget_parts(captures: Mapping[str, ContourCapture], input_keys: ArrayLike, output_keys: ArrayLike,
                   input_parts: Mapping[str, Sequence[int]], output_parts: Mapping[str, Sequence[int]]
                   ) -> NDArray[np.float64]:
    """Replay part-by-part capture (:func:`capture_parts`) on output key-shapes split into the
    same parts: each output part follows its input part, all placed by the whole keys' one map
    (so the parts stay together); a point in several parts takes their mean.

    Parameters
    ----------
    captures : mapping of str to ContourCapture
    input_keys : (K, N, 2) float
    output_keys : (K, M, 2) float
    input_parts, output_parts : mapping of str to sequence of int
        The same part names, each with its points in the input and in the output keys.

    Returns
    -------
    (T, M, 2) float

    Raises
    ------
    KeyShapeError
        For parts that do not pair up, or as :func:`retarget_keyshapes`.

    Examples
    --------
    A frame drawn as the second key, replayed on keys twice the size:

    >>> from toonmotion.api import capture_parts
    >>> S = np.array([[(0.0, 0), (4, 0), (4, 4), (0, 4), (2, 8), (3, 6)],
    ...               [(0.0, 0), (6, 0), (4, 4), (0, 4), (2, 12), (4, 7)]])
    >>> parts = {"body": [0, 1, 2, 3], "head": [2, 3, 4, 5]}
    >>> found = capture_parts([S[1]], S, parts)
    >>> bool(np.allclose(retarget_parts(found, S, S * 2, parts, parts)[0], S[1] * 2))
    True
    """
    return _retarget_parts(captures, input_keys, output_keys, input_parts, output_parts)


def retarget_keyshapes(capture: ContourCapture, input_keys: ArrayLike, output_keys: ArrayLike
                       ) -> NDArray[np.float64]:
    """Replay captured key-shape motion on another character's key-shapes (Bregler et al. 3.4).

    Parameters
    ----------
    capture : ContourCapture
        Captured with the hand-picked keys (``capture_contours(contours, keys)``).
    input_keys : (K, N, 2) float
        Those keys.
    output_keys : (K, M, 2) float
        An output key-shape per input key (any number of points, the same in each).

    Returns
    -------
    (T, M, 2) float
        The output shapes, moving as the input moved (docs/keyshapes.md).

    Raises
    ------
    KeyShapeError
        When the keys do not pair up, or the motion was captured with other keys.

    Examples
    --------
    >>> from toonmotion.keyshape.model import warp
    >>> keys = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)],
    ...                  [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])
    >>> from toonmotion.api import capture_contours
    >>> found = capture_contours([warp([[1, 0, 2], [0, 1, 0]], [0.5, 0.5], keys)], keys)
    >>> retarget_keyshapes(found, keys, keys * 2).shape  # the same keys, twice the size
    (1, 5, 2)
    """
    return retarget_shapes(capture, input_keys, output_keys)


def animate_drawing(picture: NDArray[np.uint8], outline: ArrayLike, shapes: ArrayLike, *, closed: bool = True,
                    background: tuple[int, int, int] | None = None) -> Iterator[NDArray[np.uint8]]:
    """A drawing moved by its outline: ``picture``, drawn with ``outline`` (N, 2) in its pixels,
    warped onto every shape of ``shapes`` (T, N, 2) — the output of :func:`retarget_keyshapes`
    with that outline as the first output key (the paper's 2D output).

    The outline's own triangles (Delaunay over its points, those outside a closed outline
    dropped) carry the picture inside it piecewise-affinely; what lies outside is not drawn.

    Parameters
    ----------
    picture : (h, w, 4) uint8
        RGBA.
    outline : (N, 2) float
        The drawing's outline, in its pixels.
    shapes : (T, N, 2) float
        The outline of every frame.
    closed : bool
        Whether the outline is a closed contour.
    background : (r, g, b), optional
        Behind the drawing; transparent by default.

    Returns
    -------
    iterator of (H, W, 4) uint8
        One RGBA frame per shape, all on one canvas that holds every shape (and 8 px round).

    Raises
    ------
    KeyShapeError
        For an outline that cannot be triangulated or shapes of another point count.

    Examples
    --------
    >>> picture = np.zeros((40, 40, 4), np.uint8); picture[5:35, 5:35] = (200, 40, 40, 255)
    >>> square = np.array([(5.0, 5), (35, 5), (35, 35), (5, 35)])
    >>> frames = list(animate_drawing(picture, square, [square, square * [1.5, 1]]))  # 1.5 times as wide
    >>> len(frames), frames[0].shape  # one canvas holding both, 8 px round
    (2, (46, 64, 4))
    """
    source = check_shapes(outline, what="the drawing's outline")[0]
    moved = check_shapes(shapes, what="the shapes")
    if moved.shape[1] != len(source):
        raise KeyShapeError(f"the shapes have {moved.shape[1]} points and the drawing's outline "
                            f"{len(source)}: they must be in correspondence")
    triangles = triangulate_shape(source, closed=closed)
    return warp_sequence(picture, source, moved, triangles, background=background)


def retarget_keyposes(capture: ContourCapture, input_keys: ArrayLike, skeleton: Skeleton,
                      key_poses: Timeline, *, fps: float = 12.0, reference: ArrayLike | None = None,
                      pin: tuple[str, dict[int, ArrayLike]] | None = None) -> Motion:
    """Replay captured key-shape motion on a rigged character's key poses, blending every bone's
    angle and length with the captured weights (the paper's articulated figures).

    Parameters
    ----------
    capture : ContourCapture
        Captured with the hand-picked keys.
    input_keys : (K, N, 2) float
        Those keys.
    skeleton : Skeleton
        The character's.
    key_poses : Timeline
        Its keys, in frame order, are one pose per input key.
    fps : float
        The motion's frame rate.
    reference : (n, 2) float, optional
        The character's outline in its first key pose: its size and place carry the input's
        motion over (by default the first pose's joints, which span less than the drawing).
    pin : (str, dict of int to (x, y)), optional
        A joint (a foot) and its positions at chosen frames: the motion is moved by the least
        translation per frame to put it there (blended between pinned frames, held beyond).

    Returns
    -------
    Motion
        For :func:`animate_character`.

    Raises
    ------
    KeyShapeError
        When there is not one pose per key.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.rig.pose import Pose
    >>> from toonmotion.api.animation import set_key
    >>> from toonmotion.api.posing import rotate_joint
    >>> from toonmotion.keyshape.model import warp
    >>> hero = sample_rig()
    >>> keys = np.array([[(0.0, 0), (4, 0), (4, 4), (2, 5), (0, 4)],
    ...                  [(0.0, 0), (4, 0), (4, 4), (2, 8), (0, 4)]])
    >>> poses = set_key(hero.skeleton, None, 0, Pose(hero.skeleton.positions))
    >>> poses = set_key(hero.skeleton, poses, 1, rotate_joint(hero, "right_elbow", -1.0))
    >>> from toonmotion.api import capture_contours
    >>> found = capture_contours([warp(np.eye(2, 3), w, keys) for w in ([1, 0], [0.5, 0.5], [0, 1])], keys)
    >>> retarget_keyposes(found, keys, hero.skeleton, poses).positions.shape
    (3, 17, 2)
    """
    poses = np.stack([key.pose.positions for key in key_poses.keys])
    positions = retarget_poses(capture, input_keys, skeleton, poses, reference=reference)
    if pin is not None:
        joint, targets = pin
        positions = pin_point(positions, skeleton.index(joint), targets)
    return Motion(skeleton=skeleton, positions=positions, fps=fps)


def retarget_line_of_action(lines: ArrayLike, key_lines: ArrayLike, skeleton: Skeleton, *,
                            chain: list[str] | tuple[str, ...] | str | None = None, direction: str = "auto",
                            fps: float = 12.0, lower: float = -0.5, upper: float = 1.5,
                            support: int | None = None, pin: tuple[str, dict[int, ArrayLike]] | None = None
                            ) -> Motion:
    """Capture a line of action drawn over a cartoon and bend a character's chain of joints along
    it (Bregler et al., section 4).

    Each frame's line is captured with the key lines (contour capture, straight lines allowed);
    the model's line of every frame then poses the chain: the joints at their rest arc-length
    fractions along the line, every bone keeping its rest length, the rest of the body hanging
    rigidly from the chain (docs/keyshapes.md, "The line of action").

    Parameters
    ----------
    lines : (T, N, 2) float
        The line of action of every frame, open, points in correspondence with the key lines
        (``resample_line`` makes them so), drawing pixels, y down.
    key_lines : (K, N, 2) float
        Hand-picked key lines (a straight one is allowed).
    skeleton : Skeleton
        The character's; its rest positions are the pose bent.
    chain : sequence of str or str, optional
        Joint names from a root-side joint to a tip, each the parent of the next (or one
        comma-separated string); by default the chain from the first root to the joint farthest
        from it at rest.
    direction : {"auto", "root-first", "tip-first"}
        Which end the lines were drawn from; ``"auto"`` picks the end that makes the first line
        point the way the chain does at rest.
    fps : float
        The motion's frame rate.
    lower, upper : float
        Each key line's weight bounds.
    support : int, optional
        At most this many non-zero weights.
    pin : (str, dict of int to (x, y)), optional
        A joint and its positions at chosen frames: the motion is moved by one translation per
        frame to put it there (blended between pinned frames, held beyond them).

    Returns
    -------
    Motion
        The chain bent along each frame's line, the rest hanging from it, for
        :func:`animate_character`.

    Raises
    ------
    KeyShapeError
        For lines out of correspondence or coincident points, a chain whose joints are not
        each the parent of the next, or bad bounds.
    SkeletonError
        For a chain naming a joint the skeleton lacks.

    Examples
    --------
    >>> from toonmotion.keyshape.line_of_action import resample_line
    >>> from toonmotion.keyshape.model import warp
    >>> from toonmotion.samples import sample_rig
    >>> skeleton = sample_rig().skeleton
    >>> u = np.linspace(0, 1, 50)[:, None]
    >>> straight = resample_line(np.hstack([0 * u, -100 * u]), 20)  # drawn from the hips up
    >>> lean = resample_line(np.hstack([30 * u ** 2, -100 * u]), 20)  # curving to the right
    >>> clip = [warp(np.eye(2, 3), [1 - w, w], [straight, lean]) for w in (0.0, 0.5, 1.0)]
    >>> motion = retarget_line_of_action(clip, [straight, lean], skeleton)
    >>> motion.positions.shape
    (3, 17, 2)
    >>> bool(np.allclose(motion.positions[0], skeleton.positions))  # a straight line: standing
    True
    >>> bool(motion.positions[2, skeleton.index("head"), 0] > skeleton.positions[skeleton.index("head"), 0])
    True
    """
    found = capture_lines(lines, key_lines, lower=lower, upper=upper, support=support)
    positions = retarget_line(captured_lines(found, key_lines), skeleton, chain, direction=direction)
    if pin is not None:
        joint, targets = pin
        positions = pin_point(positions, skeleton.index(joint), targets)
    return Motion(skeleton=skeleton, positions=positions, fps=fps)
