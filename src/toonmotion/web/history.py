"""The editor's undo history: every kind of edit, kept in the project folder so it survives a
reload and a restart.

``PROJECT/history.json`` holds two stacks, ``done`` and ``undone``, of entries:

* ``{"kind": "regions", "count": n}``: a region edit (depth, lasso). The edit itself lives in
  the project's own edit history (``toonmotion undo`` and ``edits`` see it); ``count`` is how
  many edits the project had after it, to check that the two histories still agree.
* ``{"kind": "keys", "before": text or null, "after": text or null}``: the key-frames file
  before and after a key edit (set, move, delete, timing, fine-tuning), ``null`` for none.
* ``{"kind": "rig", "before": joints, "after": joints, "keys_before": text or null,
  "keys_after": text or null}``: the skeleton before and after rigging again, each
  ``[[name, parent or null, [x, y]], ...]``, and the key-frames file before and after (the keys
  follow the joints moved); an entry saved without the keys leaves them as they are.
* ``{"kind": "drawing", "before": folder, "after": folder}``: a new drawing opened into the
  project; the projects before and after it are kept whole in ``history/<folder>``.

This module keeps the stacks; :mod:`toonmotion.web.session` applies an entry. Each change is
written atomically after the edit it records is saved, so a server killed in between leaves a
history one entry short, never one that names an edit that was not made; an entry that no
longer matches the project (changed outside the editor) is refused and the history cleared.
"""

from __future__ import annotations

import json
import logging
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from toonmotion.io.atomic import write_text

HISTORY_FILE = "history.json"
FORMAT, VERSION = "toonmotion-editor-history", 1
# The most edits kept to undo; older ones are dropped (a region edit stays in the project's
# own history, which `toonmotion undo` still reaches).
MAX_ENTRIES = 500

log = logging.getLogger("toonmotion.web")

Entry = dict[str, Any]


@dataclass
class History:
    """The undo and redo stacks of one project folder (newest last)."""

    folder: Path
    done: list[Entry] = field(default_factory=list)
    undone: list[Entry] = field(default_factory=list)

    @classmethod
    def open(cls, folder: Path) -> History:
        """The folder's history; an unreadable one starts afresh (the edits themselves are safe
        in the project) and says so in the log."""
        file = folder / HISTORY_FILE
        try:
            data = json.loads(file.read_text(encoding="utf-8")) if file.is_file() else {}
            if data and (data.get("format") != FORMAT or data.get("version") != VERSION):
                raise ValueError(f"not a {FORMAT} file, version {VERSION}")
            done, undone = data.get("done", []), data.get("undone", [])
            if not (isinstance(done, list) and isinstance(undone, list)
                    and all(_is_entry(e) for e in done + undone)):
                raise ValueError("malformed entries")
        except (OSError, ValueError, RecursionError) as error:
            log.warning("starting a new undo history: cannot read %s (%s)", file, error)
            done, undone = [], []
        return cls(folder=folder, done=done, undone=undone)

    def record(self, entry: Entry) -> None:
        """A new edit: it can be undone, and nothing undone before it can be redone."""
        self.done = [*self.done, entry][-MAX_ENTRIES:]
        self.undone = []
        self.save()

    def moved(self, entry: Entry, *, undo: bool) -> None:
        """``entry`` was undone (``undo``) or redone: move it to the other stack."""
        source, target = (self.done, self.undone) if undo else (self.undone, self.done)
        if source and source[-1] is entry:
            source.pop()
        target.append(entry)
        self.save()

    def clear(self) -> None:
        self.done, self.undone = [], []
        self.save()

    def counts(self) -> dict[str, int]:
        """How many edits there are to undo and to redo."""
        return {"undo": len(self.done), "redo": len(self.undone)}

    def save(self) -> None:
        text = json.dumps({"format": FORMAT, "version": VERSION, "done": self.done, "undone": self.undone})
        write_text(self.folder / HISTORY_FILE, text)


def _is_entry(entry: Any) -> bool:
    if not isinstance(entry, dict):
        return False
    kind = entry.get("kind")
    if kind == "regions":
        return isinstance(entry.get("count"), int)
    if kind in ("keys", "rig", "drawing"):
        return "before" in entry and "after" in entry
    return False
