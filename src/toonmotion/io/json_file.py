"""Reading a JSON file with one-line errors that name it."""

import json
from pathlib import Path


def read_json(path, error, *, what=""):
    """The parsed contents of ``path``; ``error`` (a ToonmotionError class) if it cannot be read.

    ``what`` names the kind of file in the message, e.g. ``"joints file "``.
    """
    path = Path(path)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error(f"cannot read {what}{path}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as problem:
        raise error(f"cannot read {what}{path} as JSON: {problem}") from None
