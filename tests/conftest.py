"""Shared fixtures: paths to the real drawings and motion clips in ../shared/data, rigged
characters cached for the session, and the check behind tests of known design gaps.

Tests that need the data skip when the folder is absent, except under CI=true, where a missing
folder is a failure (CI always has it beside the clone).
"""

import os
from pathlib import Path

import pytest

SHARED_DATA = Path(
    os.environ.get("TOONMOTION_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data")
)
DRAWINGS_DIR = SHARED_DATA / "drawings"
# The name that stands for the bundled sample character wherever drawings are named.
SAMPLE = "sample"


def _require(path):
    if not path.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"shared data missing under CI: {path}")
        pytest.skip(f"shared data not found at {path}")
    return path


def drawing_names():
    """Names of the shared drawings (empty when the data is absent)."""
    if not DRAWINGS_DIR.is_dir():
        return ["<missing>"]
    return sorted(p.name for p in DRAWINGS_DIR.iterdir() if (p / "texture.png").is_file())


@pytest.fixture(params=drawing_names())
def drawing_dir(request):
    """Each shared drawing's folder: texture.png, mask.png, char_cfg.yaml."""
    return _require(DRAWINGS_DIR) / request.param


@pytest.fixture
def drawings_root():
    return _require(DRAWINGS_DIR)


def rig_character(folder=None):
    """The bundled sample (``folder`` None) or the shared drawing in ``folder``, rigged with its own
    mask and char_cfg skeleton."""
    from toonmotion.io.drawing_folder import rig_drawing_folder
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    if folder is None:
        rgba, skeleton = sample_character()
        return rig_drawing(rgba, skeleton=skeleton)
    return rig_drawing_folder(folder)


class RiggedDrawings:
    """Characters by name (``"sample"`` or a shared drawing's folder name), each rigged at most once,
    and their deformers by name and :class:`DeformSettings` fields, each built at most once."""

    def __init__(self):
        self._characters, self._deformers = {}, {}

    def character(self, name):
        """The character ``name``; skips (fails under CI) when a shared drawing is absent."""
        if name not in self._characters:
            self._characters[name] = rig_character(None if name == SAMPLE else _require(DRAWINGS_DIR) / name)
        return self._characters[name]

    def deformer(self, name, **settings):
        """A Deformer of character ``name`` with ``DeformSettings(**settings)``."""
        from toonmotion.deform.deformer import Deformer, DeformSettings

        key = (name, tuple(sorted(settings.items())))
        if key not in self._deformers:
            self._deformers[key] = Deformer(self.character(name), DeformSettings(**settings))
        return self._deformers[key]


@pytest.fixture(scope="session")
def rigs():
    """The session's :class:`RiggedDrawings`: every test module shares its rigs."""
    return RiggedDrawings()


def expect_every_case_to_fail(cases):
    """Run every case of one known design gap, for a test marked
    ``xfail(strict=True, raises=AssertionError, reason=<the gap>)``.

    ``cases`` maps a case's name to a callable that raises AssertionError when the case fails.
    Every case fails: an AssertionError naming them, so the test xfails. None fails: nothing is
    raised and the strict xfail reports the test as a failure (XPASS). Only some fail: a plain
    failure naming the cases that now pass, so that a fixed case cannot hide behind the others (move
    it to its plain test). Any other exception propagates and, not being an AssertionError, fails
    the test.
    """
    failures, passing = [], []
    for name, check in cases.items():
        try:
            check()
        except AssertionError as error:
            failures.append(f"{name}: {str(error).strip().splitlines()[0] if str(error).strip() else ''}")
        else:
            passing.append(name)
    if failures and passing:
        pytest.fail(f"known-failing cases now pass: {', '.join(passing)}; move them to their plain tests "
                    f"(still failing: {'; '.join(failures)})", pytrace=False)
    if failures:
        raise AssertionError(f"{len(failures)} of {len(cases)} cases fail: " + "; ".join(failures))


def run_cli(*argv):
    """Run the command line in-process; return its exit code (output goes where pytest captures it)."""
    from toonmotion.cli import main

    try:
        main([str(a) for a in argv])
    except SystemExit as stop:
        return 0 if stop.code is None else stop.code
    return 0
