"""The editor's server: the page, the open project's data, and live posing over a WebSocket.

Security, as notebook servers do it: the server binds this machine's loopback address only; every
request carries the random per-launch token (``?token=``, the ``X-Toonmotion-Token`` header, or
the cookie a one-time sign-in code is exchanged for: :func:`sign_in_code`); a request must name
the editor's own host (``Host``: a page on another name that resolves here, DNS rebinding, is
refused) and, from a browser page, come from the editor's own origin. Files are named by the
server, never by the request: nothing outside the package's page and the project folder is read,
and nothing is read, written or deleted through a symbolic link (:mod:`toonmotion.io.links`).

Errors come back as one line: a 4xx reply ``{"error": "..."}`` over HTTP, a
``{"type": "error", "message": "..."}`` message over the WebSocket; a malformed message never
closes the connection and never shows a traceback.

What the WebSocket carries is :mod:`toonmotion.web.messages`'s, the open project
:mod:`toonmotion.web.editing`'s, and the replies :mod:`toonmotion.web.session`'s.
Messages are answered one at a time, in a worker thread of their own (:func:`create_app`'s
``answers``), never on the event loop: a slow pose holds up the poses after it, as before, but not
the server's other pages' HTTP requests, their messages being read, progress or broadcasts.
Every page open on the project sees the others' changes: after a reply that changed the project
(:data:`CHANGES`), every other live connection gets ``{"type": "changed", "kind": ..., "step":
..., "says": "...", "history": {...}}`` and the page fetches the project again.
"""

from __future__ import annotations

import asyncio
import collections
import concurrent.futures
import contextlib
import hmac
import json
import logging
import secrets
import threading
import time
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

import numpy as np
from fastapi import FastAPI, Request, WebSocket, WebSocketDisconnect
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse, RedirectResponse, Response
from starlette.exceptions import HTTPException

from toonmotion import api, limits
from toonmotion.errors import LinkError, ToonmotionError
from toonmotion.io.frames import load_frames
from toonmotion.io.image import load_image, png_bytes
from toonmotion.io.skeleton_json import load_skeleton_file
from toonmotion.web import keyshape_routes
from toonmotion.web.editing import EXPORT_FILE, EXPORTS, FOOTAGE, UPLOAD_PARTS, UPLOADS, Editing
from toonmotion.web.messages import MAX_MESSAGE_BYTES, bug, one_line
from toonmotion.web.proxy_routes import add_proxy_routes
from toonmotion.web.session import answer, describe
from toonmotion.web.slow_requests import suggested_joints
from toonmotion.web.socket_flow import animate_first, cancels, progress_sender, slow_handler
from toonmotion.web.uploads import as_sent, receive_body

__all__ = ["MAX_MESSAGE_BYTES", "PAGE_FILES", "create_app", "new_token", "sign_in_code"]

STATIC = Path(__file__).parent / "static"
# The page's own files: nothing else under STATIC, and nothing outside it, is served.
PAGE_FILES = {"index.html": "text/html", "editor.css": "text/css", "app.js": "text/javascript",
              "mesh_view.js": "text/javascript", "pose_panel.js": "text/javascript",
              "regions_panel.js": "text/javascript", "timeline_panel.js": "text/javascript",
              "exaggerate_panel.js": "text/javascript", "export_panel.js": "text/javascript",
              "rig_panel.js": "text/javascript", "panel_kit.js": "text/javascript",
              "capture_panel.js": "text/javascript", "proxy_panel.js": "text/javascript",
              "proxy_view.js": "text/javascript", "keyshapes_panel.js": "text/javascript"}

# Images a folder of frames may hold (sent one by one).
FRAME_SUFFIXES = ("png", "jpg", "jpeg", "webp")
# Footage the editor takes: what toonmotion.io.frames reads as one file.
# What an export's download is served as, by suffix.
EXPORT_MEDIA_TYPES = {"gif": "image/gif", "mp4": "video/mp4", "apng": "image/apng", "webp": "image/webp",
                      "webm": "video/webm", "glb": "model/gltf-binary", "json": "application/json",
                      "atlas": "text/plain", "png": "image/png", "bvh": "text/plain"}
