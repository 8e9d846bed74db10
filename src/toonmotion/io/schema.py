"""One schema layer under every JSON file format: models, shared field types, one reader.

Each format declares a pydantic model of its file (on :class:`Model`: frozen, unknown keys
refused, no NaN or infinity) and a :class:`JsonFormat` saying which ``"format"`` names and
``"version"`` numbers it reads. :func:`read_versioned` then does what every loader needs: read
the file, check ``format`` and ``version`` once, step an old version up to the current one on the
raw dict, validate with the model, and turn the first validation problem into the format's
:class:`~toonmotion.errors.ToonmotionError` subclass with a one-line message naming the file and
the field, e.g. ``hero.json: joints[2].name: Input should be a valid string``.

A field can replace pydantic's wording with its own (:func:`explained`), for problems best said in
the file's terms (``'keys' must be a list``); such a message can name the item by its place,
``{n}`` (1 for the first), and can raise another error class (edits raise ``EditError``).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any, Generic, TypeVar

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    Strict,
    StrictInt,
    StrictStr,
    TypeAdapter,
    ValidationError,
    WrapValidator,
)
from pydantic_core import ErrorDetails, PydanticCustomError

from toonmotion import limits
from toonmotion.errors import ToonmotionError

M = TypeVar("M", bound="Model")

# The error type of a message given by :func:`explained`, and the context key of its error class.
_EXPLAINED = "toonmotion"
_ERROR_KEY = "toonmotion_error_class"


class Model(BaseModel):
    """Base of every file model: frozen, no unknown keys, every float finite."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)


# A number: a JSON int or float (read as float), never a bool or a string; finite in a Model.
Float = Annotated[float, Strict()]
# A whole number, never a bool or a float; one beyond 32 bits is no count, index or frame a file
# can mean, and would overflow the arrays it goes into.
Int = Annotated[StrictInt, Field(ge=-(2**31), le=2**31 - 1)]
# A joint or bone name: a non-empty string.
Name = Annotated[StrictStr, Field(min_length=1)]
# ``[x, y]`` in drawing pixels.
Point = tuple[Float, Float]

# ``describe(value, errors)``: a message, or a message and the error class to raise, or None.
Describe = Callable[[Any, list[ErrorDetails]], str | tuple[str, type[ToonmotionError]] | None]


def explained(message: str | Describe, *, error: type[ToonmotionError] | None = None) -> WrapValidator:
    """A validator (for ``Annotated[T, explained(...)]``) that words a problem in the file's terms.

    Parameters
    ----------
    message : str or callable
        A string replaces pydantic's message when the value itself is of the wrong kind (a
        problem at this level, not inside it). A callable ``message(value, errors)`` sees the
        raw value and pydantic's errors (locations relative to the value) and returns the
        message (or a message and the error class to raise), or None to keep pydantic's.
        ``{n}`` in a message is filled in by the reader with the item's place in its list,
        counting from 1.
    error : ToonmotionError subclass, optional
        The error to raise instead of the file format's own.
    """

    def validate(value: Any, handler: Callable[[Any], Any]) -> Any:
        try:
            return handler(value)
        except ValidationError as problem:
            errors = problem.errors()
            if errors[0]["type"] == _EXPLAINED:  # said already, by what holds the problem
                raise
            if callable(message):
                said = message(value, errors)
            else:
                said = message if not errors[0]["loc"] else None
            if said is None:
                raise
            text, cls = (said, error) if isinstance(said, str) else said
            raise PydanticCustomError(_EXPLAINED, text, {_ERROR_KEY: cls}) from None

    return WrapValidator(validate)


def joint_needs(value: Any, errors: list[ErrorDetails]) -> str | None:
    """For :func:`explained`: a joint that is not an object, or lacks its name or position."""
    first = errors[0]
    if not first["loc"] or (first["type"] == "missing" and len(first["loc"]) == 1):
        return "joint {n} needs a 'name' and a 'position: [x, y]'"
    return None


class Joint(Model):
    """A skeleton joint: ``{"name": ..., "parent": ... or null, "position": [x, y]}``."""

    name: Name
    parent: StrictStr | None = None
    position: Point


# The ``joints`` list of skeleton, motion and project files.
Joints = Annotated[
    list[Annotated[Joint, explained(joint_needs)]],
    explained("'joints' must be a list of {name, parent, position} objects"),
]


def location(loc: tuple[int | str, ...]) -> str:
    """A pydantic error location as a path into the file: ``('joints', 2, 'name')`` -> ``joints[2].name``.

    >>> location(("joints", 2, "name")), location(("frames", 0, 3, 1)), location(())
    ('joints[2].name', 'frames[0][3][1]', '')
    """
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def problem(message: str, *, error: type[ToonmotionError] | None = None) -> PydanticCustomError:
    """An error for a model validator to raise, worded like an :func:`explained` message."""
    return PydanticCustomError(_EXPLAINED, message, {_ERROR_KEY: error})


