"""How the editor's live connection treats a message before it is answered
(:func:`toonmotion.web.server.create_app`): which are slow (run off the event loop,
:func:`slow_handler`), what a slow one's progress sends (:func:`progress_sender`), which cancel
it (:func:`cancels`), and the animation an export needs solved first."""

from __future__ import annotations

import asyncio
import contextlib
import json
import threading
from collections.abc import Callable
from typing import Any

from fastapi import WebSocket

from toonmotion.errors import Cancelled, ToonmotionError
from toonmotion.web import messages
from toonmotion.web.editing import Editing
from toonmotion.web.keyshape_requests import SLOW as KEYSHAPE_SLOW
from toonmotion.web.messages import MAX_MESSAGE_BYTES
from toonmotion.web.proxy_requests import PROXY_SLOW
from toonmotion.web.slow_requests import export, open_drawing, suggest, track

# The messages answered off the event loop, by type.
SLOW_HANDLERS: dict[str, Callable[..., dict[str, Any]]] = {
    "export": export, "track": track, "open_drawing": open_drawing, "suggest": suggest, **PROXY_SLOW,
    **KEYSHAPE_SLOW}


def animate_first(editing: Editing, text: str) -> None:
    """Solve the animation an export, a lift or a scene needs, in the answers' thread (the slow
    request then only takes it); a bad message is the request's to refuse."""
    with contextlib.suppress(ToonmotionError):
        message = messages.read(messages.parse(text))
        if isinstance(message, messages.Export):
            editing.animated(message.exaggeration())
        elif message.type in ("lift", "scene"):
            editing.animated(None)


def progress_sender(socket: WebSocket, loop: asyncio.AbstractEventLoop, ident: Any,
              stop: threading.Event) -> Callable[[int, int], None]:
    """A slow request's ``progress(index, count)``, called off the loop: a progress message to
    the page with the request's id, or :class:`Cancelled` once ``stop`` is set."""
    def progress(index: int, count: int) -> None:
        if stop.is_set():
            raise Cancelled("cancelled")
        said = {"id": ident, "type": "progress", "index": index, "count": count}
        asyncio.run_coroutine_threadsafe(socket.send_text(json.dumps(said)), loop)

    return progress


def cancels(text: str, ident: Any) -> bool:
    """Whether ``text`` is ``{"type": "cancel", "id": ident}`` (any id when ``ident`` is None)."""
    if len(text) > 200 or '"cancel"' not in text:
        return False
    try:
        message = json.loads(text)
    except (ValueError, RecursionError):
        return False
    return isinstance(message, dict) and message.get("type") == "cancel" and (
        ident is None or message.get("id") == ident)


def slow_handler(text: str) -> Callable[..., dict[str, Any]] | None:
    """The handler of a message that runs off the event loop (an export, a tracking, joints
    suggested on footage), or None (checked cheaply; a bad message goes to ``answer``)."""
    if len(text) > MAX_MESSAGE_BYTES or not any(f'"{kind}"' in text for kind in SLOW_HANDLERS):
        return None
    try:
        message = json.loads(text)
    except (ValueError, RecursionError):
        return None
    kind = message.get("type") if isinstance(message, dict) else None
    return SLOW_HANDLERS.get(kind) if isinstance(kind, str) else None
