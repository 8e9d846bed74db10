"""Tests for toonmotion.rig.character.RigSettings: settings that check themselves."""

import dataclasses

import numpy as np
import pytest

from toonmotion.errors import SettingsError
from toonmotion.rig.character import RigSettings


def test_defaults_are_valid():
    settings = RigSettings()
    assert (settings.spacing, settings.vertices, settings.segmentation) == (None, None, "auto")


def test_numbers_are_stored_as_floats_and_ints():
    settings = RigSettings(spacing=3, tolerance=1, max_bone=np.float32(20), min_part=0, prune=np.int64(1))
    for name in ("spacing", "tolerance", "max_bone", "min_part", "prune"):
        assert type(getattr(settings, name)) is float, name
    assert settings == RigSettings(spacing=3.0, tolerance=1.0, max_bone=20.0, min_part=0.0, prune=1.0)
    vertices = RigSettings(vertices=np.int64(300), refine_joints=np.bool_(True))
    assert type(vertices.vertices) is int and vertices.refine_joints is True


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"spacing": 0.5}, r"spacing must be at least 1 pixel, got 0\.5"),
        ({"spacing": 0}, r"spacing must be at least 1 pixel, got 0\.0"),
        ({"spacing": float("inf")}, r"spacing must be at least 1 pixel, got inf"),
        ({"spacing": float("nan")}, r"spacing must be at least 1 pixel, got nan"),
        ({"spacing": "4"}, r"spacing must be a number, got '4'"),
        ({"spacing": True}, r"spacing must be a number, got True"),
        ({"vertices": 2}, r"the vertex count must be at least 3, got 2"),
        ({"vertices": -5}, r"the vertex count must be at least 3, got -5"),
        ({"vertices": 300.0}, r"the vertex count must be a whole number, got 300\.0"),
        ({"vertices": True}, r"the vertex count must be a whole number, got True"),
        ({"spacing": 4.0, "vertices": 300}, r"give either a spacing or a vertex count, not both"),
        ({"tolerance": -1.0}, r"tolerance must be between 0 and 100 px, got -1\.0"),
        ({"tolerance": 101}, r"tolerance must be between 0 and 100 px, got 101\.0"),
        ({"tolerance": float("nan")}, r"tolerance must be between 0 and 100 px, got nan"),
        ({"min_part": 1.0}, r"min_part must be in \[0, 1\), got 1\.0"),
        ({"min_part": -0.1}, r"min_part must be in \[0, 1\), got -0\.1"),
        ({"min_part": None}, r"min_part must be a number, got None"),
        ({"prune": -1}, r"prune must be a finite number >= 0, got -1\.0"),
        ({"prune": float("inf")}, r"prune must be a finite number >= 0, got inf"),
        ({"max_bone": 0}, r"max_bone must be a finite number of pixels > 0, got 0\.0"),
        ({"max_bone": -3.0}, r"max_bone must be a finite number of pixels > 0, got -3\.0"),
        ({"segmentation": "magic"}, r"segmentation must be one of auto, flat, paper, got 'magic'"),
        ({"segmentation": None}, r"segmentation must be one of auto, flat, paper, got None"),
        ({"refine_joints": 1}, r"refine_joints must be True or False, got 1"),
        ({"largest_only": "yes"}, r"largest_only must be True or False, got 'yes'"),
    ],
)
def test_each_bad_value_is_refused_in_one_line(changes, message):
    with pytest.raises(SettingsError, match=rf"^{message}$"):
        RigSettings(**changes)


def test_replace_checks_again():
    settings = RigSettings(vertices=300)
    assert dataclasses.replace(settings, vertices=600).vertices == 600
    with pytest.raises(SettingsError, match="the vertex count must be at least 3"):
        dataclasses.replace(settings, vertices=2)
    with pytest.raises(SettingsError, match="give either a spacing or a vertex count"):
        dataclasses.replace(settings, spacing=4.0)


@pytest.mark.parametrize("value", [1, 1.0, 2.5, 1e6])
def test_the_cli_range_of_spacing_is_accepted(value):
    assert RigSettings(spacing=value).spacing == float(value)


@pytest.mark.parametrize(
    ("name", "value"), [("vertices", 3), ("tolerance", 0), ("tolerance", 100), ("min_part", 0)]
)
def test_range_ends_are_accepted(name, value):
    assert getattr(RigSettings(**{name: value}), name) == value
