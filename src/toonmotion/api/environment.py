"""What toonmotion runs on, for bug reports: ``toonmotion doctor``.

The versions of the libraries whose behaviour shows in results (NumPy, SciPy, OpenCV, Pillow,
MuJoCo, the bundled FFmpeg, ...), and whether the tools used around toonmotion are found: Debian's
Chromium (the editor's browser tests) and the Khronos glTF validator (the glTF tests, installed by
``npm ci`` in a checkout). Nothing here changes anything or reaches the network.

>>> report = environment_report()
>>> report[0].name, report[0].found
('toonmotion', True)
>>> "numpy" in [item.name for item in report]
True
"""

from __future__ import annotations

import json
import platform
import shutil
import subprocess
import sys
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

from toonmotion import __version__

# The distributions whose version matters to a result, and the name to show each by.
_LIBRARIES = (
    ("numpy", "numpy"), ("scipy", "scipy"), ("opencv", "opencv-contrib-python-headless"),
    ("pillow", "pillow"), ("scikit-image", "scikit-image"), ("shapely", "shapely"),
    ("mujoco", "mujoco"), ("numba", "numba"), ("imageio", "imageio"), ("imageio-ffmpeg", "imageio-ffmpeg"),
    ("pydantic", "pydantic"), ("fastapi", "fastapi"), ("uvicorn", "uvicorn"), ("daqp", "daqp"),
    ("dtaidistance", "dtaidistance"), ("pygltflib", "pygltflib"),
)


@dataclass(frozen=True)
class EnvironmentItem:
    """One line of the report.

    Attributes
    ----------
    name : str
        What it is (``numpy``, ``ffmpeg``, ``chromium``).
    version : str
        Its version, or why it is not there.
    found : bool
        False when it is missing; a missing optional tool is not an error.
    where : str
        Where it was found (a path), or ``""``.
    """

    name: str
    version: str
    found: bool
    where: str = ""


def environment_report(*, cwd: Path | None = None) -> list[EnvironmentItem]:
    """toonmotion, Python, the libraries that matter, FFmpeg, Chromium and the glTF validator.

    Parameters
    ----------
    cwd : Path, optional
        Where to look for ``node_modules/gltf-validator`` (and in its parents); the working folder
        by default.

    Returns
    -------
    list of EnvironmentItem
        In the order a bug report lists them.

    Examples
    --------
    >>> import numpy as np
    >>> numpy = {item.name: item for item in environment_report()}["numpy"]
    >>> numpy.found, numpy.version == np.__version__
    (True, True)
    """
    report = [
        EnvironmentItem("toonmotion", __version__, True, str(Path(__file__).resolve().parents[1])),
        EnvironmentItem("python", platform.python_version(), True, sys.executable),
        EnvironmentItem("platform", platform.platform(), True),
    ]
    report += [_library(shown, distribution) for shown, distribution in _LIBRARIES]
    report += [_ffmpeg(), _chromium(), _gltf_validator(Path.cwd() if cwd is None else cwd)]
    return report


def _library(shown: str, distribution: str) -> EnvironmentItem:
    try:
        return EnvironmentItem(shown, metadata.version(distribution), True)
    except metadata.PackageNotFoundError:
        return EnvironmentItem(shown, "not installed", False)


def _ffmpeg() -> EnvironmentItem:
    try:
        import imageio_ffmpeg

        exe = imageio_ffmpeg.get_ffmpeg_exe()
        return EnvironmentItem("ffmpeg", imageio_ffmpeg.get_ffmpeg_version(), True, exe)
    except (ImportError, RuntimeError, OSError) as error:
        return EnvironmentItem("ffmpeg", f"not found ({error}); MP4 and WebM cannot be written", False)


def _chromium() -> EnvironmentItem:
    found = next(filter(None, map(shutil.which, ("chromium", "chromium-browser", "google-chrome"))), None)
    if found is None:
        return EnvironmentItem("chromium", "not found (only the editor's browser tests use it)", False)
    return EnvironmentItem("chromium", _first_line([found, "--version"]) or "unknown version", True, found)


def _gltf_validator(cwd: Path) -> EnvironmentItem:
    folder = next((p / "node_modules" / "gltf-validator" for p in (cwd, *cwd.parents)
                   if (p / "node_modules" / "gltf-validator" / "package.json").is_file()), None)
    if folder is None:
        return EnvironmentItem("gltf-validator", "not found (for the glTF tests: npm ci in a checkout)",
                               False)
    version = json.loads((folder / "package.json").read_text(encoding="utf-8")).get("version", "unknown")
    node = shutil.which("node")
    if node is None:
        return EnvironmentItem("gltf-validator", f"{version}, but node is not installed", False, str(folder))
    node_version = _first_line([node, "--version"])
    return EnvironmentItem("gltf-validator", f"{version} (node {node_version})", True, str(folder))


def _first_line(command: list[str]) -> str:
    """The first line a program prints, or ``""`` when it fails or takes over 20 s."""
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=20, check=False)
    except (OSError, subprocess.SubprocessError):
        return ""
    return (done.stdout.strip().splitlines() or [""])[0]
