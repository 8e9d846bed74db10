"""The ``edit`` command: start the editor's local server on a project."""

from __future__ import annotations

import socket
import webbrowser
from pathlib import Path
from typing import Annotated

import typer

from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.errors import SettingsError


@app.command()
def edit(
    project: options.Project,
    port: Annotated[int, typer.Option("--port", help="Port to serve on \\[default: a free one].", min=0,
                                      max=65535)] = 0,
    host: Annotated[str, typer.Option(
        "--host", help="Address to bind; anything but 127.0.0.1 lets other machines in.")] = "127.0.0.1",
    open_browser: Annotated[bool, typer.Option("--open", help="Open the editor in the web browser.")] = False,
) -> None:
    """Edit a project in the browser: pose it live, set depths, correct regions (Ctrl-C stops)."""
    import uvicorn

    from toonmotion.web.server import create_app, new_token

    listener = _listen(host, port)
    bound = listener.getsockname()[1]
    token = new_token()
    shown = "127.0.0.1" if host in ("0.0.0.0", "::") else host
    origins = tuple(f"http://{name}:{bound}" for name in {shown, "127.0.0.1", "localhost"})
    server_app = create_app(Path(project), token=token, origins=origins)
    url = f"http://{shown}:{bound}/?token={token}"
    typer.echo(f"toonmotion editor for {project}: {url}")
    if open_browser:
        webbrowser.open(url)
    config = uvicorn.Config(server_app, log_level="warning", ws_max_size=2_000_000)
    uvicorn.Server(config).run(sockets=[listener])


def _listen(host: str, port: int) -> socket.socket:
    """A listening socket on ``host:port`` (port 0: a free one)."""
    try:
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        listener = socket.socket(family, socket.SOCK_STREAM)
        listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        listener.bind((host, port))
        listener.listen(64)
    except OSError as error:
        raise SettingsError(f"cannot serve on {host}:{port}: {error.strerror or error}") from None
    return listener
