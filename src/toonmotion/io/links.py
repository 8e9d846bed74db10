"""Keep file work inside a folder: no symbolic link under it is followed.

A project folder can come from anyone (shared, unpacked from an archive). A link inside it
(``exports/leak.gif -> /etc/passwd``, ``footage/frames -> ~/Documents``) would let the editor
read, overwrite or delete files outside the project on a request about the project's own. The
editor therefore works on a project only while nothing under it is a link (:func:`no_links`),
and checks the very path it touches besides (:func:`confined`), each time.
"""

from __future__ import annotations

import os
from pathlib import Path

from toonmotion.errors import LinkError

_ADVICE = "the editor reads, writes and deletes only the project's own files: remove the link " \
          "(or put a copy of what it points to in its place)"


def no_links(root: str | Path) -> None:
    """Raise :class:`LinkError` naming the first symbolic link found under the folder ``root``
    (``root`` itself may be one: the user chose it). Links are not followed."""
    root = Path(root)
    pending = [root]
    while pending:
        folder = pending.pop()
        try:
            entries = list(os.scandir(folder))
        except FileNotFoundError:
            continue
        for entry in entries:
            if entry.is_symlink() or _is_junction(entry.path):
                link = _shown(root, Path(entry.path))
                raise LinkError(f"{link} in the project is a symbolic link; {_ADVICE}")
            if entry.is_dir(follow_symlinks=False):
                pending.append(Path(entry.path))


def confined(root: str | Path, path: str | Path) -> Path:
    """``path``, a path under the folder ``root``, once checked: no part of it below ``root`` is a
    symbolic link, and it resolves inside ``root``; else :class:`LinkError`. Parts that do not
    exist yet pass (a file about to be written)."""
    root, path = Path(root), Path(path)
    try:
        parts = path.relative_to(root).parts
    except ValueError:
        raise LinkError(f"{path} is not in the project {root}") from None
    if ".." in parts:
        raise LinkError(f"{_shown(root, path)} leaves the project")
    current = root
    for part in parts:
        current = current / part
        if current.is_symlink() or _is_junction(current):
            raise LinkError(f"{_shown(root, current)} in the project is a symbolic link; {_ADVICE}")
    if not path.resolve().is_relative_to(root.resolve()):
        raise LinkError(f"{_shown(root, path)} leaves the project")
    return path


def _is_junction(path: str | Path) -> bool:
    """Whether ``path`` is a Windows directory junction (a link :meth:`Path.is_symlink` misses)."""
    check = getattr(os.path, "isjunction", None)  # Python 3.12+
    return bool(check is not None and check(path))


def _shown(root: Path, path: Path) -> str:
    """``path`` as the user knows it: relative to the project, with forward slashes."""
    try:
        return path.relative_to(root).as_posix()
    except ValueError:
        return str(path)
