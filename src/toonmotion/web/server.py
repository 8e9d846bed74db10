"""The editor's server: the page, the open project's data, and live posing over a WebSocket.

Security, as notebook servers do it: the server binds 127.0.0.1; every request carries the
random per-launch token (``?token=`` or the ``X-Toonmotion-Token`` header); a request from a
browser page must come from the editor's own origin. Files are named by the server, never by the
request: nothing outside the package's page and the project folder is read.

Errors come back as one line: a 4xx reply ``{"error": "..."}`` over HTTP, a
``{"type": "error", "message": "..."}`` message over the WebSocket; a malformed message never
closes the connection and never shows a traceback.

The WebSocket protocol (JSON text messages; ``id`` is echoed back):

* ``{"id": 1, "type": "pose", "positions": [[x, y], ...]}``: every joint's position, in the
  skeleton's order. Reply: ``{"id": 1, "type": "mesh", "U": [x0, y0, x1, y1, ...]}``, the
  deformed vertices (the needle model, then the joint-area solve).
* ``{"type": "overlaps", "positions": [...]}``: the regions that overlap at the same depth in
  that pose. Reply: ``{"type": "overlaps", "pairs": [{"a": bone, "b": bone, "area": px2}]}``.
* Edits of the regions, each saved in the project before the reply (atomic writes, as the
  CLI's), each recorded for undo: ``{"type": "depth", "at": [x, y], "by": 1}`` (the region
  there one layer up or down), ``{"type": "correct", "bone": name, "curve": [[x, y], ...]}``
  (a lasso), ``{"type": "undo"}``, ``{"type": "redo"}``. Reply: ``{"type": "regions", ...}``
  with the regions as :func:`regions` gives them.
"""

from __future__ import annotations

import hmac
import json
import logging
import secrets
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from fastapi import FastAPI, Request, WebSocket, WebSocketDisconnect
from fastapi.responses import FileResponse, JSONResponse, Response
from numpy.typing import NDArray
from starlette.exceptions import HTTPException

from toonmotion import api
from toonmotion.deform.deformer import Deformer
from toonmotion.deform.depth import draw_order
from toonmotion.errors import EditError, PoseError, ToonmotionError
from toonmotion.io.image import png_bytes
from toonmotion.rig.pose import Pose, check_pose

STATIC = Path(__file__).parent / "static"
# The page's own files: nothing else under STATIC, and nothing outside it, is served.
PAGE_FILES = {"index.html": "text/html", "editor.css": "text/css", "app.js": "text/javascript",
              "mesh_view.js": "text/javascript", "pose_panel.js": "text/javascript",
              "regions_panel.js": "text/javascript"}
# A WebSocket message longer than this is refused unread (a pose of 10,000 joints fits easily).
MAX_MESSAGE_BYTES = 1_000_000

log = logging.getLogger("toonmotion.web")


def new_token() -> str:
    """A random per-launch token."""
    return secrets.token_urlsafe(24)


@dataclass
class Editing:
    """The open project and what is built once for it (the deformer), shared by every client."""

    folder: Path
    character: api.Character
    lock: threading.Lock = field(default_factory=threading.Lock)
    _deformer: Deformer | None = None

    @property
    def deformer(self) -> Deformer:
        with self.lock:
            if self._deformer is None:
                self._deformer = Deformer(self.character)
            return self._deformer

    def edited(self, character: api.Character) -> None:
        """Save ``character`` in the project, then make it the one edited (a failed save changes nothing)."""
        with self.lock:
            api.save_project(self.folder, character)
            self.character, self._deformer = character, None


