"""Spine 4.2 export (io/exchange/spine_json.py, spine_schema.py): the written skeleton, evaluated the
way Spine's runtime evaluates it, lands on every frame's deformed drawing; the files check out.

The evaluator below is written from Spine's documented runtime math (spine-runtimes 4.2,
``Bone.updateWorldTransformWith`` for ``inherit: normal``, ``RotateTimeline``/``TranslateTimeline``
relative to the setup pose, ``ScaleTimeline`` multiplying it, ``VertexAttachment.computeWorldVertices``
for weighted vertices plus deform offsets) and reads only the JSON file, not the exporter's code.
"""

import json

import numpy as np
import pytest
from PIL import Image

from tests.conftest import DRAWINGS_DIR, _require
from toonmotion.animate.skin_tracks import bone_matrices
from toonmotion.api import animate_character
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import ExportError
from toonmotion.io.exchange import spine_json
from toonmotion.io.exchange.drawing_rig import drawing_rig, to_pixels
from toonmotion.io.exchange.spine_json import _hull_first, save_spine, spine_skeleton
from toonmotion.io.exchange.spine_schema import read_spine_json
from toonmotion.sample_animation import sample_keyframes
from toonmotion.samples import sample_rig
from toonmotion.testing.export_playback import spine_mesh

# Measured max error over every frame and vertex, in drawing pixels (float64 evaluation), with the
# deform offsets written to 1e-6 px (spine_json.OFFSET_DECIMALS): about 1e-6 in every case below;
# 1.2e-11 when they were written in full precision.
TOLERANCE = 1e-3


@pytest.fixture(scope="module")
def hero():
    return sample_rig()


@pytest.fixture(scope="module")
def animated(hero):
    """``settings -> (animation, rig)`` for the sample character's built-in key-frames, cached."""
    keys, cache = sample_keyframes(hero.skeleton), {}

    def make(settings):
        if settings not in cache:
            animation = animate_character(hero, keys, settings=settings)
            cache[settings] = animation, drawing_rig(hero, animation, settings=settings)
        return cache[settings]

    return make


# -- an evaluator from Spine's documented runtime math -----------------------------------------


def max_error(path, rig, animation, order, name="animation"):
    """The largest distance, pixels, between the file's mesh and the animation's, over all frames."""
    doc = json.loads(path.read_text())
    fps = doc["skeleton"]["fps"]
    worst = 0.0
    for t, (_, U) in enumerate(animation.meshes):
        pixels = np.empty_like(U)
        pixels[order] = to_pixels(spine_mesh(doc, name, t / fps), rig)
        worst = max(worst, float(np.hypot(*(pixels - U).T).max()))
    return worst


# -- exactness ----------------------------------------------------------------------------------

