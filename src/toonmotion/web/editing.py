"""The project open in the editor: its character, key-frames and footage, and what is built once for
them (the deformer, the animation), shared by every page and guarded by one lock; and where in the
project folder the editor keeps what it saves."""

from __future__ import annotations

import logging
import re
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion import api
from toonmotion.animate.timeline import Timeline
from toonmotion.deform.deformer import Deformer, DeformSettings
from toonmotion.errors import (
    KeyframeError,
)
from toonmotion.io.atomic import write_text
from toonmotion.io.links import confined, no_links
from toonmotion.io.pose_json import load_keyframes, save_keyframes
from toonmotion.web.history import History

# The project folder's key-frames, in the format `toonmotion animate` reads.
KEYS_FILE = "keys.json"


# Where footage sent to the editor is kept, and the motion tracked in it, in the project folder.
FOOTAGE = "footage"


CAPTURED = "motions/captured.json"


# The upload area in the project folder: a new drawing, its mask, a skeleton file; and where the
# projects an opened drawing replaced are kept, to undo it.
UPLOADS = "uploads"


UPLOAD_PARTS = ("drawing", "mask", "skeleton")


SNAPSHOTS = "history"


# Where the editor's exports go, in the project folder; and what an export's name may be.
EXPORTS = "exports"


# The files an export may leave, which the editor serves for download, by suffix.
EXPORT_FILE = re.compile(r"(?P<stem>[A-Za-z0-9][A-Za-z0-9_-]{0,79})(?:\.spine|\.sheet)?"
                         r"\.(?P<suffix>gif|mp4|apng|webp|webm|glb|json|atlas|png|bvh)")


log = logging.getLogger("toonmotion.web")


def _deformer_for(character: api.Character) -> Deformer:
    """The editor's deformer: every drag is a solve, so it runs the compiled loop."""
    return Deformer(character, DeformSettings(compiled=True))


@dataclass
class Editing:
    """The open project, its key-frames and what is built once for them, shared by every client."""

    folder: Path
    character: api.Character
    timeline: Timeline | None = None
    lock: threading.RLock = field(default_factory=threading.RLock)
    _deformer: Deformer | None = None
    _animation: api.Animation | None = None
    _exaggerated: tuple[api.FilterSettings, api.Animation] | None = None
    footage: tuple[NDArray[np.uint8], float] | None = None  # frames and their rate
    capture: api.Capture | None = None
    captured: api.Animation | None = None  # the capture retargeted onto the character
    # The key-shape capture retargeted, and the character it was animated on (web.keyshape_requests).
    keyshaped: tuple[api.Character, api.Animation] | None = None
    # What the Capture panel last showed, to show it again after a reload: the footage as
    # ``PUT /api/footage`` described it, the joints last tracked (with their rectangles) and the
    # ``tracked`` reply; None before footage is sent.
    capture_page: dict[str, Any] | None = None
    # The motion-capture clips (.bvh) the 3D panel offers as priors, besides those sent to the
    # project (toonmotion edit --mocap DIR); None: none.
    library: Path | None = None
    _history: History | None = None

    @property
    def history(self) -> History:
        """The undo history (:mod:`toonmotion.web.history`), read from the folder once."""
        with self.lock:
            if self._history is None:
                self._history = History.open(self.folder)
            return self._history

    @classmethod
    def open(cls, folder: str | Path, *, library: str | Path | None = None) -> Editing:
        """The project in ``folder`` and its ``keys.json`` if it has one (errors name the file); a
        project holding a symbolic link is refused (:mod:`toonmotion.io.links`). ``library``: the
        folder of motion-capture priors (:attr:`library`)."""
        folder = Path(folder)
        if folder.is_dir():
            no_links(folder)
        character = api.load_project(folder)
        keys = folder / KEYS_FILE
        timeline = load_keyframes(keys, character.skeleton) if keys.is_file() else None
        return cls(folder=folder, character=character, timeline=timeline,
                   library=None if library is None else Path(library))

    def check_links(self) -> None:
        """Refuse to go on while anything under the project is a symbolic link
        (:func:`~toonmotion.io.links.no_links`): once per request that touches files, since one
        may have been made since the last."""
        no_links(self.folder)

    def path(self, *parts: str) -> Path:
        """The project's file or folder ``parts``, to read, write or delete, once checked: no part
        of it is a symbolic link and it resolves inside the project (the request has called
        :meth:`check_links` first)."""
        return confined(self.folder, self.folder.joinpath(*parts))

    @property
    def deformer(self) -> Deformer:
        with self.lock:
            if self._deformer is None:
                self._deformer = _deformer_for(self.character)
            return self._deformer

    def prepare_deformer(self) -> None:
        """Build the deformer ahead of the first drag (the server does it in a thread at start).

        The build loads Numba and the compiled loop, about 1.6 s the first time in a process, so it
        runs outside the lock, and edits made meanwhile do not wait for it; it is kept only if the
        character has not changed since. A failure leaves it to be built on demand, where the
        error reaches the page as every other does.
        """
        with self.lock:
            character = self.character
            if self._deformer is not None:
                return
        try:
            deformer = _deformer_for(character)
        except Exception as error:  # said again, to the page, when a drag builds it
            log.debug("the deformer was not prepared: %s", error)
            return
        with self.lock:
            if self._deformer is None and self.character is character:
                self._deformer = deformer

    @property
    def animation(self) -> api.Animation:
        """Every frame of the key-frames, deformed (computed once per change of keys or regions)."""
        return self.animated(None)

    def animated(self, exaggeration: api.FilterSettings | None) -> api.Animation:
        """The key-frames' animation, through the cartoon filter when ``exaggeration`` is given
        (the last exaggerated one is kept, for scrubbing and playing it)."""
        with self.lock:
            if self.timeline is None:
                raise KeyframeError("there are no key-frames yet: set a key first")
            if exaggeration is not None:
                if self._exaggerated is None or self._exaggerated[0] != exaggeration:
                    found = api.animate_character(self.deformer, self.timeline, exaggeration=exaggeration)
                    self._exaggerated = (exaggeration, found)
                return self._exaggerated[1]
            if self._animation is None:
                self._animation = api.animate_character(self.deformer, self.timeline)
            return self._animation

    def edited(self, character: api.Character) -> None:
        """Save ``character`` in the project, then make it the one edited (a failed save changes nothing)."""
        with self.lock:
            api.save_project(self.folder, character)
            self.character, self._deformer, self._animation, self._exaggerated = character, None, None, None

    def keys_text(self) -> str | None:
        """The key-frames file as saved, or None when there are no keys."""
        file = self.path(KEYS_FILE)
        return file.read_text(encoding="utf-8") if file.is_file() else None

    def restore_keys(self, text: str | None) -> None:
        """Put back the key-frames file ``text`` (None: no keys) as it was saved."""
        with self.lock:
            file = self.path(KEYS_FILE)
            if text is None:
                file.unlink(missing_ok=True)
                timeline = None
            else:
                write_text(file, text)
                timeline = load_keyframes(file, self.character.skeleton)
            self.timeline, self._animation, self._exaggerated = timeline, None, None

    def keyed(self, timeline: Timeline | None) -> None:
        """Save the key-frames (none: the file goes), then make them the ones edited."""
        with self.lock:
            file = self.path(KEYS_FILE)
            if timeline is None:
                file.unlink(missing_ok=True)
            else:
                save_keyframes(file, self.character.skeleton, timeline)
            self.timeline, self._animation, self._exaggerated = timeline, None, None
