"""Posing a rigged drawing and drawing the result: the calls behind ``pose``, ``tune`` and the
editor's Pose panel."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.pose_filter import exaggerate_pose
from toonmotion.deform.deformer import Deformation, Deformer, DeformSettings
from toonmotion.deform.tuning import TuningEdit, apply_tuning
from toonmotion.render.frame import fit_view, render_frame
from toonmotion.rig.character import Character
from toonmotion.rig.dragging import drag_joint as rig_drag_joint
from toonmotion.rig.pose import Pose, check_pose, rotate_about
from toonmotion.rig.sketch import SketchMatch, match_sketch


@dataclass(frozen=True)
class PosedFrame:
    """A character deformed to one pose.

    Attributes
    ----------
    pose : Pose
        The joint positions used (after the single-frame filter, when asked for).
    deformation : Deformation
        ``U`` (the deformed vertices), stage one's result, stage two's iterations and energies.
    """

    pose: Pose
    deformation: Deformation


def rotate_joint(character: Character, joint: str, angle: float) -> Pose:
    """The rest pose with the bones below ``joint`` turned by ``angle`` radians about it.

    Parameters
    ----------
    character : Character
    joint : str
        A joint of ``character.skeleton``; it stays put and everything below it turns.
    angle : float
        Radians; positive turns from +x towards +y (clockwise on screen, where y points down).

    Returns
    -------
    Pose
        Every joint's position, for :func:`pose_character`.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> pose = rotate_joint(hero, "right_elbow", 0.5)
    >>> moved = np.linalg.norm(pose.positions - hero.skeleton.positions, axis=1) > 1e-9
    >>> [name for name, m in zip(hero.skeleton.names, moved) if m]
    ['right_hand']
    """
    skeleton = character.skeleton
    return Pose(rotate_about(skeleton, skeleton.positions, joint, angle))


def drag_joint(
    character: Character, pose: Pose, joint: str, target: ArrayLike, *, mode: str = "turn",
    pinned: Sequence[str] = (), bones: int = 2,
) -> Pose:
    """``pose`` with ``joint`` dragged to ``target`` (drawing pixels), as the editor's Pose panel
    drags: ``"turn"`` its bone about its parent, carrying the joints below (forward kinematics);
    ``"reach"`` by bending up to ``bones`` bones above it (inverse kinematics), stopping at a
    ``pinned`` joint; or ``"stretch"`` its bone (:mod:`toonmotion.rig.dragging`). Raises
    :class:`~toonmotion.errors.PoseError` for a bad drag, or a pose a stretch squashed.

    Parameters
    ----------
    character : Character
    pose : Pose
        The pose at the press (each move of a drag is made from it: nothing drifts).
    joint : str
        The joint dragged.
    target : (2,) float
        Where the pointer is, drawing pixels.
    mode : {"turn", "reach", "stretch"}
        Forward kinematics (the default), inverse kinematics, or a stretch.
    pinned : sequence of str
        Joints an IK chain stops at (and that a drag of their own does not move).
    bones : int
        The longest IK chain, in bones (2: a hand moves the forearm and the upper arm).

    Returns
    -------
    Pose

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> rest = Pose(hero.skeleton.positions)
    >>> hand = hero.skeleton.index("right_hand")
    >>> up = drag_joint(hero, rest, "right_hand", rest.positions[hand] + (0, -200), mode="reach")
    >>> bool(up.positions[hand, 1] < rest.positions[hand, 1])  # the arm bends up
    True
    """
    skeleton = character.skeleton
    moved = rig_drag_joint(skeleton, check_pose(skeleton, pose).positions, joint, target, mode=mode,
                           pinned=pinned, bones=bones)
    return check_pose(skeleton, Pose(moved), where="the dragged pose")


def sketch_pose(
    character: Character, strokes: Sequence[ArrayLike], *, pose: Pose | None = None
) -> SketchMatch:
    """The pose a sketched skeleton gives: strokes matched to the character's bones (thesis 6.2a).

    Parameters
    ----------
    character : Character
    strokes : sequence of (n, 2) float
        Polylines in drawing pixels, in the order drawn: a bone, a chain of bones (its corners
        are joints), or the strokes of a whole stick figure, over the drawing or beside it.
    pose : Pose, optional
        The pose being edited (the rest pose by default): joints the sketch does not reach
        keep their place in it, or follow the sketched bone above them.

    Returns
    -------
    SketchMatch
        ``pose`` (for :func:`pose_character`), the ``bones`` the sketch covered, and whether a
        piece was drawn ``elsewhere`` (beside the figure, so scaled and hung from its joint).

    Raises
    ------
    SketchError
        For malformed strokes, or a sketch no part of the skeleton matches.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> bent = rotate_joint(hero, "right_elbow", 0.5).positions  # where to draw the forearm
    >>> elbow, hand = (hero.skeleton.index(n) for n in ("right_elbow", "right_hand"))
    >>> found = sketch_pose(hero, [[bent[elbow], bent[hand]]])
    >>> found.bones, bool(np.allclose(found.pose.positions, bent))
    (('right_hand',), True)
    """
    skeleton = character.skeleton
    return match_sketch(skeleton, pose if pose is not None else Pose(skeleton.positions), strokes)


def pose_character(
    character: Character | Deformer,
    pose: Pose,
    *,
    edits: Sequence[TuningEdit] = (),
    accel: tuple[float, float] | None = None,
    fixed: Sequence[str] = (),
    root: str | None = None,
    settings: DeformSettings | None = None,
) -> PosedFrame:
    """Deform a character to a pose (needle model, then the joint-area solve), then apply ``edits``.

    Parameters
    ----------
    character : Character or Deformer
        The rigged drawing, or a :class:`Deformer` already built for it: build one when posing
        many times, since building it is the costly step.
    pose : Pose
        Every joint's position, in ``character.skeleton``'s order.
    edits : sequence of TuningEdit, optional
        Fine-tuning sketch curves and drags, in drawing pixels, applied in order.
    accel : (float, float), optional
        An acceleration in pixels at ``root``: the single-frame cartoon filter (thesis 5.2.1)
        first exaggerates the pose as if it moved so.
    fixed : sequence of str, optional
        Joints ``accel`` must not move (feet on the ground).
    root : str, optional
        Where ``accel`` acts; the skeleton's root by default.
    settings : DeformSettings, optional
        Used only when ``character`` is a Character.

    Returns
    -------
    PosedFrame
        The pose used and the deformation (``deformation.U``: the deformed mesh vertices).

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> frame = pose_character(hero, rotate_joint(hero, "right_elbow", 0.8))
    >>> frame.deformation.U.shape == hero.mesh.V.shape
    True
    """
    deformer = character if isinstance(character, Deformer) else Deformer(character, settings)
    if accel is not None:
        pose = exaggerate_pose(deformer.character.skeleton, pose, accel, tuple(fixed), root=root)
    result = apply_tuning(deformer, pose, deformer.deform(pose), tuple(edits))
    return PosedFrame(pose=pose, deformation=result)


def render_pose(
    character: Character,
    frame: PosedFrame,
    *,
    size: tuple[int, int] | None = None,
    background: tuple[int, int, int] | None = None,
    overlays: Sequence[str] = (),
) -> NDArray[np.uint8]:
    """A posed frame as a picture, its view grown to hold the whole figure (:func:`pose_view`).

    Parameters
    ----------
    character : Character
    frame : PosedFrame
        From :func:`pose_character`.
    size : (int, int), optional
        ``(width, height)`` of the picture; by default the view at one pixel per drawing pixel.
    background : (int, int, int), optional
        An opaque RGB background; transparent by default.
    overlays : sequence of str, optional
        Drawn over the figure: any of :data:`toonmotion.render.frame.OVERLAYS` (the mesh, the
        skeleton, ...).

    Returns
    -------
    (H, W, 4) uint8
        RGBA pixels.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> picture = render_pose(hero, pose_character(hero, rotate_joint(hero, "head", 0.3)),
    ...                       size=(120, 160), background=(255, 255, 255))
    >>> picture.shape, bool((picture[..., 3] == 255).all())
    ((160, 120, 4), True)
    """
    return render_frame(character, frame.deformation.U, pose=frame.pose, size=size,
                        view=pose_view(character, frame), background=background, overlays=overlays)


def pose_view(character: Character, frame: PosedFrame) -> tuple[float, float, float, float]:
    """The view :func:`render_pose` draws: the drawing's canvas and the posed figure.

    Parameters
    ----------
    character : Character
    frame : PosedFrame
        From :func:`pose_character`.

    Returns
    -------
    (x0, y0, x1, y1) float
        In drawing pixels; it holds the drawing's own canvas and every deformed vertex.

    Examples
    --------
    >>> from toonmotion.samples import sample_rig
    >>> hero = sample_rig()
    >>> x0, y0, x1, y1 = pose_view(hero, pose_character(hero, rotate_joint(hero, "hip", 3.0)))
    >>> (x0, y0) <= (0, 0) and (x1, y1) >= hero.size
    True
    """
    return fit_view(character, [frame.deformation.U])
