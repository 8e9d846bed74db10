"""A character's editing history: decomposition corrections (6.3a) and depth settings (3.5, 6.3b).

A project keeps the edits themselves, in the order they were made, not only their result:

* a :class:`~toonmotion.rig.binding.Correction` attaches every vertex inside a closed curve to
  a bone;
* a :class:`DepthEdit` puts a bone's region, named or picked by a point, at a depth layer.

Both are in drawing pixels and bone names, never vertex numbers, so :func:`replay` can apply
them to a re-meshed character, skipping (and saying why) any that no longer make sense, such as
a bone the new skeleton lacks. :func:`undo` rebuilds the character from its automatic
decomposition and every edit but the last; the undone edits are kept for :func:`redo` until a
new edit is made.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable
from typing import TypeAlias

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import EditError, SettingsError, ToonmotionError
from toonmotion.rig.binding import Correction, attach_inside, decompose
from toonmotion.rig.character import Character
from toonmotion.rig.depth_edit import DepthEdit

Edit: TypeAlias = Correction | DepthEdit
"""An edit of a character's binding or depths."""


def apply_edit(character: Character, edit: Edit) -> Character:
    """``character`` with ``edit`` made: its result applied and the edit appended to the history.

    A new edit clears what :func:`redo` could bring back. A correction that moves no vertex to
    another bone is an :class:`EditError`, not an edit to keep.
    """
    edited = _applied(character, edit)
    if isinstance(edit, Correction) and np.array_equal(edited.binding.bone, character.binding.bone):
        raise EditError(f"every vertex inside the curve is attached to {edit.bone} already: nothing "
                        "to change")
    return dataclasses.replace(edited, undone=())


def replay(character: Character, edits: Iterable[Edit]) -> tuple[Character, list[tuple[Edit, str]]]:
    """Apply ``edits`` in order to ``character`` (e.g. one just re-meshed).

    Returns
    -------
    character : Character
    skipped : list of (edit, str)
        Edits that no longer apply, with the reason.
    """
    skipped = []
    for edit in edits:
        try:
            character = _applied(character, edit)
        except ToonmotionError as error:
            skipped.append((edit, str(error)))
    return character, skipped


def undo(character: Character, steps: int = 1) -> tuple[Character, tuple[Edit, ...]]:
    """Take back the last ``steps`` edits; returns ``(character, undone edits)``."""
    edits = character.edits
    if not (isinstance(steps, int) and steps >= 1):
        raise SettingsError(f"undo takes a number of steps >= 1, got {steps!r}")
    if steps > len(edits):
        raise EditError(
            f"there {'is' if len(edits) == 1 else 'are'} only {len(edits)} edit"
            f"{'' if len(edits) == 1 else 's'} to undo" if edits else "there are no edits to undo"
        )
    keep, taken = edits[: len(edits) - steps], edits[len(edits) - steps:]
    rebuilt, skipped = replay(without_edits(character), keep)
    if skipped:  # cannot happen for edits that applied before; never lose them silently
        raise EditError(f"an earlier edit no longer applies: {skipped[0][1]}")
    return dataclasses.replace(rebuilt, undone=(*taken, *character.undone)), taken


def redo(character: Character, steps: int = 1) -> tuple[Character, tuple[Edit, ...]]:
    """Make again the last ``steps`` undone edits; returns ``(character, redone edits)``."""
    undone = character.undone
    if not (isinstance(steps, int) and steps >= 1):
        raise SettingsError(f"redo takes a number of steps >= 1, got {steps!r}")
    if steps > len(undone):
        raise EditError(f"there {'is' if len(undone) == 1 else 'are'} only {len(undone)} undone "
                        f"edit{'' if len(undone) == 1 else 's'} to redo" if undone
                        else "there is nothing to redo")
    again = undone[:steps]
    for edit in again:
        character = _applied(character, edit)
    return dataclasses.replace(character, undone=undone[steps:]), again


def without_edits(character: Character) -> Character:
    """The character as rigging left it: the automatic decomposition, every region at depth 0."""
    binding = decompose(character.mesh, character.skeleton, character.mask,
                        rule=character.settings.decomposition)
    depth = np.zeros(len(character.skeleton.bones), dtype=np.int64)
    return dataclasses.replace(character, binding=binding, depth=depth, edits=(), undone=())


def describe(edit: Edit) -> str:
    """One line for listings."""
    if isinstance(edit, Correction):
        return f"attach {len(edit.curve)}-point region to bone {edit.bone}"
    where = edit.bone  # a depth edit has a bone or a point, exactly one
    if edit.at is not None:
        where = f"the region at ({edit.at[0]:.0f}, {edit.at[1]:.0f})"
    return f"depth {edit.value} for {where}"


def region_at(character: Character, point: tuple[float, float] | NDArray[np.float64]) -> int:
    """The bone (index) whose region holds the rest-mesh vertex nearest ``point``; an
    :class:`EditError` when no vertex is within two mesh spacings (a point off the drawing)."""
    V = character.mesh.V
    distance = np.hypot(V[:, 0] - point[0], V[:, 1] - point[1])
    vertex = int(np.argmin(distance))
    reach = character.mesh.pick_reach
    if distance[vertex] > reach:
        raise EditError(f"no part of the drawing is at ({point[0]:.0f}, {point[1]:.0f}): the nearest is "
                        f"{distance[vertex]:.0f} px away (at most {reach:.0f}); pick a point on the drawing")
    return int(character.binding.bone[vertex])


def _applied(character, edit):
    names = character.skeleton.bone_names
    if isinstance(edit, Correction):
        binding = attach_inside(character.binding, character.mesh, character.skeleton,
                                edit.curve, edit.bone)
        character = dataclasses.replace(character, binding=binding)
    elif isinstance(edit, DepthEdit):
        if edit.bone is not None:
            if edit.bone not in names:
                raise EditError(f"no bone is called {edit.bone!r}; the bones are: {', '.join(names)}")
            b = names.index(edit.bone)
        else:
            b = region_at(character, edit.at)
        depth = np.array(character.depth)
        depth[b] = edit.value
        character = dataclasses.replace(character, depth=depth)
    else:
        raise EditError(f"unknown edit {type(edit).__name__}")
    return dataclasses.replace(character, edits=(*character.edits, edit))
