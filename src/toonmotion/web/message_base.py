"""What every editor message model is built from (:mod:`toonmotion.web.messages`,
:mod:`toonmotion.web.proxy_messages`): the base :class:`Message`, and fields whose problems read
as one line saying what the field must be."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field
from pydantic_core import ErrorDetails

from toonmotion.io.schema import explained


class Message(BaseModel):
    """What every message has: its ``type`` and an ``id`` to echo back."""

    model_config = ConfigDict(extra="ignore", frozen=True, allow_inf_nan=False)

    type: str
    id: int | str | None = None


def _got(value: Any) -> str:
    return repr(value)[:40]


def must(text: str, *, inner: str | None = None) -> Any:
    """A field whose every problem reads ``"{text}, got {value}"``; a problem inside one of its
    items reads ``"{inner}, got {item}"`` when ``inner`` is given."""

    def say(value: Any, errors: list[ErrorDetails]) -> str:
        if inner is not None and len(errors[0]["loc"]) >= 2:
            return f"{inner}, got {_got(errors[0]['input'])}"
        return f"{text}, got {_got(value)}"

    return explained(say)


def required() -> Any:
    """A field the message must give: missing, it is validated as null, so its own message says so
    (``'joint' must name the joint dragged, got None``) rather than pydantic's."""
    return Field(default=None, validate_default=True)
