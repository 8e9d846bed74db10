"""What a request's body sent to the editor goes through: streamed into a file of the project under a
limit (:func:`receive_body`), and errors reading it told of the file the user sent (:func:`as_sent`)."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path

from fastapi import Request
from starlette.exceptions import HTTPException

from toonmotion import limits
from toonmotion.errors import ToonmotionError
from toonmotion.io.atomic import atomic_path


@contextlib.contextmanager
def as_sent(file: Path, name: str) -> Iterator[None]:
    """Errors reading ``file``, where an upload was kept, told of ``name``, the file the user sent
    (not the server's path), with the editor's way to raise a limit."""
    try:
        yield
    except ToonmotionError as error:
        message = str(error)
        # Its path, and its bare name where that cannot be a word of the message (clip.mp4, or
        # "drawing" opening it).
        for form in (str(file.resolve()), str(file), *([file.name] if "." in file.name else [])):
            message = message.replace(form, name[:200])
        if message.startswith(f"{file.name} "):
            message = name[:200] + message[len(file.name):]
        message = message.replace("(--max-pixels, or --limit image_pixels=N)",
                                  "(start the editor with toonmotion --limit image_pixels=N edit ...)")
        raise HTTPException(400, message) from None


async def receive_body(request: Request, file: Path, what: str, *, already: int = 0,
                   limit: str = "upload_bytes") -> None:
    """Stream the request's body into ``file`` (atomically), refused as soon as it passes the
    limit named ``limit`` (``already``: bytes sent before it that count too): a body over it is
    never held whole, nor read."""
    most = getattr(limits.current(), limit)
    received = already
    with atomic_path(file) as partial, open(partial, "wb") as out:
        async for chunk in request.stream():
            received += len(chunk)
            if received > most:
                raise HTTPException(413, f"{what} is over the limit {limit}={most:,}; make it "
                                         "smaller (or raise the limit with --limit)")
            out.write(chunk)
