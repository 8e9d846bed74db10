"""Tests for toonmotion.io.project (project folders)."""

import dataclasses
import json
import re

import numpy as np
import pytest
from PIL import Image

import toonmotion.io.project as project_module
from toonmotion.errors import ProjectError, ProjectVersionError, ToonmotionError
from toonmotion.io.project import PROJECT_FILE, load_project, save_project
from toonmotion.rig.binding import Correction
from toonmotion.rig.character import RigSettings
from toonmotion.rig.edits import DepthEdit, apply_edit, undo
from toonmotion.rig.pipeline import rig_drawing
from toonmotion.rig.skeleton import Skeleton


def _u_drawing():
    """A U with a hole in its bottom bar, random colours; transparent background."""
    mask = np.zeros((60, 62), dtype=bool)
    mask[4:52, 4:24] = True
    mask[4:52, 28:48] = True
    mask[40:52, 4:48] = True
    mask[44:49, 14:19] = False
    rgba = np.random.default_rng(7).integers(0, 256, size=(60, 62, 4), dtype=np.uint8)
    rgba[..., 3] = np.where(mask, 255, 0)
    return rgba


def _skeleton():
    # "outside" runs 7 px right of the figure: near enough to be accepted, and its vertices
    # that cannot reach a bone inside the figure are recorded as fallback.
    return Skeleton.from_joints(
        [
            ("base", None, (6.0, 46.0)),
            ("left", "base", (6.0, 6.0)),
            ("bar", "base", (40.0, 46.0)),
            ("top", None, (54.0, 48.0)),
            ("outside", "top", (54.0, 6.0)),
        ]
    )


@pytest.fixture(scope="module")
def character():
    # Whole-number settings as a user would type them: saved and reloaded as floats. The thesis's
    # straight-line rule, so that fallback vertices are saved and read back too.
    settings = RigSettings(spacing=3, tolerance=1, max_bone=20, min_part=0, prune=1, decomposition="straight")
    ch = rig_drawing(_u_drawing(), skeleton=_skeleton(), settings=settings)
    curve = np.array([[2.3, 10.7], [25.1, 10.7], [25.1, 20.3], [2.3, 20.3]])
    ch = apply_edit(ch, Correction(curve=curve, bone="bar"))
    ch = apply_edit(ch, DepthEdit(value=2, at=(10.0, 30.0)))
    ch = apply_edit(ch, DepthEdit(value=-1, bone="outside"))
    assert ch.silhouette.parts[0].holes, "the test drawing should have a hole"
    assert ch.binding.fallback.any(), "the test rig should have fallback vertices"
    return ch


def _assert_same(a, b):
    np.testing.assert_array_equal(a.texture, b.texture)
    assert a.texture.dtype == b.texture.dtype == np.uint8
    np.testing.assert_array_equal(a.mask, b.mask)
    assert a.mask.dtype == b.mask.dtype == bool
    assert a.silhouette.tolerance == b.silhouette.tolerance
    assert len(a.silhouette.parts) == len(b.silhouette.parts)
    for pa, pb in zip(a.silhouette.parts, b.silhouette.parts, strict=True):
        assert len(pa.holes) == len(pb.holes)
    for la, lb in zip(a.silhouette.loops, b.silhouette.loops, strict=True):
        np.testing.assert_array_equal(la, lb)
    ca, cb = a.curve_skeleton, b.curve_skeleton
    np.testing.assert_array_equal(ca.nodes, cb.nodes)
    assert ca.kinds == cb.kinds
    np.testing.assert_array_equal(ca.radius, cb.radius)
    np.testing.assert_array_equal(ca.branches, cb.branches)
    for pa, pb in zip(ca.paths, cb.paths, strict=True):
        np.testing.assert_array_equal(pa, pb)
    assert len(ca.paths) == len(cb.paths)
    assert a.skeleton.names == b.skeleton.names
    np.testing.assert_array_equal(a.skeleton.parents, b.skeleton.parents)
    np.testing.assert_array_equal(a.skeleton.positions, b.skeleton.positions)
    np.testing.assert_array_equal(a.mesh.V, b.mesh.V)
    np.testing.assert_array_equal(a.mesh.F, b.mesh.F)
    assert len(a.mesh.boundary) == len(b.mesh.boundary)
    for la, lb in zip(a.mesh.boundary, b.mesh.boundary, strict=True):
        np.testing.assert_array_equal(la, lb)
    assert a.mesh.spacing == b.mesh.spacing
    for field in ("bone", "fallback", "vertex_kind", "joint_triangle", "joint_area"):
        np.testing.assert_array_equal(getattr(a.binding, field), getattr(b.binding, field))
    assert len(a.binding.corrections) == len(b.binding.corrections)
    for ka, kb in zip(a.binding.corrections, b.binding.corrections, strict=True):
        assert ka.bone == kb.bone
        np.testing.assert_array_equal(ka.curve, kb.curve)
    assert a.settings == b.settings
    np.testing.assert_array_equal(a.depth, b.depth)
    for ea, eb in zip(a.edits + a.undone, b.edits + b.undone, strict=True):
        assert type(ea) is type(eb)
        if isinstance(ea, Correction):
            assert ea.bone == eb.bone
            np.testing.assert_array_equal(ea.curve, eb.curve)
        else:
            assert ea == eb
    assert (len(a.edits), len(a.undone)) == (len(b.edits), len(b.undone))


