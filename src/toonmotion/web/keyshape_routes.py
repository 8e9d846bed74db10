"""The Key-shapes panel's HTTP routes (:func:`add_routes`, called by
:func:`toonmotion.web.server.create_app`): the model's in-between sheet, and the outlines or contours
files sent to the panel. As every route of the editor, the files are named by the server, never by
the request, and every error is one line (:mod:`toonmotion.web.server`)."""

from __future__ import annotations

import asyncio
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse
from starlette.exceptions import HTTPException

from toonmotion.errors import ToonmotionError
from toonmotion.web.editing import Editing
from toonmotion.web.keyshape_messages import MOST_POINTS
from toonmotion.web.keyshape_requests import (
    KEYSHAPES,
    OUTLINE_SUFFIXES,
    SHEET,
    UPLOAD_PARTS,
    read_upload,
)
from toonmotion.web.uploads import receive_body


def add_routes(app: FastAPI, editing: Editing) -> None:
    """``GET /api/keyshapes/sheet.png`` and ``PUT /api/keyshapes/{outlines|contours}?suffix=&points=``."""

    @app.get("/api/keyshapes/sheet.png")
    def sheet() -> FileResponse:
        editing.check_links()
        file = editing.path(KEYSHAPES, SHEET)
        if not file.is_file():
            raise HTTPException(404, "there is no key-shape model yet")
        return FileResponse(file, media_type="image/png")

    @app.put("/api/keyshapes/{part}")
    async def upload(request: Request, part: str, suffix: str, points: int | None = None,
                     name: str = "") -> dict[str, Any]:
        """Key outlines to add, or contours to capture, the request's body: a contours file (JSON,
        CSV) or SVG, read as the CLI reads it (``points``: each resampled to that many)."""
        if part not in UPLOAD_PARTS:
            raise HTTPException(404, f"the key-shapes panel takes {' or '.join(UPLOAD_PARTS)}, "
                                     f"not {part[:20]!r}")
        if suffix.lower() not in OUTLINE_SUFFIXES:
            raise HTTPException(400, f"send outlines as {', '.join(OUTLINE_SUFFIXES)}, not {suffix[:10]!r}")
        if points is not None and not 3 <= points <= MOST_POINTS:
            raise HTTPException(400, f"points must be 3 to {MOST_POINTS:,}, got {points}")
        editing.check_links()
        file = editing.path(KEYSHAPES, f"sent-{part}.{suffix.lower()}")
        await receive_body(request, file, "the file")
        try:
            return await asyncio.to_thread(read_upload, editing, part, file, points)
        except ToonmotionError as error:
            said = str(error).replace(str(file), file.name).replace(file.name, name[:200] or "the file sent")
            raise HTTPException(400, said) from None