def describe(error: ErrorDetails) -> tuple[str, type[ToonmotionError] | None]:
    """One line for one pydantic error, and the error class an :func:`explained` field asks for.

    pydantic's own messages follow the field path (``joints[2].name: ...``). An explained
    message names its field itself (``'keys' must be a list``, ``joint 3 needs ...``), so only
    the path of what holds that field comes first (``keys[0]: 'edits' must be a list``).
    """
    loc = error["loc"]
    if error["type"] != _EXPLAINED:
        where = location(loc)
        return (f"{where}: {error['msg']}" if where else error["msg"]), None
    places = [i for i, part in enumerate(loc) if isinstance(part, int)]
    fields = [i for i, part in enumerate(loc) if isinstance(part, str)]
    text = error["msg"].replace("{n}", str(int(loc[places[-1]]) + 1) if places else "1")
    where = location(loc[: fields[-1]]) if fields else ""
    return (f"{where}: {text}" if where else text), error.get("ctx", {}).get(_ERROR_KEY)


_ADAPTERS: dict[Any, TypeAdapter[Any]] = {}


def validate(kind: Any, data: Any, *, where: str, error: type[ToonmotionError]) -> Any:
    """``data`` validated as ``kind`` (a model or any type pydantic knows).

    Raises ``error`` (or the class an :func:`explained` field names) with the one-line message
    ``"{where}: {field path}: {problem}"``.
    """
    if kind not in _ADAPTERS:
        _ADAPTERS[kind] = TypeAdapter(kind)
    try:
        return _ADAPTERS[kind].validate_python(data)
    except ValidationError as problem:
        text, cls = describe(problem.errors()[0])
        raise (cls or error)(f"{where}: {text}") from None


def read_json(path: str | Path, error: type[ToonmotionError], *, what: str = "") -> Any:
    """The parsed contents of ``path``; ``error`` (a ToonmotionError class) if it cannot be read.

    ``what`` names the kind of file in the message, e.g. ``"joints file "``.
    """
    path = Path(path)
    try:
        limits.check("file_bytes", path.stat().st_size, f"{what}{path.name}'s size in bytes")
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise error(f"cannot read {what}{path}: no such file") from None
    except RecursionError:
        raise error(f"cannot read {what}{path}: its lists or objects are nested too deeply") from None
    except (OSError, UnicodeDecodeError, ValueError) as problem:  # ValueError: JSON, or a 5000-digit int
        raise error(f"cannot read {what}{path} as JSON: {problem}") from None


Migration = Callable[[dict[str, Any]], dict[str, Any]]


@dataclass(frozen=True)
class JsonFormat(Generic[M]):
    """A versioned JSON file format: what it reads and how its errors read.

    Attributes
    ----------
    models : mapping of str to Model subclass
        The accepted ``"format"`` names, each with the model of its current version (most
        formats have one name; a pose file may also be a skeleton file).
    version : int
        The version written and validated.
    error : ToonmotionError subclass
        Raised for every problem with the file.
    title : str
        ``"{path} is not a {title} (format ...)"``.
    label : str
        ``"{path} is {label} version 7; this toonmotion reads version 1"``.
    what : str
        Names the file when it cannot be read: ``"cannot read {what}{path}"``.
    migrations : mapping of int to callable
        ``migrations[v]`` turns a version ``v`` file's raw dict into version ``v + 1`` (a new
        dict; it may be malformed, validation comes after the last step).
    """

    models: Mapping[str, type[M]]
    version: int
    error: type[ToonmotionError]
    title: str
    label: str
    what: str = ""
    migrations: Mapping[int, Migration] = field(default_factory=dict)

    @property
    def readable(self) -> tuple[int, ...]:
        """Every version this toonmotion reads, oldest first."""
        return (*sorted(self.migrations), self.version)

    def read(self, path: Path) -> Any:
        """The raw contents of the file."""
        return read_json(path, self.error, what=self.what)

    def not_this_format(self, path: Path) -> ToonmotionError:
        """The error for a file whose ``format`` is none of :attr:`models`."""
        names = " or ".join(repr(name) for name in self.models)
        return self.error(f"{path} is not a {self.title} (format {names})")

    def unreadable_version(self, path: Path, version: Any) -> ToonmotionError:
        """The error for a ``version`` that is not one of :attr:`readable`."""
        return self.error(
            f"{path} is {self.label} version {version!r}; this toonmotion reads version "
            + ", ".join(map(str, self.readable))
        )

    def invalid(self, path: Path, text: str, error: type[ToonmotionError] | None) -> ToonmotionError:
        """The error for a file that does not fit its model; ``text`` says where and what."""
        return (error or self.error)(f"{path}: {text}")


def read_versioned(path: str | Path, spec: JsonFormat[M]) -> M:
    """Read, check, migrate and validate a file of the format ``spec``; returns its model.

    Raises ``spec.error`` (or a field's own error class) with a one-line message naming the
    file, for a missing or unreadable file, another format, an unknown version, or a value
    that does not fit the model.
    """
    path = Path(path)
    return parse_versioned(spec.read(path), path, spec)


def parse_versioned(data: Any, path: str | Path, spec: JsonFormat[M]) -> M:
    """:func:`read_versioned` for a file already read into ``data``."""
    path = Path(path)
    name = data.get("format") if isinstance(data, dict) else None
    if not isinstance(name, str) or name not in spec.models:
        raise spec.not_this_format(path)
    version = data.get("version")
    # A bool is an int to Python; not to a file format.
    if isinstance(version, bool) or not isinstance(version, int) or version not in spec.readable:
        raise spec.unreadable_version(path, version)
    for step in range(version, spec.version):
        data = spec.migrations[step](dict(data))
        data["version"] = step + 1
    try:
        return spec.models[name].model_validate(data)
    except ValidationError as problem:
        text, error = describe(problem.errors()[0])
        raise spec.invalid(path, text, error) from None
