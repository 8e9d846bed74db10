"""The editor served from a background thread on a free loopback port: what the browser tests and
the editor's benchmarks run (``toonmotion edit`` serves in the foreground)."""

from __future__ import annotations

import contextlib
import socket
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from fastapi import FastAPI

from toonmotion.web.server import create_app, new_token


@dataclass(frozen=True)
class Served:
    """A running editor: its app, and the page's and the live connection's addresses (with the token)."""

    app: FastAPI
    port: int
    token: str

    @property
    def page(self) -> str:
        return f"http://127.0.0.1:{self.port}/?token={self.token}"

    @property
    def live(self) -> str:
        return f"ws://127.0.0.1:{self.port}/ws?token={self.token}"


@contextlib.contextmanager
def serving(project: str | Path, *, library: str | Path | None = None) -> Iterator[Served]:
    """The editor on the project folder ``project`` (with the priors' folder ``library``), served
    until the block ends."""
    import uvicorn

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen(64)
    port = listener.getsockname()[1]
    token = new_token()
    app = create_app(project, token=token, origins=(f"http://127.0.0.1:{port}",), library=library)
    server = uvicorn.Server(uvicorn.Config(app, log_level="warning"))
    thread = threading.Thread(target=server.run, kwargs={"sockets": [listener]}, daemon=True)
    thread.start()
    while not server.started:
        if not thread.is_alive():
            raise RuntimeError("the editor's server stopped as it started")
        time.sleep(0.02)
    try:
        yield Served(app=app, port=port, token=token)
    finally:
        server.should_exit = True
        thread.join(timeout=10)
        listener.close()
