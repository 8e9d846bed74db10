"""Tests for toonmotion.io.schema: the shared models, the reader and its one-line errors."""

import json
import re
from typing import Annotated, Any, Literal

import pytest
from pydantic import model_validator

from toonmotion.errors import EditError, ToonmotionError
from toonmotion.io.schema import (
    Float,
    Int,
    Joint,
    Joints,
    JsonFormat,
    Model,
    Name,
    Point,
    explained,
    location,
    problem,
    read_json,
    read_versioned,
    validate,
)


class ThingError(ToonmotionError):
    """The error of the test format."""


class _Thing(Model):
    format: Literal["test.thing"]
    version: Literal[3]
    name: Name
    at: Point = (0.0, 0.0)
    count: Int = 0
    weight: Float = 1.0
    joints: Joints = []
    tags: Annotated[list[str], explained("'tags' must be a list of words")] = []
    items: list[Annotated[dict[str, Any], explained("item {n} must be an object", error=EditError)]] = []

    @model_validator(mode="after")
    def _no_ghosts(self) -> "_Thing":
        if self.name == "ghost":
            raise problem("a thing cannot be called ghost")
        return self


def _v1_to_v2(data):
    data["label"] = data.pop("title")
    return data


def _v2_to_v3(data):
    data["name"] = data.pop("label")
    return data


THING = JsonFormat(models={"test.thing": _Thing}, version=3, error=ThingError, title="thing file",
                   label="thing format", migrations={1: _v1_to_v2, 2: _v2_to_v3})


def _write(tmp_path, data, name="thing.json"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else json.dumps(data), encoding="utf-8")
    return path


def _thing(**changes):
    return {"format": "test.thing", "version": 3, "name": "box"} | changes


def _refused(path, message, error=ThingError):
    with pytest.raises(ToonmotionError) as info:
        read_versioned(path, THING)
    assert type(info.value) is error
    text = str(info.value)
    assert "\n" not in text
    assert re.fullmatch(message.format(path=re.escape(str(path))), text), text
    return text


def test_a_valid_file_reads_as_its_model(tmp_path):
    thing = read_versioned(_write(tmp_path, _thing(at=[1, 2.5], count=4)), THING)
    assert isinstance(thing, _Thing)
    assert (thing.name, thing.at, thing.count) == ("box", (1.0, 2.5), 4)
    assert isinstance(thing.at[0], float)


def test_old_versions_step_up_on_the_raw_dict(tmp_path):
    one = {"format": "test.thing", "version": 1, "title": "old box"}
    assert read_versioned(_write(tmp_path, one), THING).name == "old box"
    two = {"format": "test.thing", "version": 2, "label": "newer box"}
    assert read_versioned(_write(tmp_path, two), THING).name == "newer box"
    assert THING.readable == (1, 2, 3)


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (None, r"cannot read {path}: no such file"),
        ("{oops", r"cannot read {path} as JSON: .*"),
        ([1, 2], r"{path} is not a thing file \(format 'test.thing'\)"),
        (_thing(format="test.other"), r"{path} is not a thing file \(format 'test.thing'\)"),
        (_thing(format=["test.thing"]), r"{path} is not a thing file .*"),
        (_thing(version=True), r"{path} is thing format version True; this toonmotion reads version 1, 2, 3"),
        (_thing(version=3.0), r"{path} is thing format version 3.0; .*"),
        (_thing(version=4), r"{path} is thing format version 4; .*"),
        (_thing(version=0), r"{path} is thing format version 0; .*"),
        ({"format": "test.thing"}, r"{path} is thing format version None; .*"),
    ],
    ids=["missing", "not-json", "not-an-object", "other-format", "unhashable-format", "bool-version",
         "float-version", "future-version", "old-unknown-version", "no-version"],
)
def test_format_and_version_are_checked_once_for_all(tmp_path, data, message):
    path = tmp_path / "thing.json"
    if data is not None:
        _write(tmp_path, data)
    _refused(path, message)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"name": 1}, r"{path}: name: Input should be a valid string"),
        ({"name": ["box"]}, r"{path}: name: Input should be a valid string"),
        ({"name": ""}, r"{path}: name: String should have at least 1 character"),
        ({"at": [1, True]}, r"{path}: at\[1\]: Input should be a valid number"),
        ({"at": [1, "2"]}, r"{path}: at\[1\]: Input should be a valid number"),
        ({"at": [1, 2, 3]}, r"{path}: at: Tuple should have at most 2 items.*"),
        ({"weight": 1e400}, r"{path}: weight: Input should be a finite number"),
        ({"count": True}, r"{path}: count: Input should be a valid integer"),
        ({"count": 2.0}, r"{path}: count: Input should be a valid integer"),
        ({"colour": "red"}, r"{path}: colour: Extra inputs are not permitted"),
        ({"joints": [{"name": "a", "position": [0, 0]}, {"name": 2, "parent": None, "position": [1, 1]}]},
         r"{path}: joints\[1\].name: Input should be a valid string"),
        ({"joints": [{"name": "a", "parent": 7, "position": [0, 0]}]},
         r"{path}: joints\[0\].parent: Input should be a valid string"),
    ],
    ids=["int-name", "list-name", "empty-name", "bool-coordinate", "string-coordinate", "three-coordinates",
         "infinite", "bool-int", "float-int", "unknown-key", "joint-name", "joint-parent"],
)
def test_a_bad_field_is_one_line_naming_file_and_field(tmp_path, changes, message):
    _refused(_write(tmp_path, _thing(**changes)), message)


