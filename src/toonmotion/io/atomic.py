"""Atomic writes: a file is written beside its target, then renamed over it.

A crash or error mid-write leaves the old file untouched; readers never see half a file. A
process killed mid-write cannot remove its temporary file, so each temporary name carries the
writing process's id, and the next successful write of the same target sweeps away those whose
process is gone (:func:`sweep_leftovers`).
"""

import os
import re
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path


def temporary_prefix(name):
    """The start of this process's temporary names for the target ``name``."""
    return f".{name}.{os.getpid()}."


@contextmanager
def atomic_path(path):
    """Yield a temporary path beside ``path``; on success rename it over ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=temporary_prefix(path.name), suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, _mode_for(path))  # mkstemp makes files only their owner can read
        os.replace(tmp, path)
    finally:
        Path(tmp).unlink(missing_ok=True)  # gone already after a successful rename
    sweep_leftovers(path.parent, path.name)


def sweep_leftovers(folder, name):
    """Remove temporary files or folders for the target ``name`` left by killed processes.

    Only names made by :func:`temporary_prefix` whose process no longer runs are removed; another
    process writing the same target at the same moment keeps its temporary file.
    """
    pattern = re.compile(re.escape(f".{name}.") + r"(\d+)\..*\.tmp")
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        match = pattern.fullmatch(entry.name)
        if match is None or _running(int(match.group(1))):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            else:
                os.unlink(entry.path)
        except OSError:
            pass  # gone already, or not ours to remove


def _running(pid):
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, OSError):
        return True  # someone else's process, or a number we cannot check: leave it
    return True


def _mode_for(path):
    """The replaced file's permissions, or those a new file gets under the umask."""
    try:
        return os.stat(path).st_mode & 0o777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def write_bytes(path, data):
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def write_text(path, text):
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    write_bytes(path, text.encode("utf-8"))
