"""Tests for toonmotion.io.char_cfg (Animated Drawings char_cfg.yaml)."""

import numpy as np
import pytest
import yaml
from PIL import Image

from toonmotion.errors import SkeletonError
from toonmotion.io.char_cfg import load_char_cfg, save_char_cfg
from toonmotion.rig.skeleton import Skeleton


def test_every_shared_char_cfg_loads_with_its_size(drawing_dir):
    skeleton, size = load_char_cfg(drawing_dir / "char_cfg.yaml")
    with Image.open(drawing_dir / "texture.png") as texture:
        assert size == texture.size
    data = yaml.safe_load((drawing_dir / "char_cfg.yaml").read_text())
    assert len(skeleton) == len(data["skeleton"]) == 16
    assert set(skeleton.names) == {j["name"] for j in data["skeleton"]}
    roots = [skeleton.names[i] for i in np.flatnonzero(skeleton.parents == -1)]
    assert roots == ["root"]


def _same(a, b, *, atol=0.0):
    assert a.names == b.names
    np.testing.assert_array_equal(a.parents, b.parents)
    np.testing.assert_allclose(a.positions, b.positions, rtol=0, atol=atol)


def test_shared_char_cfg_round_trips(drawing_dir, tmp_path):
    skeleton, size = load_char_cfg(drawing_dir / "char_cfg.yaml")
    save_char_cfg(tmp_path / "again.yaml", skeleton, size)
    again, again_size = load_char_cfg(tmp_path / "again.yaml")
    assert again_size == size
    _same(again, skeleton)  # whole pixels: exact


def test_save_then_load_round_trips_names_parents_positions(tmp_path):
    skeleton = Skeleton.from_joints(
        [
            ("root", None, (10.25, 20.5)),
            ("spine", "root", (10.125, 5.0)),
            ("arm", "spine", (-3.5, 6.0)),
            ("hat", None, (1.0 / 3.0, 1e6)),
        ]
    )
    path = tmp_path / "sub" / "char_cfg.yaml"
    save_char_cfg(path, skeleton, (640, 480))
    loaded, size = load_char_cfg(path)
    assert size == (640, 480)
    # Positions are written to a thousandth of a pixel.
    _same(loaded, skeleton, atol=5e-4)
    np.testing.assert_array_equal(loaded.positions[:3], skeleton.positions[:3])
    data = yaml.safe_load(path.read_text())
    assert data["width"] == 640 and data["height"] == 480
    assert data["skeleton"][0] == {"name": "root", "parent": None, "loc": [10.25, 20.5]}
    assert [p.name for p in path.parent.iterdir()] == ["char_cfg.yaml"]  # no temp files


def _write(tmp_path, text, name="char_cfg.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("skeleton: [\n  {name: a\n", r"cannot read .*char_cfg.yaml as YAML: "),
        ("width: 10\nheight: 10\n", r"has no 'skeleton' list of joints; is it a char_cfg.yaml\?"),
        ("- just\n- a list\n", r"has no 'skeleton' list of joints"),
        ("skeleton: 5\n", r"has no 'skeleton' list of joints"),
        ("", r"has no 'skeleton' list of joints"),
        (
            "skeleton:\n- {name: root, parent: null, loc: [1, 2]}\n- {name: arm, parent: root}\n",
            r"char_cfg.yaml: joint 2 needs a 'name' and a 'loc: \[x, y\]'",
        ),
        ("skeleton:\n- 7\n", r"joint 1 needs a 'name' and a 'loc"),
        (
            "skeleton:\n- {name: root, parent: null, loc: [1, 2]}\n"
            "- {name: arm, parent: leg, loc: [3, 4]}\n",
            r"joint 'arm' names an unknown parent 'leg'",
        ),
        (
            "skeleton:\n- {name: a, parent: b, loc: [1, 2]}\n- {name: b, parent: a, loc: [3, 4]}\n",
            r"the skeleton has a cycle through joints a, b",
        ),
        (
            "skeleton:\n- {name: root, parent: null, loc: [1, two]}\n",
            r"joint 'root' has position \[1, 'two'\]; give two numbers \[x, y\]",
        ),
        (
            "width: wide\nheight: 4\nskeleton:\n- {name: root, parent: null, loc: [1, 2]}\n",
            r"width and height must be whole numbers",
        ),
    ],
    ids=[
        "bad-yaml",
        "missing-skeleton",
        "not-a-mapping",
        "skeleton-not-a-list",
        "empty-file",
        "joint-without-loc",
        "joint-not-a-mapping",
        "unknown-parent",
        "cycle",
        "bad-loc",
        "bad-width",
    ],
)
def test_malformed_char_cfg_raises_skeleton_error(tmp_path, text, message):
    path = _write(tmp_path, text)
    with pytest.raises(SkeletonError, match=message) as info:
        load_char_cfg(path)
    assert "\n" not in str(info.value)


def test_missing_char_cfg(tmp_path):
    with pytest.raises(SkeletonError, match="no such file"):
        load_char_cfg(tmp_path / "nope.yaml")


def test_undecodable_char_cfg(tmp_path):
    path = tmp_path / "char_cfg.yaml"
    path.write_bytes(b"skeleton: \xff\xfe\xfa\n")
    with pytest.raises(SkeletonError, match="cannot read .* as YAML") as info:
        load_char_cfg(path)
    assert "\n" not in str(info.value)


def test_size_is_none_without_width_and_height(tmp_path):
    path = _write(tmp_path, "skeleton:\n- {name: root, parent: null, loc: [1, 2]}\n")
    skeleton, size = load_char_cfg(path)
    assert size is None
    assert skeleton.names == ("root",)
