"""toonmotion's own skeleton file: JSON, versioned.

``{"format": "toonmotion.skeleton", "version": 1, "width": W, "height": H,
"joints": [{"name": ..., "parent": ... or null, "position": [x, y]}, ...]}``
(width and height are optional: the drawing the joints were placed on).
"""

import json
from pathlib import Path

from toonmotion.errors import SkeletonError
from toonmotion.io.atomic import write_text
from toonmotion.io.json_file import read_json
from toonmotion.rig.skeleton import Skeleton

FORMAT = "toonmotion.skeleton"
VERSION = 1


def skeleton_to_dict(skeleton):
    """The ``joints`` list of a skeleton, as JSON-ready dicts, parents first."""
    return [
        {"name": name, "parent": parent, "position": [x, y]}
        for name, parent, (x, y) in skeleton.joints()
    ]


def skeleton_from_dict(joints, *, where="skeleton"):
    """Build a Skeleton from a ``joints`` list as written by :func:`skeleton_to_dict`."""
    if not isinstance(joints, list):
        raise SkeletonError(f"{where}: 'joints' must be a list")
    triples = []
    for i, joint in enumerate(joints):
        if not isinstance(joint, dict) or not {"name", "position"} <= joint.keys():
            raise SkeletonError(f"{where}: joint {i + 1} needs a 'name' and a 'position: [x, y]'")
        triples.append((joint["name"], joint.get("parent"), joint["position"]))
    return Skeleton.from_joints(triples)


def load_skeleton_json(path):
    """Read a skeleton JSON file; returns ``(skeleton, (width, height) or None)``."""
    path = Path(path)
    data = read_json(path, SkeletonError)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise SkeletonError(f"{path} is not a toonmotion skeleton file (format {FORMAT!r})")
    if data.get("version") != VERSION:
        raise SkeletonError(
            f"{path} is skeleton format version {data.get('version')!r}; this toonmotion reads "
            f"version {VERSION}"
        )
    size = None
    if "width" in data or "height" in data:
        try:
            size = (int(data["width"]), int(data["height"]))
        except (KeyError, TypeError, ValueError):
            raise SkeletonError(f"{path}: width and height must be whole numbers") from None
    return skeleton_from_dict(data.get("joints"), where=str(path)), size


def save_skeleton_json(path, skeleton, size=None):
    """Write a skeleton JSON file atomically."""
    data = {"format": FORMAT, "version": VERSION}
    if size is not None:
        data.update(width=int(size[0]), height=int(size[1]))
    data["joints"] = skeleton_to_dict(skeleton)
    write_text(path, json.dumps(data, indent=1) + "\n")


def load_skeleton_file(path, *, image_size=None):
    """Read a skeleton from a char_cfg ``.yaml``/``.yml`` or a toonmotion ``.json`` file.

    Parameters
    ----------
    image_size : (width, height), optional
        The drawing's size; a file annotated on a drawing of another size is an error.
    """
    from toonmotion.io.char_cfg import load_char_cfg

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix in (".yaml", ".yml"):
        skeleton, size = load_char_cfg(path)
    elif suffix == ".json":
        skeleton, size = load_skeleton_json(path)
    else:
        raise SkeletonError(
            f"cannot tell the skeleton format of {path.name}: use a char_cfg .yaml or a .json file"
        )
    if image_size is not None and size is not None and tuple(size) != tuple(image_size):
        raise SkeletonError(
            f"{path.name} was made for a {size[0]}x{size[1]} drawing but this one is "
            f"{image_size[0]}x{image_size[1]}; use the skeleton made for this drawing"
        )
    return skeleton
