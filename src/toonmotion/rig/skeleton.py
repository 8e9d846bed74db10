"""Animation skeleton: named joints with parents and rest positions.

A skeleton is a forest: every joint has at most one parent, and a joint with none is a root
(a hat tracked apart from a man is a second root). A *bone* joins a joint to its parent and is
named after the child joint. Joints are stored parents first.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion import limits
from toonmotion.errors import SkeletonError
from toonmotion.geometry.arrays import finite_point, frozen_array

# Bones shorter than this (pixels) have no direction: nothing attaches to them.
MIN_BONE_LENGTH = 1e-6


@dataclass(frozen=True, eq=False)
class Skeleton:
    """Joints, their parents and their rest positions.

    Attributes
    ----------
    names : tuple of str
        Unique joint names.
    parents : (k,) int
        Index of each joint's parent, -1 for a root; parents come before their children.
    positions : (k, 2) float
        Rest positions, (x, y) pixels, y down.

    Construction copies the arrays (read-only) and raises :class:`SkeletonError` unless the
    names are distinct non-empty strings, each parent is -1 or an earlier joint, and the
    positions are finite, one row per joint. :meth:`from_joints` builds one from joints in any
    order.
    """

    names: tuple[str, ...]
    parents: NDArray[np.int64]
    positions: NDArray[np.float64]

    def __post_init__(self) -> None:
        names = tuple(self.names)
        limits.check("joints", len(names), "the skeleton's joint count")
        if not all(isinstance(n, str) and n.strip() for n in names):
            raise SkeletonError("every joint needs a name: a non-empty string")
        if len(set(names)) != len(names):
            twice = next(n for n in names if names.count(n) > 1)
            raise SkeletonError(f"joint name {twice!r} is used twice; names must be unique")
        k = len(names)
        parents = frozen_array(self.parents, dtype=np.int64, shape=(k,), name="a skeleton's parents",
                               error=SkeletonError)
        if np.any((parents < -1) | (parents >= np.arange(k))):
            raise SkeletonError("a skeleton's parents must be -1 (a root) or an earlier joint: parents first")
        positions = frozen_array(self.positions, dtype=np.float64, shape=(k, 2),
                                 name="a skeleton's positions", error=SkeletonError, coordinates=True)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "parents", parents)
        object.__setattr__(self, "positions", positions)

    @classmethod
    def from_joints(cls, joints: Iterable[tuple[str, str | None, Any]]) -> Skeleton:
        """Build from ``(name, parent_name_or_None, (x, y))`` triples in any order.

        Raises :class:`SkeletonError` on duplicate or empty names, unknown parents, cycles and
        non-finite positions.

        Examples
        --------
        >>> s = Skeleton.from_joints([("hand", "arm", (9, 0)), ("arm", None, (0, 0))])
        >>> s.names, s.parents.tolist()
        (('arm', 'hand'), [-1, 0])
        """
        joints = list(joints)
        if not joints:
            raise SkeletonError("the skeleton has no joints; give at least one")
        limits.check("joints", len(joints), "the skeleton's joint count")
        names = [str(j[0]) for j in joints]
        seen = set()
        for name in names:
            if not name.strip():
                raise SkeletonError("a joint has an empty name; give every joint a name")
            if name in seen:
                raise SkeletonError(f"joint name {name!r} is used twice; names must be unique")
            seen.add(name)
        parent_of = {}
        for name, parent, _ in joints:
            if parent is not None and parent not in seen:
                raise SkeletonError(
                    f"joint {name!r} names an unknown parent {parent!r}; "
                    "every parent must be one of the skeleton's joints"
                )
            parent_of[name] = parent
        order = _parents_first(names, parent_of)
        index = {name: i for i, name in enumerate(order)}
        position_of = {str(j[0]): j[2] for j in joints}
        positions = np.array([finite_point(position_of[n], name=f"joint {n!r}", error=SkeletonError)
                              for n in order], dtype=float)
        parents = np.array([index[parent_of[n]] if parent_of[n] else -1 for n in order])
        return cls(names=tuple(order), parents=parents.astype(np.int64), positions=positions)

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        """Index of the joint called ``name``."""
        try:
            return self.names.index(name)
        except ValueError:
            raise SkeletonError(
                f"no joint is called {name!r}; the joints are: {', '.join(self.names)}"
            ) from None

    @property
    def bones(self) -> NDArray[np.int64]:
        """Bones as ``(parent, child)`` joint indices, ``(b, 2)``, one per non-root joint."""
        child = np.flatnonzero(self.parents >= 0)
        return np.stack([self.parents[child], child], axis=1)

    @property
    def bone_names(self) -> tuple[str, ...]:
        """Each bone's name: its child joint's name."""
        return tuple(self.names[c] for c in self.bones[:, 1])

    @property
    def bone_lengths(self) -> NDArray[np.float64]:
        """Rest length of each bone in pixels, ``(b,)``."""
        b = self.bones
        return np.linalg.norm(self.positions[b[:, 1]] - self.positions[b[:, 0]], axis=1)

    def joints(self) -> list[tuple[str, str | None, tuple[float, float]]]:
        """The skeleton as ``(name, parent_name_or_None, (x, y))`` triples, parents first."""
        return [
            (n, self.names[p] if p >= 0 else None, (float(x), float(y)))
            for n, p, (x, y) in zip(self.names, self.parents, self.positions, strict=True)
        ]




def _parents_first(names, parent_of):
    """Order names so every parent precedes its children; reject cycles."""
    children = {}
    for name in names:
        children.setdefault(parent_of[name], []).append(name)
    order, stack = [], list(reversed(children.get(None, [])))
    while stack:
        name = stack.pop()
        order.append(name)
        stack.extend(reversed(children.get(name, [])))
    if len(order) != len(names):
        stuck = [n for n in names if n not in set(order)]
        raise SkeletonError(
            f"the skeleton has a cycle through joints {', '.join(stuck)}; "
            "follow each joint's parent and make sure the chain ends at a root"
        )
    return order
