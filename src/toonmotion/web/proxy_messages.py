"""The 3D panel's WebSocket messages (Jain et al. 2012 in the editor), as pydantic models like every
other message (:mod:`toonmotion.web.messages`, whose ``MODELS`` holds them too). What each does is
:mod:`toonmotion.web.proxy_requests`'s; the files it keeps are under the project's ``proxy3d/``.

* ``proxy``: what the panel shows again after a reload: the priors to choose from, and the proxy
  and scene last made. Reply ``{"type": "proxy", "priors", "lift", "proxy", "scene",
  "timeline"}`` (``timeline``: the scene the Timeline plays, as ``GET /api/project``'s ``scene``).
* ``lift``: the key-frames' animation lifted into 3D (:func:`toonmotion.api.lift_animation`)
  with the motion-capture ``prior`` (a name from ``priors``), from the ``view``
  [azimuth, elevation] in degrees (null: searched), with ``up`` (degrees clockwise the world's up
  leans in the picture), ``hold_elevation``, ``ground`` ("prior" or "feet") and ``segment``
  ([start, stop]: the prior's frames to use, stop null for its end); off the event
  loop with progress. Saved as ``proxy3d/proxy.json`` (what ``toonmotion scene`` reads). Reply as
  ``proxy``'s.
* ``scene``: the ``elements`` (each ``{"kind": "balloon" | "balls" | "scarf" | "skirt" | "cape" |
  "rain", "markers": [...], "count"}``) simulated round the proxy and composited into the
  animation's frames (:func:`toonmotion.api.simulate_scene`, :func:`~toonmotion.api.composite_scene`),
  off the event loop with progress; the frames are saved under ``proxy3d/scene/`` and served as
  ``GET /api/scene/{index}.png``. Reply ``{"type": "scene", "frames", "elements", "warnings"}``.
* ``proxy_export``: the proxy (``glb``, ``bvh``) or the scene (``mp4``, ``gif``, ``png`` frames,
  ``passes``) written into ``exports/`` as ``name``, off the event loop. Reply ``{"type":
  "exported", "file", "files", "frames"}``.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import Field, StrictBool, StrictInt, StrictStr

from toonmotion.web.message_base import Message, must, required

ELEMENT_KINDS = ("balloon", "balls", "scarf", "skirt", "cape", "rain")
# What the 3D panel exports, and each one's file name after the export's name.
PROXY_EXPORTS = {"glb": ".glb", "bvh": ".bvh", "mp4": ".mp4", "gif": ".gif", "png": "", "passes": ""}

Angle = Annotated[float, Field(ge=-360.0, le=360.0)]
Count = Annotated[StrictInt, Field(ge=0, le=10_000_000)]


class Lift(Message):
    prior: Annotated[StrictStr, Field(min_length=1, max_length=200),
                     must("'prior' must name a motion-capture clip from the list of priors")] = required()
    view: Annotated[tuple[Angle, Angle] | None,
                    must("'view' must be null (searched) or [azimuth, elevation] in degrees, -360 to 360")
                    ] = None
    up: Annotated[Angle, must("'up' must be degrees, -360 to 360")] = 0.0
    hold_elevation: Annotated[StrictBool, must("'hold_elevation' must be true or false")] = False
    ground: Annotated[Literal["prior", "feet"], must("'ground' must be 'prior' or 'feet'")] = "prior"
    segment: Annotated[tuple[Count, Count | None],
                       must("'segment' must be [start, stop], the prior's frames to use (stop null: its end)")
                       ] = (0, None)


class SceneElement(Message):
    """One element of a scene; ``type`` is not sent for these (they ride in a ``scene`` message)."""

    type: str = "element"
    kind: Annotated[Literal["balloon", "balls", "scarf", "skirt", "cape", "rain"],
                    must(f"an element's 'kind' must be one of {', '.join(ELEMENT_KINDS)}")] = required()
    markers: Annotated[list[StrictStr], Field(max_length=64),
                       must("an element's 'markers' must list marker names")] = []
    count: Annotated[StrictInt, Field(ge=1, le=10_000),
                     must("an element's 'count' must be a whole number from 1 to 10,000")] = 3


class Scene(Message):
    elements: Annotated[list[SceneElement], Field(min_length=1, max_length=64),
                        must("'elements' must list 1 to 64 elements, each {kind, markers}")] = required()
    antialias: Annotated[StrictInt, Field(ge=1, le=4), must("'antialias' must be 1 to 4")] = 2
    shading: Annotated[Literal["toon", "smooth", "flat"], must("'shading' must be toon, smooth or flat")
                       ] = "toon"


class ProxyExport(Message):
    format: Annotated[Literal["glb", "bvh", "mp4", "gif", "png", "passes"],
                      must(f"'format' must be one of {', '.join(PROXY_EXPORTS)}")] = required()
    name: Annotated[StrictStr, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9_-]{0,63}$"),
                    must("'name' must be 1 to 64 letters, digits, '-' or '_', starting with a letter or digit"
                         )] = required()


# The 3D panel's messages, by type (joined into messages.MODELS).
PROXY_MODELS: dict[str, type[Message]] = {"proxy": Message, "lift": Lift, "scene": Scene,
                                          "proxy_export": ProxyExport}

__all__ = ["ELEMENT_KINDS", "PROXY_EXPORTS", "PROXY_MODELS", "Lift", "ProxyExport", "Scene", "SceneElement"]