def _files(folder):
    return sorted(p.name for p in folder.iterdir())


def _assets(folder):
    data = json.loads((folder / PROJECT_FILE).read_text())
    return data["texture"], data["mask"]


def test_save_then_load_gives_equal_arrays(character, tmp_path):
    save_project(tmp_path / "hero", character)
    loaded = load_project(tmp_path / "hero")
    _assert_same(loaded, character)
    # project.json itself may be named too.
    _assert_same(load_project(tmp_path / "hero" / PROJECT_FILE), character)
    texture, mask = _assets(tmp_path / "hero")
    assert _files(tmp_path / "hero") == sorted([PROJECT_FILE, texture, mask])
    assert texture.startswith("texture-") and mask.startswith("mask-")


def test_saving_a_loaded_project_writes_the_same_bytes(character, tmp_path):
    save_project(tmp_path / "a", character)
    first = (tmp_path / "a" / PROJECT_FILE).read_bytes()
    save_project(tmp_path / "b", load_project(tmp_path / "a"))
    assert (tmp_path / "b" / PROJECT_FILE).read_bytes() == first
    save_project(tmp_path / "a", load_project(tmp_path / "a"))  # in place, too
    assert (tmp_path / "a" / PROJECT_FILE).read_bytes() == first
    for name in _assets(tmp_path / "a"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_settings_are_saved_with_their_types(character, tmp_path):
    save_project(tmp_path / "p", character)
    settings = json.loads((tmp_path / "p" / PROJECT_FILE).read_text())["settings"]
    assert settings["spacing"] == 3.0 and isinstance(settings["spacing"], float)
    assert settings["vertices"] is None
    assert load_project(tmp_path / "p").settings == character.settings


def test_corrections_survive_the_round_trip(character, tmp_path):
    save_project(tmp_path / "p", character)
    loaded = load_project(tmp_path / "p")
    (correction,) = loaded.binding.corrections
    assert correction.bone == "bar"
    np.testing.assert_array_equal(correction.curve, character.binding.corrections[0].curve)
    # The loaded binding carries the corrected bones, not a fresh decomposition.
    bar = loaded.skeleton.bone_names.index("bar")
    inside = (
        (loaded.mesh.V[:, 0] > 2.3) & (loaded.mesh.V[:, 0] < 25.1)
        & (loaded.mesh.V[:, 1] > 10.7) & (loaded.mesh.V[:, 1] < 20.3)
    )
    assert inside.any() and np.all(loaded.binding.bone[inside] == bar)


def test_resaving_a_changed_project_removes_stale_assets_only(character, tmp_path):
    folder = tmp_path / "hero"
    save_project(folder, character)
    old_texture, old_mask = _assets(folder)
    (folder / "notes.txt").write_text("mine")
    (folder / "reference.png").write_bytes(b"not toonmotion's")
    texture = character.texture.copy()
    texture[0, 0] = (1, 2, 3, 4)
    save_project(folder, dataclasses.replace(character, texture=texture))
    new_texture, new_mask = _assets(folder)
    assert new_texture != old_texture and new_mask == old_mask
    assert _files(folder) == sorted(
        [PROJECT_FILE, new_texture, new_mask, "notes.txt", "reference.png"]
    )
    assert (folder / "notes.txt").read_text() == "mine"
    np.testing.assert_array_equal(load_project(folder).texture, texture)


def test_saving_over_a_file_is_refused(character, tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(ProjectError, match="is a file; a project is a folder"):
        save_project(tmp_path / "file", character)


def test_a_drawing_given_for_a_project_is_named_as_not_one(tmp_path):
    (tmp_path / "hero.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    with pytest.raises(ProjectError, match=r"hero\.png is a file, not a project: give the project folder"):
        load_project(tmp_path / "hero.png")


@pytest.fixture
def saved(character, tmp_path):
    folder = tmp_path / "p"
    save_project(folder, character)
    return folder


def _edit(folder, change):
    path = folder / PROJECT_FILE
    data = json.loads(path.read_text())
    change(data)
    path.write_text(json.dumps(data))


def _expect(folder, error, message):
    with pytest.raises(error, match=message) as info:
        load_project(folder)
    assert isinstance(info.value, ProjectError) and isinstance(info.value, ToonmotionError)
    assert "\n" not in str(info.value), str(info.value)
    return info.value


def test_missing_folder(tmp_path):
    _expect(tmp_path / "nowhere", ProjectError, r"no project at .*nowhere: give a project folder")


def test_folder_without_project(tmp_path):
    _expect(tmp_path, ProjectError, "no project at")


def test_garbage_json(saved):
    (saved / PROJECT_FILE).write_text("{ this is : not json")
    _expect(saved, ProjectError, r"cannot read .*project.json as JSON: Expecting")


@pytest.mark.parametrize(
    "change",
    [lambda d: d.update(format="toonmotion.skeleton"), lambda d: d.pop("format"),
     lambda d: d.clear()],
    ids=["other-format", "no-format", "empty"],
)
def test_wrong_format(saved, change):
    _edit(saved, change)
    _expect(saved, ProjectError, r"is not a toonmotion project \(no 'format': 'toonmotion.project'\)")


def test_json_that_is_not_an_object(saved):
    (saved / PROJECT_FILE).write_text("[1, 2, 3]")
    _expect(saved, ProjectError, "is not a toonmotion project")


def test_newer_version_says_upgrade(saved):
    _edit(saved, lambda d: d.update(version=4))
    error = _expect(saved, ProjectVersionError, r"is project version 4, newer than this toonmotion")
    assert str(error).endswith("upgrade toonmotion")


@pytest.mark.parametrize("version", [0, "1", None])
def test_unknown_version(saved, version):
    _edit(saved, lambda d: d.update(version=version))
    _expect(saved, ProjectVersionError, r"has unknown project version .*reads versions 1, 2, 3")


def _first_triangle_out_of_range(data):
    data["mesh"]["triangles"][0][1] = len(data["mesh"]["vertices"]) + 5


def _negative_triangle_index(data):
    data["mesh"]["triangles"][3][2] = -1


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (_first_triangle_out_of_range, "a mesh triangle names a vertex that does not exist"),
        (_negative_triangle_index, "a mesh triangle names a vertex that does not exist"),
        (lambda d: d["binding"]["vertex_bone"].pop(), r"the binding has \d+ vertices but the mesh has"),
        (lambda d: d["binding"]["vertex_bone"].__setitem__(0, 99), "names a bone that does not exist"),
        (lambda d: d["binding"]["fallback"].append(10**6), "fallback list names a vertex"),
        (lambda d: d["binding"]["bones"].reverse(), "bone list does not match the skeleton"),
        (lambda d: d["edits"][0].update(bone="tail"), "unknown bone 'tail'"),
        (lambda d: d["edits"][2].update(bone="tail"), "unknown bone 'tail'"),
        (lambda d: d["edits"][1].update(bone="bar"), "names a bone or gives a point"),
        (lambda d: d["binding"].update(corrections=[{"bone": "bar", "curve": [[0, 0], [1, 0], [0, 1]]}]),
         "keeps its corrections in 'edits'"),
        (lambda d: d["mesh"]["boundary"][0].reverse(), "outline loops must list vertices 0, 1"),
        (lambda d: d["mesh"]["triangles"].pop(), "the project's mesh is broken: "),
        (lambda d: d["curve_skeleton"]["branches"][0].update(nodes=[0, 999]), "branch names a node"),
        (lambda d: d["skeleton"]["joints"][1].update(parent="nobody"), "unknown parent 'nobody'"),
        (lambda d: d["mesh"].update(spacing=-1), r"not a valid project: mesh.spacing: "),
        (lambda d: d.pop("binding"), r"not a valid project: binding: Field required"),
        (lambda d: d.update(extra=1), r"not a valid project: extra: "),
        (lambda d: d["mesh"]["vertices"][0].append(1.0), r"not a valid project: mesh.vertices.0"),
    ],
    ids=[
        "triangle-index-out-of-range",
        "negative-triangle-index",
        "binding-wrong-length",
        "binding-bone-out-of-range",
        "fallback-out-of-range",
        "bone-list-mismatch",
        "correction-unknown-bone",
        "depth-edit-unknown-bone",
        "depth-edit-bone-and-point",
        "v3-corrections-in-binding",
        "boundary-out-of-order",
        "missing-triangle",
        "curve-skeleton-node-out-of-range",
        "skeleton-unknown-parent",
        "negative-spacing",
        "missing-section",
        "unknown-key",
        "three-coordinates",
    ],
)
def test_inconsistent_projects_raise_project_error(saved, change, message):
    _edit(saved, change)
    _expect(saved, ProjectError, message)


def test_texture_of_the_wrong_size(saved):
    texture, _ = _assets(saved)
    Image.fromarray(np.zeros((10, 12, 4), dtype=np.uint8)).save(saved / texture)
    _expect(saved, ProjectError, r"the project's texture is 12x10 but the project says 62x60")


def test_mask_of_the_wrong_size(saved):
    _, mask = _assets(saved)
    Image.fromarray(np.zeros((60, 61), dtype=np.uint8)).save(saved / mask)
    _expect(saved, ProjectError, r"the project's mask is 61x60 but the project says 62x60")


def test_missing_asset(saved):
    texture, _ = _assets(saved)
    (saved / texture).unlink()
    _expect(saved, ProjectError, r"not a valid project: cannot read .*texture-.*no such file")


def test_damaged_asset(saved):
    texture, _ = _assets(saved)
    data = (saved / texture).read_bytes()
    (saved / texture).write_bytes(data[: len(data) // 2])
    _expect(saved, ProjectError, r"not a valid project: cannot read .* damaged or truncated")


def test_failed_save_leaves_the_previous_project(character, saved, monkeypatch):
    before = {name: (saved / name).read_bytes() for name in _files(saved)}

    def fail(path, text):
        raise OSError("disk full")

    monkeypatch.setattr(project_module, "write_text", fail)
    texture = character.texture.copy()
    texture[5, 5] = 0
    changed = dataclasses.replace(character, texture=texture)
    with pytest.raises(OSError, match="disk full"):
        save_project(saved, changed)
    monkeypatch.undo()
    # Unchanged: same files with the same bytes; the new texture written first is gone again.
    assert _files(saved) == sorted(before)
    for name, data in before.items():
        assert (saved / name).read_bytes() == data
    _assert_same(load_project(saved), character)
    assert not any(p.name.endswith(".tmp") for p in saved.iterdir())


def _to_version_2(data):
    """A version 3 project as version 2 wrote it: corrections in the binding, no history."""
    data["version"] = 2
    data["binding"]["corrections"] = [
        {"bone": e["bone"], "curve": e["curve"]} for e in data["edits"] if e["kind"] == "correction"
    ]
    del data["edits"], data["undone"]


def test_version_1_loads_with_every_region_at_depth_0(saved):
    """Projects written before depth layers existed still load."""
    def to_v1(data):
        _to_version_2(data)
        data["version"] = 1
        del data["depth"]

    _edit(saved, to_v1)
    loaded = load_project(saved)
    assert not loaded.depth.any()
    assert [type(e) for e in loaded.edits] == [Correction]


def test_version_2_loads_as_an_edit_history(saved, character):
    """A version 2 project's corrections and depths become edits that can be undone."""
    _edit(saved, _to_version_2)
    loaded = load_project(saved)
    assert [type(e) for e in loaded.edits] == [Correction, DepthEdit, DepthEdit]
    np.testing.assert_array_equal(loaded.depth, character.depth)
    np.testing.assert_array_equal(loaded.binding.bone, character.binding.bone)
    earlier, _ = undo(loaded, 2)
    assert not earlier.depth.any()
    np.testing.assert_array_equal(earlier.binding.bone, character.binding.bone)


def test_depth_layers_round_trip(tmp_path, saved):
    character = load_project(saved)
    depth = np.arange(len(character.depth)) % 3 - 1
    save_project(tmp_path / "p", dataclasses.replace(character, depth=depth))
    assert load_project(tmp_path / "p").depth.tolist() == depth.tolist()


def test_depth_naming_an_unknown_bone(saved):
    _edit(saved, lambda d: d["depth"].update(tail=2))
    _expect(saved, ProjectError, "unknown bone 'tail'")


def test_a_bool_version_is_not_version_1(saved):
    _edit(saved, lambda d: d.update(version=True))
    _expect(saved, ProjectVersionError, r".*project.json has unknown project version True; .*1, 2, 3$")


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: d["skeleton"]["joints"][1].update(name=5),
         r"skeleton\.joints\[1\]\.name: Input should be a valid string"),
        (lambda d: d["skeleton"]["joints"][1].update(name=["left"]),
         r"skeleton\.joints\[1\]\.name: Input should be a valid string"),
        (lambda d: d["skeleton"]["joints"][1].update(parent=0),
         r"skeleton\.joints\[1\]\.parent: Input should be a valid string"),
        (lambda d: d["skeleton"]["joints"][1].pop("position"),
         r"skeleton: joint 2 needs a 'name' and a 'position: \[x, y\]'"),
        (lambda d: d["mesh"]["triangles"][0].__setitem__(0, True),
         r"mesh\.triangles\[0\]\[0\]: Input should be a valid integer"),
        (lambda d: d["binding"]["vertex_bone"].__setitem__(0, 0.0),
         r"binding\.vertex_bone\[0\]: Input should be a valid integer"),
        (lambda d: d.update(width=62.0), r"width: Input should be a valid integer"),
        (lambda d: d["edits"][1].update(value=True),
         r"edits\[1\]\.depth\.value: Input should be a valid integer"),
        (lambda d: d["settings"].update(vertices=300.0),
         r"settings\.vertices: Input should be a valid integer"),
        (lambda d: d["settings"].update(spacing="3"), r"settings\.spacing: Input should be a valid number"),
        (lambda d: d["settings"].update(refine_joints=1),
         r"settings\.refine_joints: Input should be a valid boolean"),
        (lambda d: d["settings"].update(colour="red"), r"settings\.colour: Extra inputs are not permitted"),
        (lambda d: d["settings"].update(spacing=0.5), r"spacing must be at least 1 pixel, got 0\.5"),
        (lambda d: d["settings"].update(segmentation="sky"),
         r"segmentation must be one of auto, flat, paper, got 'sky'"),
        (lambda d: d["settings"].update(vertices=300), r"give either a spacing or a vertex count, not both"),
    ],
    ids=["int-name", "list-name", "int-parent", "joint-without-position", "bool-index", "float-index",
         "float-width", "bool-depth", "float-vertices", "string-spacing", "int-flag", "unknown-setting",
         "small-spacing", "unknown-segmentation", "spacing-and-vertices"],
)
def test_a_bad_value_names_the_file_and_field(saved, change, message):
    _edit(saved, change)
    where = re.escape(str(saved / PROJECT_FILE))
    _expect(saved, ProjectError, rf"^{where} is not a valid project: {message}$")


