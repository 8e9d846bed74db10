"""Animated Drawings ``char_cfg.yaml`` skeleton files.

The format: ``width`` and ``height`` of the drawing, and ``skeleton``, a list of joints
``{name, parent, loc: [x, y]}`` in pixels (x right, y down), ``parent: null`` for the root.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from toonmotion import limits
from toonmotion.errors import SkeletonError
from toonmotion.io.atomic import write_text
from toonmotion.rig.skeleton import Skeleton


def load_char_cfg(path: str | Path) -> tuple[Skeleton, tuple[int, int] | None]:
    """Read a char_cfg.yaml.

    Returns
    -------
    skeleton : Skeleton
    size : (width, height) or None
        The drawing size the joints were placed on, when the file gives it.
    """
    path = Path(path)
    try:
        limits.check("file_bytes", path.stat().st_size, f"{path.name}'s size in bytes")
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SkeletonError(f"cannot read {path}: no such file") from None
    except RecursionError:
        raise SkeletonError(f"cannot read {path}: its lists or mappings are nested too deeply") from None
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as error:
        problem = str(error).splitlines()[0] if str(error) else type(error).__name__
        raise SkeletonError(f"cannot read {path} as YAML: {problem}") from None
    if not isinstance(data, dict) or not isinstance(data.get("skeleton"), list):
        raise SkeletonError(f"{path} has no 'skeleton' list of joints; is it a char_cfg.yaml?")
    joints: list[tuple[str, str | None, Any]] = []
    for i, joint in enumerate(data["skeleton"]):
        if not isinstance(joint, dict) or not {"name", "loc"} <= joint.keys():
            raise SkeletonError(f"{path}: joint {i + 1} needs a 'name' and a 'loc: [x, y]'")
        parent = joint.get("parent")
        joints.append((str(joint["name"]), None if parent is None else str(parent), joint["loc"]))
    size = None
    if "width" in data and "height" in data:
        try:
            size = (int(data["width"]), int(data["height"]))
        except (TypeError, ValueError):
            raise SkeletonError(f"{path}: width and height must be whole numbers") from None
    return Skeleton.from_joints(joints), size


def save_char_cfg(path: str | Path, skeleton: Skeleton, size: tuple[int, int]) -> None:
    """Write a skeleton as a char_cfg.yaml for a drawing of ``size`` (width, height)."""
    data = {
        "width": int(size[0]),
        "height": int(size[1]),
        "skeleton": [
            {"name": name, "parent": parent, "loc": [round(x, 3), round(y, 3)]}
            for name, parent, (x, y) in skeleton.joints()
        ],
    }
    write_text(path, yaml.safe_dump(data, sort_keys=False))