@pytest.mark.parametrize(
    ("changes", "message", "error"),
    [
        ({"tags": "red"}, r"{path}: 'tags' must be a list of words", ThingError),
        ({"tags": ["red", 5]}, r"{path}: tags\[1\]: Input should be a valid string", ThingError),
        ({"items": [{}, {}, 3]}, r"{path}: item 3 must be an object", EditError),
        ({"name": "ghost"}, r"{path}: a thing cannot be called ghost", ThingError),
        ({"joints": [{"name": "a", "position": [0, 0]}, {"name": "b"}]},
         r"{path}: joint 2 needs a 'name' and a 'position: \[x, y\]'", ThingError),
        ({"joints": {"a": [0, 0]}},
         r"{path}: 'joints' must be a list of \{{name, parent, position\}} objects", ThingError),
    ],
    ids=["list-level", "inside-the-list", "item-numbered", "model-validator", "joint-numbered", "joints"],
)
def test_explained_fields_word_problems_in_the_files_terms(tmp_path, changes, message, error):
    _refused(_write(tmp_path, _thing(**changes)), message, error)


def test_validate_names_where_the_data_came_from():
    joints = validate(Joints, [{"name": "a", "parent": None, "position": [1, 2]}], where="w",
                      error=ThingError)
    assert joints == [Joint(name="a", parent=None, position=(1.0, 2.0))]
    with pytest.raises(ThingError, match=r"^here: joint 1 needs a 'name' and a 'position: \[x, y\]'$"):
        validate(Joints, [{"name": "a"}], where="here", error=ThingError)
    with pytest.raises(ThingError, match=r"^here: \[0\]\.position\[0\]: Input should be a valid number$"):
        validate(Joints, [{"name": "a", "position": [None, 1]}], where="here", error=ThingError)


def test_models_are_frozen():
    joint = Joint(name="a", position=(1, 2))
    with pytest.raises(ValueError):
        joint.name = "b"


def test_location():
    assert location(("keys", 0, "edits", 2, "points", 1, 0)) == "keys[0].edits[2].points[1][0]"
    assert location((3,)) == "[3]"


def test_read_json_keeps_raw_data(tmp_path):
    path = _write(tmp_path, {"anything": [1, True]}, name="raw.json")
    assert read_json(path, ThingError) == {"anything": [1, True]}
    with pytest.raises(ThingError, match=r"cannot read joints file .*gone.json: no such file"):
        read_json(tmp_path / "gone.json", ThingError, what="joints file ")
