"""Hypothesis strategies that spoil valid input: JSON documents, images, BVH text and option values.

Each strategy returns the spoiled input with ``must_refuse``: True when the input breaks a
rule every reader must enforce, so exit 0 would be a failure. The rules, the same for every
format:

* a JSON value replaced by one of another JSON type (a string for a number, a bool for a number,
  an object for a list, ...; ``null`` and int/float swaps excepted, since some fields are
  optional or take either), a list nested 50,000 deep, text that is no longer JSON, or a
  changed ``format`` or ``version``;
* an image with no valid header, an empty or random file, a header claiming more pixels than the
  limit, or a file cut inside its header;
* an option value that is not a finite number where a number is asked for.

Everything else (numbers changed within their type, deleted keys, dropped list items, odd image
modes and sizes, bytes flipped inside the picture data) may be accepted or refused; it must never
crash, hang or print more than one line.
"""

from __future__ import annotations

import copy
import io
import json
import struct
import zlib
from typing import Any

import numpy as np
from hypothesis import strategies as st
from PIL import Image

DEEP = 50_000
_DEEP_MARK = "__toonmotion_fuzz_deep__"

HOSTILE_VALUES: list[Any] = [
    2**70,
    -(2**70),
    10**30,
    -1,
    0,
    1,
    1e308,
    -1e308,
    1e-300,
    0.5,
    3.0,
    "",
    " ",
    "x",
    "root",
    "x" * 5000,
    "\u00e9\u0000",
    True,
    False,
    None,
    [],
    {},
    [1, 2],
    [[1, 2]],
    {"a": 1},
]
HOSTILE_NUMBERS: list[Any] = [0, -1, 1, 2**31, 2**70, 10**30, -1e9, 1e9, 1e308, -1e308, 1e-300, 0.5, -0.5]
HOSTILE_STRINGS = ["", " ", "x", "root", "head", "x" * 5000, "\u00e9", "\u0000", "../../etc/passwd"]


def json_type(value: Any) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, (int, float)):
        return "number"
    return {str: "string", list: "list", dict: "object", type(None): "null"}[type(value)]


def _paths(value: Any, path: tuple = ()) -> list[tuple]:
    found = [path]
    if isinstance(value, dict):
        for key, item in value.items():
            found += _paths(item, (*path, key))
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found += _paths(item, (*path, index))
    return found


def _get(value: Any, path: tuple) -> Any:
    for step in path:
        value = value[step]
    return value


def _set(document: Any, path: tuple, new: Any) -> Any:
    if not path:
        return new
    _get(document, path[:-1])[path[-1]] = new
    return document


@st.composite
def spoiled_json(draw, document: dict[str, Any]) -> tuple[str, bool, str]:
    """``(text, must_refuse, what was done)`` from a valid JSON ``document``."""
    text_level = draw(st.integers(0, 9)) == 0
    if text_level:
        text = json.dumps(document, indent=1)
        how = draw(st.sampled_from(["cut", "flip"]))
        if how == "cut":
            at = draw(st.integers(0, len(text) - 1))
            spoiled = text[:at]
        else:
            at = draw(st.integers(0, len(text) - 1))
            spoiled = text[:at] + draw(st.sampled_from(list('{}[],:"0a-. \\'))) + text[at + 1 :]
        try:
            json.loads(spoiled)
            parses = True
        except ValueError:
            parses = False
        return spoiled, not parses, f"{how} text at {at}"
    document = copy.deepcopy(document)
    path = draw(st.sampled_from(_paths(document)))
    old = _get(document, path)
    ops = ["retype", "deep"]
    if isinstance(old, (int, float)) and not isinstance(old, bool):
        ops += ["number"] * 4
    if isinstance(old, str):
        ops += ["string"] * 2
    if isinstance(old, list) and old:
        ops += ["drop", "repeat", "empty"]
    if isinstance(old, dict) and old:
        ops += ["delete", "add", "empty"]
    op = draw(st.sampled_from(ops))
    key = path[-1] if path else None
    vital = key in ("format", "version") and len(path) == 1
    must_refuse = False
    if op == "retype":
        choices = [v for v in HOSTILE_VALUES if json_type(v) != json_type(old)]
        new = draw(st.sampled_from(choices))
        must_refuse = json_type(old) != "null" and json_type(new) != "null" or vital
        document = _set(document, path, new)
    elif op == "deep":
        document = _set(document, path, _DEEP_MARK)
        must_refuse = True
    elif op == "number":
        new = draw(st.sampled_from([*HOSTILE_NUMBERS, old * 1e6, -old, old + 0.5]))
        must_refuse = vital and new != old
        document = _set(document, path, new)
    elif op == "string":
        new = draw(st.sampled_from([*HOSTILE_STRINGS, old + "_x", old.upper()]))
        must_refuse = vital and new != old
        document = _set(document, path, new)
    elif op == "drop":
        del old[draw(st.integers(0, len(old) - 1))]
    elif op == "repeat":
        old.append(copy.deepcopy(old[draw(st.integers(0, len(old) - 1))]))
    elif op == "empty":
        old.clear()
        must_refuse = not path  # an empty document has no format
    elif op == "delete":
        name = draw(st.sampled_from(sorted(old)))
        del old[name]
        must_refuse = not path and name in ("format", "version")
    elif op == "add":
        old[draw(st.sampled_from(["extra", "name", "", "joints"]))] = draw(st.sampled_from(HOSTILE_VALUES))
    text = json.dumps(document, indent=1)
    text = text.replace(json.dumps(_DEEP_MARK), "[" * DEEP + "]" * DEEP)
    return text, must_refuse, f"{op} at {list(path)}"