FOOTAGE_SUFFIXES = ("mp4", "mov", "avi", "mkv", "webm", "gif", "png", "apng", "webp")

log = logging.getLogger("toonmotion.web")

# Replies that say the project changed: the other pages are told (module docstring).
CHANGES = frozenset({"regions", "keys", "undone", "redone", "rigged", "opened", "lifted", "scene"})

# The cookie a sign-in code is exchanged for, and how long a code is good for (seconds).
TOKEN_COOKIE = "toonmotion_token"
SIGN_IN_SECONDS = 120.0
# Names of this machine a request may give as its Host (with any port).
LOOPBACK_NAMES = ("127.0.0.1", "localhost", "[::1]")


def new_token() -> str:
    """A random per-launch token."""
    return secrets.token_urlsafe(24)


def sign_in_code(app: FastAPI) -> str:
    """A new one-time code for ``app``: the page's address with ``?code=`` (good once, for
    :data:`SIGN_IN_SECONDS`) sets the token as a cookie and leaves the address without it. What
    ``toonmotion edit --open`` gives the browser, so that the token is on no command line."""
    code = secrets.token_urlsafe(24)
    app.state.sign_in_codes[code] = time.monotonic() + SIGN_IN_SECONDS
    return code


def create_app(project: str | Path, *, token: str, origins: tuple[str, ...] = (),
               library: str | Path | None = None) -> FastAPI:
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
        A request's ``Host`` must be one of :data:`LOOPBACK_NAMES` or an origin's host name.
    library : path, optional
        A folder of motion-capture clips (``.bvh``) the 3D panel offers as priors: the one
        folder outside the project the editor reads, and only the clips it lists there.
    """
    editing = Editing.open(project, library=library)
    hosts = {*LOOPBACK_NAMES, *(urlsplit(origin).hostname or "" for origin in origins)}
    hosts |= {f"[{name}]" for name in hosts if ":" in name}
    threading.Thread(target=editing.prepare_deformer, name="toonmotion-prepare", daemon=True).start()
    app = FastAPI(title="toonmotion editor", docs_url=None, redoc_url=None, openapi_url=None)
    app.state.sign_in_codes = {}
    pages: set[WebSocket] = set()  # every live connection, to tell each of the others' changes
    # Every message is answered in this one thread, in the order they come: the session's state is
    # the answers' alone (the slow requests' threads take only what they are given).
    answers = concurrent.futures.ThreadPoolExecutor(max_workers=1, thread_name_prefix="toonmotion-answer")

    async def tell_the_others(socket: WebSocket, reply: dict[str, Any]) -> None:
        """After ``reply`` to ``socket`` changed the project, every other page is told."""
        if reply.get("type") not in CHANGES:
            return
        note = json.dumps({"type": "changed", "kind": reply["type"], "step": reply.get("kind"),
                           "says": reply.get("says"), "history": reply.get("history")})
        for other in list(pages):
            if other is not socket:
                with contextlib.suppress(Exception):  # a page going away is its own connection's business
                    await other.send_text(note)

    def authorised(token_given: str | None, origin: str | None, host: str | None) -> str | None:
        """Why a request is refused, or None."""
        name = _host_name(host)
        if name not in hosts:
            return (f"requests for the host {str(host)[:60]!r} are not allowed: open the address "
                    "'toonmotion edit' printed")
        if not token_given or not hmac.compare_digest(token_given.encode(), token.encode()):
            return "missing or wrong token: open the address 'toonmotion edit' printed"
        if origin is not None and origin not in origins:
            return f"requests from {origin} are not allowed"
        return None

    def given_token(connection: Request | WebSocket) -> str | None:
        return (connection.headers.get("x-toonmotion-token") or connection.query_params.get("token")
                or connection.cookies.get(TOKEN_COOKIE))

    @app.middleware("http")
    async def check_token(request: Request, call_next):
        given = given_token(request)
        path = request.url.path
        if path in ("/", "/favicon.ico") or path.startswith("/static/"):
            given = token  # the page's own code holds no data: only the project needs the token
        refused = authorised(given, request.headers.get("origin"), request.headers.get("host"))
        if refused is not None:
            return JSONResponse({"error": refused}, status_code=403)
        code = request.query_params.get("code")
        if path == "/" and code is not None:
            return sign_in(code)
        return await call_next(request)

    def sign_in(code: str) -> Response:
        """The page's address with a sign-in code: the token as a cookie, and the address again
        without the code; a used, expired or unknown code is refused."""
        codes = app.state.sign_in_codes
        for old in [c for c, until in codes.items() if until < time.monotonic()]:
            del codes[old]
        if codes.pop(code, None) is None:
            return JSONResponse({"error": "this sign-in address was used already or has expired: open the "
                                          "address 'toonmotion edit' printed"}, status_code=403)
        reply = RedirectResponse("/", status_code=303)
        reply.set_cookie(TOKEN_COOKIE, token, httponly=True, samesite="strict", path="/")
        return reply

    @app.exception_handler(LinkError)
    async def link_refused(request: Request, error: LinkError) -> JSONResponse:
        return JSONResponse({"error": one_line(str(error))}, status_code=403)

    @app.exception_handler(ToonmotionError)
    async def user_error(request: Request, error: ToonmotionError) -> JSONResponse:
        return JSONResponse({"error": one_line(str(error))}, status_code=400)

    @app.exception_handler(HTTPException)
    async def http_error(request: Request, error: HTTPException) -> JSONResponse:
        return JSONResponse({"error": one_line(str(error.detail))}, status_code=error.status_code)

    @app.exception_handler(RequestValidationError)
    async def bad_request(request: Request, error: RequestValidationError) -> JSONResponse:
        first = error.errors()[0]
        where = ".".join(str(part) for part in first.get("loc", ()))
        return JSONResponse({"error": one_line(f"{where}: {first.get('msg', 'not valid')}")}, status_code=400)

    @app.exception_handler(Exception)
    async def internal_error(request: Request, error: Exception) -> JSONResponse:
        log.error("internal error on %s: %s: %s", request.url.path, type(error).__name__, error)
        return JSONResponse({"error": bug(error)}, status_code=500)

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

    add_proxy_routes(app, editing)

    @app.get("/api/project")
    def project_data() -> dict[str, Any]:
        return describe(editing)

    @app.get("/api/texture.png")
    def texture() -> Response:
        return Response(png_bytes(editing.character.texture), media_type="image/png")

    @app.put("/api/footage")
    async def footage(request: Request, suffix: str, name: str = "") -> dict[str, Any]:
        """Footage to capture from, the request's body: saved in the project, read, joints suggested
        (errors name it ``name``, the file the user sent)."""
        if suffix.lower() not in FOOTAGE_SUFFIXES:
            raise HTTPException(400, f"send footage as {', '.join(FOOTAGE_SUFFIXES)}, not {suffix[:10]!r}")
        editing.check_links()
        file = editing.path(FOOTAGE, f"clip.{suffix.lower()}")
        await receive_body(request, file, "the footage")
        with as_sent(file, name or "the footage sent"):
            return await footage_read(file)

    @app.put("/api/footage/frames/{index}")
    async def footage_frame_file(request: Request, index: int, count: int, suffix: str) -> dict[str, Any]:
        """One image of a folder of frames (frame ``index`` of ``count``, sent in order); the
        last one read with the rest, as a folder of numbered images (``io.frames``)."""
        if suffix.lower() not in FRAME_SUFFIXES:
            raise HTTPException(400, f"send frames as {', '.join(FRAME_SUFFIXES)}, not {suffix[:10]!r}")
        most = limits.current().footage_frames
        if not 1 <= count <= most or not 0 <= index < count:
            raise HTTPException(400, f"frames are numbered 0 to count - 1, count 1 to {most:,} "
                                     "(the footage_frames limit)")
        editing.check_links()
        folder = editing.path(FOOTAGE, "frames")
        if index == 0 and folder.is_dir():  # a new folder of frames replaces the last one
            for old in folder.iterdir():
                old.unlink()
        sent = sum(f.stat().st_size for f in folder.iterdir()) if folder.is_dir() else 0
        await receive_body(request, folder / f"{index:06d}.{suffix.lower()}", "the frames together",
                           already=sent)
        if index < count - 1:
            return {"received": index + 1, "count": count}
        return await footage_read(folder)

    async def footage_read(source: Path) -> dict[str, Any]:
        """Footage saved in the project, read; the joints it suggests, to track, the colour of its
        first frame's border when that is flat (what the figure is told from), else null, and the
        box round that frame's figure (``[left, top, right, bottom]``, or null)."""
        try:
            frames, fps = await asyncio.to_thread(load_frames, source)
        except ToonmotionError:
            if source.is_file():
                source.unlink(missing_ok=True)
            raise
        skeleton, sizes = api.suggest_joints(frames)
        rate = fps or 24.0
        editing.footage, editing.capture, editing.captured = (frames, rate), None, None
        border = api.border_colour(frames[0])
        box = api.figure_box(frames, colour=border)
        described = {"frames": len(frames), "width": frames.shape[2], "height": frames.shape[1], "fps": rate,
                     "joints": suggested_joints(skeleton, sizes),
                     "border": None if border is None else list(border),
                     "figure": None if box is None else list(box)}
        editing.capture_page = {"footage": described, "joints": None, "tracked": None}
        return described

    @app.put("/api/uploads/{part}")
    async def upload(request: Request, part: str, format: str = "", name: str = "") -> dict[str, Any]:
        """A drawing, its mask, or a skeleton file, the request's body, kept in the project's
        upload area (``uploads/``) and read at once: a drawing or mask must be an image, a
        skeleton a char_cfg YAML or toonmotion JSON (``format=yaml|json``), whose joints come back."""
        if part not in UPLOAD_PARTS:
            raise HTTPException(404, f"uploads are {', '.join(UPLOAD_PARTS)}, not {part[:20]!r}")
        if part == "skeleton" and format not in ("yaml", "json"):
            raise HTTPException(400, "say the skeleton file's format: ?format=yaml (a char_cfg) "
                                     "or ?format=json")
        editing.check_links()
        file = editing.path(UPLOADS, f"skeleton.{format}" if part == "skeleton" else part)
        limit = "skeleton_bytes" if part == "skeleton" else "upload_bytes"
        await receive_body(request, file, "the file", limit=limit)
        with as_sent(file, name or f"the {part} file sent"):
            return await read_upload(part, file)

    async def read_upload(part: str, file: Path) -> dict[str, Any]:
        try:
            if part == "skeleton":
                skeleton = await asyncio.to_thread(load_skeleton_file, file)
                return {"joints": [{"name": n, "parent": p, "position": list(xy)}
                                   for n, p, xy in skeleton.joints()]}
            picture = await asyncio.to_thread(load_image, file)
        except ToonmotionError:
            file.unlink(missing_ok=True)
            raise
        return {"width": picture.shape[1], "height": picture.shape[0]}

    @app.get("/api/mask.png")
    def mask() -> Response:
        """The figure's mask to lay over the drawing: blue where the figure is, clear elsewhere."""
        figure = editing.character.mask
        rgba = np.zeros((*figure.shape, 4), dtype=np.uint8)
        rgba[figure] = (49, 130, 206, 255)
        return Response(png_bytes(rgba), media_type="image/png")

    @app.get("/api/footage/{index}.png")
    def footage_frame(index: int) -> Response:
        if editing.footage is None or not 0 <= index < len(editing.footage[0]):
            raise HTTPException(404, f"no footage frame {index}")
        return Response(png_bytes(editing.footage[0][index]), media_type="image/png")

    @app.get("/api/exports/{name}")
    def exported(name: str) -> FileResponse:
        allowed = EXPORT_FILE.fullmatch(name)
        if allowed is None:
            raise HTTPException(404, f"no export {name!r}")
        editing.check_links()
        file = editing.path(EXPORTS, name)
        if not file.is_file():
            raise HTTPException(404, f"no export {name!r}")
        return FileResponse(file, media_type=EXPORT_MEDIA_TYPES[allowed["suffix"]], filename=name)

    keyshape_routes.add_routes(app, editing)  # the Key-shapes panel's sheet and files sent

    @app.websocket("/ws")
    async def live(socket: WebSocket) -> None:
        refused = authorised(given_token(socket), socket.headers.get("origin"), socket.headers.get("host"))
        if refused is not None:
            await socket.close(code=1008, reason=refused[:120])
            return
        await socket.accept()
        pages.add(socket)
        loop = asyncio.get_running_loop()
        # Messages are read as they come, into a queue (None: the page went away), so that a
        # cancel can reach a slow request while it runs; other messages wait for it, in order.
        inbox: asyncio.Queue[str | None] = asyncio.Queue()
        waiting: collections.deque[str | None] = collections.deque()
        broken: list[str] = []  # why the connection broke, when it did not just close

        async def read() -> None:
            try:
                while True:
                    await inbox.put(await socket.receive_text())
            except WebSocketDisconnect:
                pass
            except Exception as error:  # a binary frame, a broken connection: the session ends
                broken.append(f"{type(error).__name__}: {error}")
            finally:
                inbox.put_nowait(None)

        reader = asyncio.create_task(read())
        stop = threading.Event()  # the running slow request's: set, it stops at its next step
        try:
            while True:
                text = waiting.popleft() if waiting else await inbox.get()
                if text is None:
                    return
                slow = slow_handler(text)
                if slow is not None:  # long: off the event loop, with progress messages
                    ident = json.loads(text).get("id")
                    stop = threading.Event()
                    progress = progress_sender(socket, loop, ident, stop)
                    # the animation is solved where messages are answered
                    await loop.run_in_executor(answers, animate_first, editing, text)
                    job = asyncio.ensure_future(asyncio.to_thread(slow, editing, text, progress))
                    while not job.done():
                        heard = asyncio.ensure_future(inbox.get())
                        await asyncio.wait({job, heard}, return_when=asyncio.FIRST_COMPLETED)
                        if not heard.done():
                            heard.cancel()
                            continue
                        other = heard.result()
                        if other is not None and cancels(other, ident):
                            stop.set()
                            continue
                        waiting.append(other)  # answered after it, in order
                        if other is None:  # the page went away: nobody waits for the reply
                            stop.set()
                    reply = job.result()
                    if waiting and waiting[-1] is None:
                        return
                elif cancels(text, None):
                    continue  # a cancel that came after its request was answered
                else:
                    reply = await loop.run_in_executor(answers, answer, editing, text)
                await socket.send_text(json.dumps(reply))
                await tell_the_others(socket, reply)
        except WebSocketDisconnect:
            return
        finally:  # the page went away, or the server stops: so does what runs for it
            pages.discard(socket)
            stop.set()
            reader.cancel()
            if broken:
                log.warning("the live connection broke: %s", broken[0])
                with contextlib.suppress(Exception):
                    await socket.close(code=1003, reason="the editor sends text messages only; reload")

    return app


def _host_name(host: str | None) -> str:
    """The name in a ``Host`` header, without its port (``[::1]:8000`` -> ``[::1]``)."""
    host = (host or "").strip().lower()
    if host.startswith("["):
        return host[: host.find("]") + 1] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