def test_settings_are_saved_field_by_field_from_the_dataclass(character, tmp_path):
    save_project(tmp_path / "p", character)
    settings = json.loads((tmp_path / "p" / PROJECT_FILE).read_text())["settings"]
    assert list(settings) == [f.name for f in dataclasses.fields(RigSettings)]
    assert settings == dataclasses.asdict(character.settings)
    _edit(tmp_path / "p", lambda d: d["settings"].pop("prune"))  # a missing setting takes its default
    assert load_project(tmp_path / "p").settings.prune == RigSettings().prune


def test_version_2_depth_edits_follow_the_bone_order(saved, character):
    _edit(saved, _to_version_2)
    loaded = load_project(saved)
    depth_bones = [e.bone for e in loaded.edits if isinstance(e, DepthEdit)]
    names = loaded.skeleton.bone_names
    assert len(depth_bones) == 2
    assert depth_bones == [n for n, d in zip(names, character.depth, strict=True) if d != 0]
    # A migrated project saves as version 3 and reads back the same.
    save_project(saved, loaded)
    assert json.loads((saved / PROJECT_FILE).read_text())["version"] == 3
    _assert_same(load_project(saved), loaded)


def test_a_project_is_not_saved_into_a_folder_of_other_files(character, tmp_path):
    (tmp_path / "holiday.jpg").write_bytes(b"mine")
    with pytest.raises(ProjectError, match=r"holds other files \(holiday.jpg, ...\) and no project"):
        save_project(tmp_path, character)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["holiday.jpg"]
    (tmp_path / "empty").mkdir()
    save_project(tmp_path / "empty", character)  # an empty folder is fine, and so is a project
    save_project(tmp_path / "empty", character)