# --- images ---------------------------------------------------------------------------------------


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def bomb_png(width: int, height: int) -> bytes:
    """A PNG whose header claims ``width`` x ``height`` RGBA pixels over a few bytes of data."""
    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    return (
        b"\x89PNG\r\n\x1a\n"
        + _png_chunk(b"IHDR", header)
        + _png_chunk(b"IDAT", zlib.compress(b"\0" * 1000))
        + _png_chunk(b"IEND", b"")
    )


@st.composite
def spoiled_image(draw, rgba: np.ndarray, limit: int) -> tuple[bytes, str, bool, str]:
    """``(bytes, suffix, must_refuse, what)`` from a valid RGBA drawing; ``limit``: the pixel limit."""
    how = draw(st.sampled_from(["format", "format", "cut", "flip", "bomb", "junk", "size", "alpha"]))
    if how == "bomb":
        side = draw(st.integers(1, 200_000))
        other = max(1, limit // side + draw(st.integers(1, 10_000)))
        w, h = draw(st.permutations([side, other]))
        return bomb_png(w, h), ".png", w * h > limit, f"bomb {w}x{h}"
    if how == "junk":
        data = draw(st.sampled_from([b"", b"\x89PNG\r\n\x1a\n", b"GIF89a", b"hello", bytes(range(256)) * 4]))
        return data, draw(st.sampled_from([".png", ".jpg", ".gif", ".bmp"])), True, f"junk {data[:8]!r}"
    image = Image.fromarray(rgba)
    if how == "size":
        w, h = draw(st.integers(1, 64)), draw(st.integers(1, 64))
        image = image.resize((w, h))
    if how == "alpha":
        alpha = draw(st.sampled_from(["clear", "opaque", "checker", "half"]))
        a = np.asarray(image).copy()
        if alpha == "clear":
            a[..., 3] = 0
        elif alpha == "opaque":
            a[..., 3] = 255
        elif alpha == "checker":
            a[..., 3] = ((np.indices(a.shape[:2]).sum(axis=0) % 2) * 255).astype(np.uint8)
        else:
            a[..., 3] = 128
        image = Image.fromarray(a)
    fmt, suffix, modes = draw(
        st.sampled_from(
            [
                ("PNG", ".png", ["RGBA", "RGB", "L", "LA", "P", "1", "I;16"]),
                ("JPEG", ".jpg", ["RGB", "L"]),
                ("BMP", ".bmp", ["RGB", "L", "P", "1"]),
                ("GIF", ".gif", ["P", "L"]),
                ("TIFF", ".tif", ["RGBA", "RGB", "L", "I;16"]),
                ("WEBP", ".webp", ["RGBA", "RGB"]),
            ]
        )
    )
    mode = draw(st.sampled_from(modes))
    buffer = io.BytesIO()
    image.convert(mode).save(buffer, format=fmt)
    data = buffer.getvalue()
    if how == "cut":
        at = draw(st.integers(0, len(data) - 1))
        return data[:at], suffix, at < 26, f"{fmt} {mode} cut at {at} of {len(data)}"
    if how == "flip":
        data = bytearray(data)
        for _ in range(draw(st.integers(1, 8))):
            data[draw(st.integers(0, len(data) - 1))] = draw(st.integers(0, 255))
        return bytes(data), suffix, False, f"{fmt} {mode} bytes flipped"
    # A drawing that is transparent everywhere has no figure (once the alpha is dropped, it has).
    transparent = how == "alpha" and alpha == "clear" and mode in ("RGBA", "LA")
    return data, suffix, transparent, f"{fmt} {mode} {how}"


# --- options --------------------------------------------------------------------------------------

HOSTILE_OPTION_NUMBERS = [
    "0",
    "-1",
    "1",
    "0.001",
    "1e-300",
    "1e9",
    "1e12",
    "1e308",
    "-1e308",
    "2e19",
    str(2**70),
    "nan",
    "inf",
    "-inf",
    "abc",
    "",
    "1,2",
]


def not_a_finite_number(text: str) -> bool:
    try:
        return not np.isfinite(float(text))
    except ValueError:
        return True