def create_app(project: str | Path, *, token: str, origins: tuple[str, ...] = ()) -> FastAPI:
    """The editor for the project folder ``project``.

    Parameters
    ----------
    project : path
        A project folder made by ``toonmotion rig`` (loaded now: a bad project fails here).
    token : str
        The per-launch token every request must carry.
    origins : tuple of str
        The page's own origins (``http://127.0.0.1:PORT``); a browser request from any other
        origin is refused. Requests without an ``Origin`` header (not from a page) are allowed.
    """
    editing = Editing(folder=Path(project), character=api.load_project(project))
    app = FastAPI(title="toonmotion editor", docs_url=None, redoc_url=None, openapi_url=None)

    def authorised(token_given: str | None, origin: str | None) -> str | None:
        """Why a request is refused, or None."""
        if not token_given or not hmac.compare_digest(token_given.encode(), token.encode()):
            return "missing or wrong token: open the address 'toonmotion edit' printed"
        if origin is not None and origin not in origins:
            return f"requests from {origin} are not allowed"
        return None

    @app.middleware("http")
    async def check_token(request: Request, call_next):
        given = request.headers.get("x-toonmotion-token") or request.query_params.get("token")
        if request.url.path in ("/", "/favicon.ico") or request.url.path.startswith("/static/"):
            given = token  # the page's own code holds no data: only the project needs the token
        refused = authorised(given, request.headers.get("origin"))
        if refused is not None:
            return JSONResponse({"error": refused}, status_code=403)
        return await call_next(request)

    @app.exception_handler(ToonmotionError)
    async def user_error(request: Request, error: ToonmotionError) -> JSONResponse:
        return JSONResponse({"error": _one_line(str(error))}, status_code=400)

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, error: HTTPException) -> JSONResponse:
        return JSONResponse({"error": _one_line(str(error.detail))}, status_code=error.status_code)

    @app.exception_handler(Exception)
    async def internal_error(request: Request, error: Exception) -> JSONResponse:
        log.error("internal error on %s: %s: %s", request.url.path, type(error).__name__, error)
        return JSONResponse({"error": _bug(error)}, status_code=500)

    @app.get("/")
    def page() -> FileResponse:
        return FileResponse(STATIC / "index.html", media_type="text/html")

    @app.get("/favicon.ico")
    def favicon() -> Response:
        return Response(status_code=204)

    @app.get("/static/{name}")
    def static(name: str) -> FileResponse:
        if name not in PAGE_FILES:
            raise HTTPException(404, f"no page file {name!r}")
        return FileResponse(STATIC / name, media_type=PAGE_FILES[name])

    @app.get("/api/project")
    def project_data() -> dict[str, Any]:
        return describe(editing)

    @app.get("/api/texture.png")
    def texture() -> Response:
        return Response(png_bytes(editing.character.texture), media_type="image/png")

    @app.websocket("/ws")
    async def live(socket: WebSocket) -> None:
        given = socket.query_params.get("token")
        refused = authorised(given, socket.headers.get("origin"))
        if refused is not None:
            await socket.close(code=1008, reason=refused[:120])
            return
        await socket.accept()
        try:
            while True:
                text = await socket.receive_text()
                await socket.send_text(json.dumps(answer(editing, text)))
        except WebSocketDisconnect:
            return

    return app


def describe(editing: Editing) -> dict[str, Any]:
    """The project as the page draws it: size, rest mesh, skeleton, and its regions."""
    character = editing.character
    mesh, skeleton = character.mesh, character.skeleton
    return {
        "name": editing.folder.name,
        "width": character.size[0],
        "height": character.size[1],
        "vertices": mesh.V.ravel().tolist(),
        "joints": [{"name": n, "parent": int(p), "position": skeleton.positions[i].tolist()}
                   for i, (n, p) in enumerate(zip(skeleton.names, skeleton.parents, strict=True))],
        "bones": list(skeleton.bone_names),
        **regions(character),
    }


def regions(character: api.Character) -> dict[str, Any]:
    """The bone regions: the triangles in draw order (depth layers), each vertex's bone (an index
    into the bone names), each bone's depth, and how many edits there are to undo and redo."""
    order = draw_order(character.mesh, character.binding, character.depth)
    return {
        "triangles": character.mesh.F[order].ravel().tolist(),
        "vertex_bone": character.binding.bone.tolist(),
        "depth": character.depth.tolist(),
        "edits": len(character.edits),
        "undone": len(character.undone),
    }


