"""The ``edit`` command: start the editor's local server on a project."""

from __future__ import annotations

import ipaddress
import os
import socket
import webbrowser
from pathlib import Path
from typing import Annotated

import typer

from toonmotion import api
from toonmotion.cli.app import app
from toonmotion.errors import SettingsError
from toonmotion.io.project import PROJECT_FILE


@app.command()
def edit(
    target: Annotated[Path, typer.Argument(
        metavar="PROJECT|IMAGE",
        help="A project folder, or a drawing: it is rigged into a project folder beside it, named after it "
        "(opened again next time).")],
    port: Annotated[int, typer.Option("--port", help="Port to serve on \\[default: a free one].", min=0,
                                      max=65535)] = 0,
    host: Annotated[str, typer.Option(
        "--host", help="This machine's address to serve on: 127.0.0.1, localhost or ::1. The editor serves "
        "this machine only; to edit from another, forward its port over SSH.")]
    = "127.0.0.1",
    open_browser: Annotated[bool, typer.Option(
        "--open", help="Open the editor in the web browser (with a one-time sign-in code, not the token).")]
    = False,
    mocap: Annotated[Path | None, typer.Option(
        "--mocap", envvar="TOONMOTION_MOCAP", help="A folder of motion-capture clips (.bvh) the 3D panel "
        "offers as priors (clips can also be sent from the page).")] = None,
) -> None:
    """Edit a project in the browser: rig, pose, regions, key-frames, exaggerate, capture, 3D, export."""
    import uvicorn

    from toonmotion.web.server import create_app, new_token, sign_in_code

    _check_host(host)

    # imageio-ffmpeg starts ffmpeg with preexec_fn (to keep Ctrl+C from it); started from the
    # server's worker threads, Python prints an "Exception ignored in _after_fork" traceback for
    # every video read or written. Its own switch turns that off; the server stops ffmpeg itself.
    os.environ.setdefault("IMAGEIO_FFMPEG_NO_PREVENT_SIGINT", "1")

    project = _project_for(target)
    listener = _listen(host, port)
    bound = listener.getsockname()[1]
    token = new_token()
    shown = f"[{host}]" if ":" in host else host
    names = dict.fromkeys((shown, "127.0.0.1", "localhost", "[::1]"))
    origins = tuple(f"http://{name}:{bound}" for name in names)
    if mocap is not None and not mocap.is_dir():
        raise SettingsError(f"--mocap must be a folder of .bvh clips; {mocap} is not a folder")
    server_app = create_app(Path(project), token=token, origins=origins, library=mocap)
    url = f"http://{shown}:{bound}/?token={token}"
    typer.echo(f"toonmotion editor for {project}: {url}")
    if open_browser:  # a code good once, for two minutes: the token itself is on no command line
        webbrowser.open(f"http://{shown}:{bound}/?code={sign_in_code(server_app)}")
    config = uvicorn.Config(server_app, log_level="warning", ws_max_size=2_000_000)
    uvicorn.Server(config).run(sockets=[listener])


def _project_for(target: Path) -> Path:
    """The project to edit: ``target``, or for a drawing the project beside it (rigged if new)."""
    if not target.is_file():
        return target
    project = target.with_suffix("")
    if (project / PROJECT_FILE).is_file():
        typer.echo(f"opening {project}, the project made from {target.name}")
        return project
    character = api.rig_image(target)
    api.save_project(project, character)
    typer.echo(f"rigged {target.name}: {len(character.mesh.V)} vertices, {len(character.skeleton)} joints "
               f"-> {project}")
    return project


def _check_host(host: str) -> None:
    """Refuse an address other than this machine's loopback: the editor's token and origin checks
    are made for a browser on this machine, and it has no TLS to carry the token across a network."""
    try:
        loopback = host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        loopback = False
    if not loopback:
        raise SettingsError(
            f"--host {host}: the editor serves this machine only (127.0.0.1, localhost or ::1); to edit from "
            "another machine, forward the port over SSH (ssh -L 8000:127.0.0.1:8000 THIS-MACHINE, with "
            "--port 8000 here) and open the printed address there")


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