CASES = {
    "one-bone": DeformSettings(),
    "weights": DeformSettings(skinning="weights"),
    "one-bone without area": DeformSettings(preserve_area=False),
    "weights without area": DeformSettings(skinning="weights", preserve_area=False),
    "stage two off": DeformSettings(stage_two=False, skinning="weights"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_the_file_evaluated_as_spine_does_lands_on_every_frame(case, animated, tmp_path):
    settings = CASES[case]
    animation, rig = animated(settings)
    path = tmp_path / "hero.json"
    save_spine(path, rig)
    order = spine_skeleton(rig).order
    error = max_error(path, rig, animation, order)
    print(case, "max error px", error)
    assert error < TOLERANCE
    doc = json.loads(path.read_text())
    deform = doc["animations"]["animation"].get("attachments")
    if not settings.stage_two:  # no frame needs offsets: no deform timeline at all
        assert deform is None
    else:
        keys = deform["default"]["drawing"]["drawing"]["deform"]
        assert len(keys) == rig.frame_count and any("vertices" in key for key in keys)


def test_a_real_drawing_whose_joint_is_called_root(tmp_path):
    from toonmotion.io.drawing_folder import rig_drawing_folder

    character = rig_drawing_folder(_require(DRAWINGS_DIR / "char2"))
    settings = DeformSettings(skinning="weights")
    animation = animate_character(character, sample_keyframes(character.skeleton), settings=settings)
    rig = drawing_rig(character, animation, settings=settings)
    path = tmp_path / "char2.json"
    save_spine(path, rig, name="hop")
    doc = json.loads(path.read_text())
    assert [b["name"] for b in doc["bones"][:2]] == ["root_1", "root"]  # the joint keeps its name
    error = max_error(path, rig, animation, spine_skeleton(rig).order, name="hop")
    print("char2 max error px", error)
    assert error < TOLERANCE


def test_offsets_are_the_smallest_that_carry_each_vertex_where_the_skin_misses_it(animated):
    """Per vertex, its entries' offsets are the least-norm solution of sum_k w_k L_k off_k = missed,
    with L_k bone k's posed linear part (in Spine's world, the rig's own skin) and missed what the
    skin leaves between it and toonmotion's vertex: so never larger than they need be, even where a
    blend of bones nearly cancels (see the next test)."""
    _, rig = animated(DeformSettings(skinning="weights"))
    spine = spine_skeleton(rig)
    mesh = spine.file.skins[0].attachments["drawing"]["drawing"]
    keys = spine.file.animations["animation"].attachments["default"]["drawing"]["drawing"].deform
    order = spine.order
    vertex, slot = np.nonzero(rig.weight[order] > 0)
    b = rig.bone[order][vertex, slot]
    w = rig.weight[order][vertex, slot]
    assert len(mesh.vertices) == len(order) + 4 * len(b)
    for t in (5, 12, 27):
        matrices = bone_matrices(rig.tracks, t)
        M = np.einsum("nk,nkij->nij", rig.weight[order], matrices[rig.bone[order]])
        missed = rig.U[t][order] - (np.einsum("nij,nj->ni", M[:, :, :2], rig.V[order]) + M[:, :, 2])
        angle, scale = rig.tracks.bone_angle[t][b], rig.tracks.bone_scale[t][b]
        c, s = np.cos(angle), np.sin(angle)
        L = np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2) * scale[:, None, :]
        # Each vertex's entries side by side, (2, 2 K), padded with zero columns to K = 4.
        stacked = np.zeros((len(order), 2, 8))
        column = slot  # entries keep their slot, so padding sits where weights are 0
        for k in range(4):
            at = column == k
            stacked[vertex[at], :, 2 * k:2 * k + 2] = w[at, None, None] * L[at]
        least = np.einsum("nij,nj->ni", np.linalg.pinv(stacked), missed).reshape(len(order), 4, 2)
        expected = least[vertex, slot]
        written = np.zeros(2 * len(b))
        written[keys[t].offset:keys[t].offset + len(keys[t].vertices)] = keys[t].vertices
        assert np.abs(written.reshape(-1, 2) - expected).max() <= 0.5e-6 + 1e-9  # written to 1e-6 px


def test_a_blend_that_nearly_cancels_keeps_its_offsets_small():
    """Two bones blended half and half, both squashed to 1/40 (40 times thicker across), one turned
    half round from the other: their blend nearly cancels, and one offset shared by both (what a
    glTF morph target must be) would be hundreds of times the entries' own."""
    from toonmotion.io.exchange.spine_json import _entry_offsets

    A = 0.5 * np.stack([np.diag([0.025, 40.0]), np.diag([-0.0249, -39.999])])
    missed = np.array([[0.3, -0.2]])
    offsets = _entry_offsets(missed, np.array([0, 0]), A)
    assert np.allclose(np.einsum("eij,ej->i", A, offsets), missed[0])
    shared = np.linalg.solve(A.sum(axis=0), missed[0])
    assert np.allclose(A.sum(axis=0) @ shared, missed[0])
    assert np.abs(shared).max() > 400 * np.abs(offsets).max()


# -- the files ----------------------------------------------------------------------------------


def parse_atlas(text):
    """Pages of a Spine 4 atlas: ``{page: {"fields": {...}, "regions": {name: {...}}}}``."""
    pages, page, region = {}, None, None
    for line in text.splitlines():
        if not line.strip():
            page = region = None
        elif ":" in line:
            key, value = (part.strip() for part in line.split(":", 1))
            target = pages[page]["regions"][region] if region else pages[page]["fields"]
            target[key] = [part.strip() for part in value.split(",")]
        elif page is None:
            page = line.strip()
            pages[page] = {"fields": {}, "regions": {}}
        else:
            region = line.strip()
            pages[page]["regions"][region] = {}
    return pages


def test_the_atlas_page_and_uvs(animated, tmp_path):
    _, rig = animated(DeformSettings())
    save_spine(tmp_path / "hero.json", rig)
    height, width = rig.page.shape[:2]
    atlas = parse_atlas((tmp_path / "hero.atlas").read_text())
    assert list(atlas) == ["hero.png"]
    page = atlas["hero.png"]
    assert page["fields"]["size"] == [str(width), str(height)]
    assert page["fields"]["filter"] == ["Linear", "Linear"]
    assert page["regions"] == {"drawing": {"bounds": ["0", "0", str(width), str(height)]}}
    assert np.array_equal(np.asarray(Image.open(tmp_path / "hero.png").convert("RGBA")), rig.page)
    doc = json.loads((tmp_path / "hero.json").read_text())
    uvs = np.array(doc["skins"][0]["attachments"]["drawing"]["drawing"]["uvs"]).reshape(-1, 2)
    assert uvs.min() >= 0 and uvs.max() <= 1
    assert np.array_equal(uvs, rig.uv[spine_skeleton(rig).order])
    assert doc["skeleton"]["spine"] == "4.2.00" and doc["skeleton"]["images"] == "./"
    assert doc["slots"] == [{"name": "drawing", "bone": "root_1", "attachment": "drawing"}]


def test_the_hull_is_the_outline_clockwise_from_its_first_vertex(hero, animated):
    _, rig = animated(DeformSettings())
    spine = spine_skeleton(rig)
    hull = spine.file.skins[0].attachments["drawing"]["drawing"].hull
    loops = hero.mesh.boundary
    V = hero.mesh.V
    def area(L):
        return abs(np.sum(V[L, 0] * np.roll(V[L, 1], -1) - np.roll(V[L, 0], -1) * V[L, 1]))

    outer = max(loops, key=area)
    # The drawing's outline runs counter-clockwise on screen; Spine's hull the other way round.
    assert spine.order[:hull].tolist() == np.roll(outer[::-1], 1).tolist()
    assert hull == len(outer)


def test_the_hull_of_a_mesh_with_a_hole_an_island_and_a_pinch():
    # A 3 x 3 grid of squares without the middle one (a ring: outer loop and hole), a far triangle,
    # and two triangles meeting at one vertex (a pinch), all counter-clockwise with y up.
    grid = np.array([(x, y) for y in range(4) for x in range(4)], float)
    F = []
    for y in range(3):
        for x in range(3):
            if (x, y) != (1, 1):
                a = 4 * y + x
                F += [(a, a + 1, a + 5), (a, a + 5, a + 4)]
    island = np.array([(10, 0), (11, 0), (10, 1), (12, 1), (13, 1), (12, 2)], float)
    V = np.concatenate([grid, island])
    F += [(16, 17, 18), (17, 19, 20), (17, 20, 21)]
    order, hull = _hull_first(V, np.array(F))
    assert hull == 12
    ring = [0, 4, 8, 12, 13, 14, 15, 11, 7, 3, 2, 1]  # clockwise (y up) from vertex 0
    assert order[:hull].tolist() == ring
    assert sorted(order.tolist()) == list(range(len(V)))


def test_the_schema_passes_the_written_file_and_refuses_broken_ones(animated, tmp_path):
    _, rig = animated(DeformSettings())
    path = tmp_path / "hero.json"
    save_spine(path, rig)
    model = read_spine_json(path)
    assert [bone.name for bone in model.bones] == [bone.name for bone in spine_skeleton(rig).file.bones]
    text = path.read_text()

    def broken(change):
        data = json.loads(text)
        change(data)
        out = tmp_path / "broken.json"
        out.write_text(json.dumps(data))
        return out

    def parent_later(data):
        data["bones"].append(data["bones"].pop(1))  # the joint "root" after its children

    def triangle_out_of_range(data):
        mesh = data["skins"][0]["attachments"]["drawing"]["drawing"]
        mesh["triangles"][4] = len(mesh["uvs"]) // 2

    def no_root(data):
        data["bones"].pop(0)

    with pytest.raises(ExportError, match=r"bone 'hip' names parent 'root', which comes after it"):
        read_spine_json(broken(parent_later))
    with pytest.raises(ExportError, match=r"'triangles' index vertex 1504, but the mesh has 1504 vertices"):
        read_spine_json(broken(triangle_out_of_range))
    with pytest.raises(ExportError, match=r"the first bone, 'root', has a parent; Spine's first bone is"):
        read_spine_json(broken(no_root))

    def short_weights(data):
        data["skins"][0]["attachments"]["drawing"]["drawing"]["vertices"].pop()

    def unknown_bone_key(data):
        data["animations"]["animation"]["bones"]["tail"] = {"rotate": [{"value": 1.0}]}

    def keys_out_of_order(data):
        keys = data["animations"]["animation"]["bones"]["bone:right_elbow"]["rotate"]
        keys[1], keys[2] = keys[2], keys[1]

    with pytest.raises(ExportError, match=r"weighted 'vertices' end inside vertex 1503"):
        read_spine_json(broken(short_weights))
    with pytest.raises(ExportError, match=r"keys bone 'tail', which is not in 'bones'"):
        read_spine_json(broken(unknown_bone_key))
    with pytest.raises(ExportError, match=r"keys must be in increasing time"):
        read_spine_json(broken(keys_out_of_order))


# -- bad input and failed writes -----------------------------------------------------------------


def test_a_path_not_ending_in_json_is_refused(animated, tmp_path):
    _, rig = animated(DeformSettings())
    with pytest.raises(ExportError, match=r"ends in \.json"):
        save_spine(tmp_path / "hero.skel", rig)
    assert list(tmp_path.iterdir()) == []


def test_a_failed_write_leaves_the_previous_set_and_no_temporaries(animated, tmp_path, monkeypatch):
    _, rig = animated(DeformSettings())
    path = tmp_path / "hero.json"
    save_spine(path, rig, name="first")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    calls = []
    real = type(path).write_bytes

    def fail_on_the_third(self, data):
        calls.append(self.name)
        if len(calls) == 3:
            raise OSError("disk full")
        return real(self, data)

    monkeypatch.setattr(type(path), "write_bytes", fail_on_the_third)
    with pytest.raises(OSError, match="disk full"):
        save_spine(path, rig, name="second")
    monkeypatch.undo()
    assert len(calls) == 3  # two files were staged before the failure
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before


def test_clashing_bone_names_are_refused(animated, monkeypatch):
    _, rig = animated(DeformSettings())
    monkeypatch.setattr(spine_json, "BONE_PREFIX", "")  # a bone named as its end joint
    with pytest.raises(ExportError, match=r"two Spine bones would be named 'hip'"):
        spine_skeleton(rig)