def answer(editing: Editing, text: str) -> dict[str, Any]:
    """The reply to one WebSocket message (module docstring); errors are replies too."""
    ident: Any = None
    try:
        if len(text) > MAX_MESSAGE_BYTES:
            raise PoseError(f"a message may be {MAX_MESSAGE_BYTES:,} bytes at most, got {len(text):,}")
        try:
            message = json.loads(text)
        except (ValueError, RecursionError):
            raise PoseError("a message must be a JSON object") from None
        if not isinstance(message, dict):
            raise PoseError("a message must be a JSON object")
        ident = message.get("id")
        if not isinstance(ident, (int, str, type(None))) or isinstance(ident, bool):
            ident = None
        kind = message.get("type")
        if kind == "pose":
            U = _posed(editing, message.get("positions"))
            return {"id": ident, "type": "mesh", "U": np.round(U, 3).ravel().tolist()}
        if kind == "overlaps":
            U = _posed(editing, message.get("positions"))
            found = api.same_depth_overlaps(editing.character, [(0, U)])
            pairs = [{"a": o.bone_a, "b": o.bone_b, "area": round(o.area, 1)} for o in found]
            return {"id": ident, "type": "overlaps", "pairs": pairs}
        if kind in _EDITS:
            editing.edited(_EDITS[kind](editing.character, message))
            return {"id": ident, "type": "regions", **regions(editing.character)}
        raise PoseError(f"unknown message type {kind!r}; the editor sends {', '.join(map(repr, _KINDS))}")
    except ToonmotionError as error:
        return {"id": ident, "type": "error", "message": _one_line(str(error))}
    except Exception as error:  # a bug: one line to the page, the details to the log
        log.error("internal error answering a message: %s: %s", type(error).__name__, error)
        return {"id": ident, "type": "error", "message": _bug(error)}


def _point(value: Any, what: str) -> tuple[float, float]:
    if not (isinstance(value, list) and len(value) == 2 and all(_is_number(v) for v in value)):
        raise EditError(f"{what} must be [x, y], got {str(value)[:40]}")
    return float(value[0]), float(value[1])


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _depth(character: api.Character, message: dict[str, Any]) -> api.Character:
    by = message.get("by")
    if by not in (-1, 1) or isinstance(by, bool):
        raise EditError("'by' must be 1 (one layer up) or -1 (one down)")
    return api.set_depth(character, 0, at=_point(message.get("at"), "'at'"), by=by)


def _correct(character: api.Character, message: dict[str, Any]) -> api.Character:
    bone, curve = message.get("bone"), message.get("curve")
    if not isinstance(bone, str):
        raise EditError("'bone' must name the bone to attach to")
    if not isinstance(curve, list) or not 3 <= len(curve) <= 10_000:
        raise EditError("'curve' must be a closed curve of 3 to 10,000 [x, y] points")
    return api.correct_regions(character, bone, [_point(p, "a curve point") for p in curve])


_EDITS = {
    "depth": _depth,
    "correct": _correct,
    "undo": lambda character, message: api.undo_edits(character),
    "redo": lambda character, message: api.redo_edits(character),
}
_KINDS = ("pose", "overlaps", *_EDITS)


def _posed(editing: Editing, positions: Any) -> NDArray[np.float64]:
    skeleton = editing.character.skeleton
    if not isinstance(positions, list) or len(positions) != len(skeleton):
        raise PoseError(f"'positions' must list [x, y] for each of the {len(skeleton)} joints")
    try:
        array = np.array(positions, dtype=float)
    except (TypeError, ValueError):
        raise PoseError("'positions' must be [x, y] pairs of numbers") from None
    if array.shape != (len(skeleton), 2):
        raise PoseError("'positions' must be [x, y] pairs of numbers")
    pose = check_pose(skeleton, Pose(array))
    return api.pose_character(editing.deformer, pose).deformation.U


def _bug(error: Exception) -> str:
    return f"internal error ({type(error).__name__}); this is a bug in toonmotion, please report it"


def _one_line(text: str) -> str:
    return " ".join(text.split())[:400]
