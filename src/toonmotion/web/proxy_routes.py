"""The 3D panel's HTTP requests: a motion-capture clip sent as a prior (``PUT /api/priors``), kept
in the project's ``proxy3d/priors/``; the animation's frames a proxy was lifted from (``GET
/api/proxy/frames/{index}.png``) and the scene's composited frames (``GET
/api/scene/{index}.png``). Files are named by the server: a prior's name is cut to a safe stem."""

from __future__ import annotations

import asyncio
import re
from typing import Any

from fastapi import FastAPI, Request
from fastapi.responses import FileResponse
from starlette.exceptions import HTTPException

from toonmotion.errors import ToonmotionError
from toonmotion.io.bvh import load_bvh
from toonmotion.web.editing import Editing
from toonmotion.web.proxy_requests import DRAWN_FRAMES, PRIORS, PROXY_DIR, SCENE_FRAMES, UPLOADED, priors
from toonmotion.web.uploads import as_sent, receive_body

# What a sent prior's file is called in the project: its own name's letters, digits, '-' and '_'.
_UNSAFE = re.compile(r"[^A-Za-z0-9_-]+")


def add_proxy_routes(app: FastAPI, editing: Editing) -> None:
    """Serve the 3D panel's HTTP requests for ``editing``'s project on ``app``."""

    @app.put("/api/priors")
    async def prior(request: Request, name: str = "") -> dict[str, Any]:
        """A ``.bvh`` clip, the request's body, read at once and kept as a prior of the project's;
        the reply lists the priors and names the one sent."""
        stem = _UNSAFE.sub("_", name.rsplit(".", 1)[0] if name.lower().endswith(".bvh") else name)
        stem = stem.strip("_")[:64] or "prior"
        editing.check_links()
        folder = editing.path(PROXY_DIR, PRIORS)
        folder.mkdir(parents=True, exist_ok=True)
        file = folder / f"{stem}.bvh"
        await receive_body(request, file, "the clip")
        with as_sent(file, name or "the clip sent"):
            try:
                clip = await asyncio.to_thread(load_bvh, file)
            except ToonmotionError:
                file.unlink(missing_ok=True)
                raise
        return {"priors": priors(editing), "sent": f"{UPLOADED}/{file.name}", "frames": len(clip.motion),
                "joints": len(clip.names)}

    @app.get("/api/scene/{index}.png")
    def scene_frame(index: int) -> FileResponse:
        return _frame(editing, SCENE_FRAMES, index, "scene frame")

    @app.get("/api/proxy/frames/{index}.png")
    def drawn_frame(index: int) -> FileResponse:
        """The animation's frame ``index`` the proxy was lifted from (its camera's pixels)."""
        return _frame(editing, DRAWN_FRAMES, index, "lifted frame")


def _frame(editing: Editing, folder: str, index: int, what: str) -> FileResponse:
    editing.check_links()
    file = editing.path(PROXY_DIR, folder, f"{index:04d}.png")
    if index < 0 or not file.is_file():
        raise HTTPException(404, f"no {what} {index}")
    return FileResponse(file, media_type="image/png")
