"""The Key-shapes panel's WebSocket messages (Bregler et al. 2002 capture in the editor), part of
:data:`toonmotion.web.messages.MODELS` (:data:`KEYSHAPE_MODELS`); what each does is
:mod:`toonmotion.web.keyshape_requests`'s.

* ``keyshapes``: what the project folder's ``keyshapes/`` holds, to show again after a reload or a
  restart. Reply ``{"type": "keyshapes", "outlines", "key_frames", "points", "inbetweens", "model",
  "contours", "footage", "capture", "retargeted"}`` (each null until made).
* ``keyshape_model``: the key ``outlines`` (closed curves, each a list of [x, y]; drawn, picked or
  read from a file), resampled by the library to ``points`` points each (null: they must already be
  in correspondence) and built into a key-shape model with ``inbetweens`` in-betweens per pair (what
  ``toonmotion keyshapes`` does); ``key_frames``, one per outline, are the footage frames they are
  drawn on (for video capture). Off the event loop; the reply is the ``keyshapes`` state.
* ``keyshape_pick``: the outline of the layer under ``at`` [x, y] in footage frame ``frame``, by its
  colour within ``tolerance`` (:func:`toonmotion.api.pick_layer`). Reply ``{"type": "picked",
  "outline", "frame"}``.
* ``keyshape_capture``: the key-shape motion captured with the model's keys from the ``source``
  ``"contours"`` (the contours file sent) or ``"video"`` (the footage sent with ``PUT
  /api/footage``, the keys drawn on their ``key_frames``), off the event loop with progress
  messages; ``lower`` and ``upper`` bound each key's weight. Reply the ``keyshapes`` state.
* ``keyshape_retarget``: the captured motion replayed on the character's key poses, the Timeline's
  keys at ``keys`` (one frame per key-shape, in the key-shapes' order), ``pin`` ``{"joint", "at"}``
  holding a joint at a place on every frame (``toonmotion retarget-keyshapes --project --poses``).
  Reply ``{"type": "keyshape_retargeted", "first", "last", "fps", "file"}``, whose frames a
  ``frame`` message with ``"source": "keyshapes"`` gives.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, StrictStr

from toonmotion.io.schema import Float, Point
from toonmotion.web.message_base import Message, must, required

Frame = Annotated[StrictInt, Field(ge=0, le=2**31 - 1)]

# At most this many key outlines, points per outline, and points resampled to.
MOST_KEYS, MOST_POINTS = 64, 10_000

_Outline = Annotated[list[Point], Field(min_length=3, max_length=MOST_POINTS)]


class KeyshapeModel(Message):
    outlines: Annotated[list[_Outline], Field(min_length=1, max_length=MOST_KEYS),
                        must(f"'outlines' must list 1 to {MOST_KEYS} closed curves, each 3 to "
                             f"{MOST_POINTS:,} [x, y] points")] = required()
    points: Annotated[StrictInt | None, Field(ge=3, le=MOST_POINTS),
                      must(f"'points' must be null or a whole number of points from 3 to {MOST_POINTS:,}")
                      ] = None
    key_frames: Annotated[list[Frame] | None,
                          must("'key_frames' must be null or list a frame number for each outline")] = None
    inbetweens: Annotated[StrictInt, Field(ge=0, le=100),
                          must("'inbetweens' must be a whole number from 0 to 100")] = 5


class KeyshapePick(Message):
    frame: Annotated[Frame, must("'frame' must be a frame number, a whole number >= 0")] = 0
    at: Annotated[Point, must("'at' must be [x, y]")] = required()
    tolerance: Annotated[StrictInt, Field(ge=1, le=255), must("'tolerance' must be a whole number 1 to 255")
                         ] = 24
    points: Annotated[StrictInt, Field(ge=3, le=MOST_POINTS),
                      must(f"'points' must be a whole number of points from 3 to {MOST_POINTS:,}")] = 100


class KeyshapeCapture(Message):
    source: Annotated[Literal["contours", "video"], must("'source' must be \"contours\" or \"video\"")
                      ] = required()
    lower: Annotated[Float, must("'lower' must be a number")] = -0.5
    upper: Annotated[Float, must("'upper' must be a number")] = 1.5


class Pin(BaseModel):
    model_config = ConfigDict(extra="ignore", frozen=True, allow_inf_nan=False)

    joint: StrictStr
    at: Point


class KeyshapeRetarget(Message):
    keys: Annotated[list[Frame], Field(min_length=1, max_length=MOST_KEYS),
                    must("'keys' must list the frames of the Timeline's keys, one per key-shape")
                    ] = required()
    pin: Annotated[Pin | None, must("'pin' must be null or {\"joint\": name, \"at\": [x, y]}")] = None


KEYSHAPE_MODELS: dict[str, type[Message]] = {
    "keyshapes": Message, "keyshape_model": KeyshapeModel, "keyshape_pick": KeyshapePick,
    "keyshape_capture": KeyshapeCapture, "keyshape_retarget": KeyshapeRetarget,
}
