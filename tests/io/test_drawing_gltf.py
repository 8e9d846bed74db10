"""GLB export of an animated drawing (toonmotion.io.exchange.drawing_gltf), read back and evaluated.

The file is read with pygltflib and evaluated here, independently of the exporter: node
transforms ``T R S`` composed from the root (quaternions through scipy), skin joints' world
matrices times their inverse bind matrices, weights, and the morph targets at their animated
weights. At every frame this must land on toonmotion's own deformed vertices.
"""

import shutil
import subprocess

import numpy as np
import pygltflib as gl
import pytest
from PIL import Image

from tests.conftest import SAMPLE
from tests.gltf_reader import validator_installed, validator_report
from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.api import animate_character, set_depth
from toonmotion.deform.deformer import DeformSettings
from toonmotion.deform.depth import triangle_layers
from toonmotion.errors import ExportError
from toonmotion.io.exchange.drawing_gltf import PIXELS_PER_METRE, save_animation_glb
from toonmotion.io.exchange.drawing_rig import drawing_rig
from toonmotion.sample_animation import sample_keyframes
from toonmotion.testing.export_playback import GlbScene, glb_mesh

# Measured: 2.2e-5 to 4.4e-5 px over the cases below: float32 rounding of the skin, where a
# vertex carries no offset (drawing_gltf.MORPH_FLOOR_PX is 5e-5 px).
BOUND_PX = 1e-4


def in_pixels(points, character):
    """The file's points in the drawing's pixels: origin at the rest mesh's bottom centre, y up,
    100 pixels to the metre (drawing_rig's module docstring)."""
    V = character.mesh.V
    origin = np.array([(V[:, 0].min() + V[:, 0].max()) / 2, V[:, 1].max()])
    return points[:, :2] * PIXELS_PER_METRE * [1, -1] + origin


def export(character, animation, settings, path):
    save_animation_glb(path, drawing_rig(character, animation, settings=settings, unit=PIXELS_PER_METRE))
    return GlbScene(path)


CASES = {
    "one-bone": dict(settings=DeformSettings()),
    "weights": dict(settings=DeformSettings(skinning="weights")),
    "no area": dict(settings=DeformSettings(preserve_area=False)),
    "stage one only": dict(settings=DeformSettings(stage_two=False)),
    "solved in-betweens": dict(settings=DeformSettings(), method="solve"),
    "exaggerated": dict(settings=DeformSettings(), exaggeration=FilterSettings(strength=1.5)),
}


@pytest.mark.parametrize("name", ["one-bone", "weights", "no area", "stage one only", "solved in-betweens",
                                  "exaggerated"])
def test_every_frame_lands_on_the_deformed_drawing(rigs, tmp_path, name):
    case = dict(CASES[name])
    settings = case.pop("settings")
    hero = rigs.character(SAMPLE)
    animation = animate_character(hero, sample_keyframes(hero.skeleton), settings=settings, **case)
    scene = export(hero, animation, settings, tmp_path / "hero.glb")
    assert np.array_equal(scene.times, (np.arange(len(animation.meshes)) / animation.motion.fps)
                          .astype(np.float32))
    worst = 0.0
    for t, U in animation.meshes:
        points = glb_mesh(scene, t)
        assert np.abs(points[:, 2]).max() == 0
        worst = max(worst, np.abs(in_pixels(points, hero) - U).max())
    assert worst < BOUND_PX, f"{name}: {worst:.3g} px"
    targets = scene.gltf.meshes[0].primitives[0].targets
    assert (len(targets) == 0) == (name == "stage one only")


def test_stretched_bones_stay_within_the_morph_floor(rigs, tmp_path):
    """A figure grown to 1.8 times its size: the skin's float32 rounding grows with the stretch, and
    every vertex it misses by more than the floor carries an offset."""
    from toonmotion.animate.motion import Motion
    from toonmotion.io.exchange.drawing_gltf import MORPH_FLOOR_PX

    hero = rigs.character(SAMPLE)
    rest = hero.skeleton.positions
    grow = np.linspace(1.0, 1.8, 12)[:, None, None]
    motion = Motion(hero.skeleton, rest[0] + (rest - rest[0]) * grow, fps=12.0)
    animation = animate_character(hero, motion)
    scene = export(hero, animation, DeformSettings(), tmp_path / "grown.glb")
    worst = max(np.abs(in_pixels(glb_mesh(scene, t), hero) - U).max() for t, U in animation.meshes)
    assert worst <= MORPH_FLOOR_PX, f"{worst:.3g} px"


def test_a_bone_squashed_to_a_fortieth_stays_within_the_morph_floor(rigs, tmp_path):
    """Squashed to 1/40 of its length, a forearm is 40 times thicker across: the float32 rounding of
    its large rest-frame offsets, magnified 40 times, is carried by a second target."""
    from toonmotion.animate.motion import Motion
    from toonmotion.io.exchange.drawing_gltf import MORPH_FLOOR_PX

    hero = rigs.character(SAMPLE)
    skeleton = hero.skeleton
    start, end = skeleton.bones[np.argmax(skeleton.bone_lengths)]  # the longest bone
    below = [j for j in range(len(skeleton)) if _hangs_below(skeleton.parents, j, end)]
    P = np.tile(skeleton.positions, (10, 1, 1))
    for t, share in enumerate(np.geomspace(1.0, 1 / 40, 10)):
        move = (share - 1) * (skeleton.positions[end] - skeleton.positions[start])
        P[t, below] += move
    animation = animate_character(hero, Motion(skeleton, P, fps=12.0))
    scene = export(hero, animation, DeformSettings(), tmp_path / "squashed.glb")
    worst = max(np.abs(in_pixels(glb_mesh(scene, t), hero) - U).max() for t, U in animation.meshes)
    assert worst <= MORPH_FLOOR_PX, f"{worst:.3g} px"


def _hangs_below(parents, joint, top):
    """True when ``joint`` is ``top`` or below it."""
    while joint >= 0:
        if joint == top:
            return True
        joint = int(parents[joint])
    return False


def test_a_shared_drawing_too(rigs, drawing_dir, tmp_path):
    character = rigs.character(drawing_dir.name)
    animation = animate_character(character, sample_keyframes(character.skeleton))
    scene = export(character, animation, DeformSettings(), tmp_path / "drawing.glb")
    worst = max(np.abs(in_pixels(glb_mesh(scene, t), character) - U).max() for t, U in animation.meshes)
    assert worst < BOUND_PX, f"{drawing_dir.name}: {worst:.3g} px"


def test_joint_nodes_follow_the_joints_and_nothing_scales_a_joint(rigs, tmp_path):
    hero = rigs.character(SAMPLE)
    animation = animate_character(hero, sample_keyframes(hero.skeleton))
    scene = export(hero, animation, DeformSettings(), tmp_path / "hero.glb")
    for t in range(0, len(animation.meshes), 5):
        for j, name in enumerate(hero.skeleton.names):
            world = scene.world(scene.node(name), t)
            joint = in_pixels(world[None, :3, 3], hero)[0]
            assert np.abs(joint - animation.motion.positions[t, j]).max() < 1e-4
            assert np.allclose(world[:3, :3].T @ world[:3, :3], np.eye(3), atol=1e-6)  # a turn, no scale
        for start, end in hero.skeleton.bones:
            node = scene.node(f"bone:{hero.skeleton.names[end]}")
            assert scene.parent[node] == scene.node(hero.skeleton.names[start])


def test_texture_and_uvs_show_the_drawing_where_each_vertex_is(rigs, tmp_path):
    hero = rigs.character(SAMPLE)
    animation = animate_character(hero, sample_keyframes(hero.skeleton))
    scene = export(hero, animation, DeformSettings(), tmp_path / "hero.glb")
    gltf = scene.gltf
    view = gltf.bufferViews[gltf.images[0].bufferView]
    from io import BytesIO
    page = np.asarray(Image.open(BytesIO(scene.blob[view.byteOffset:view.byteOffset + view.byteLength])))
    primitive = gltf.meshes[0].primitives[0]
    uv = scene.read(primitive.attributes.TEXCOORD_0)
    h, w = page.shape[:2]
    # A vertex at a pixel centre samples that pixel: uv * size - 0.5 is the pixel's index.
    V = hero.mesh.V
    pixel = np.floor(V + 0.5).astype(int)
    clear = (np.abs(V + 0.5 - np.rint(V + 0.5)) > 1e-6).all(axis=1)  # not on a pixel's edge
    inside = hero.mask[pixel[:, 1], pixel[:, 0]] & clear
    at = np.floor(uv * [w, h]).astype(int)
    drawn = hero.texture[pixel[:, 1], pixel[:, 0]]
    assert inside.sum() > len(V) // 2
    assert np.array_equal(page[at[inside, 1], at[inside, 0]], drawn[inside])
    assert gltf.materials[0].alphaMode == "BLEND" and "KHR_materials_unlit" in gltf.extensionsUsed
    # Off the figure the page is transparent.
    assert page[..., 3].min() == 0


def test_triangles_face_the_viewer_back_to_front(rigs, tmp_path):
    hero = rigs.character(SAMPLE)
    arm = "right_elbow" if "right_elbow" in hero.skeleton.names else hero.skeleton.bone_names[-1]
    layered = set_depth(hero, 2, bone=arm)
    animation = animate_character(layered, sample_keyframes(layered.skeleton))
    scene = export(layered, animation, DeformSettings(), tmp_path / "hero.glb")
    primitive = scene.gltf.meshes[0].primitives[0]
    F = scene.read(primitive.indices).reshape(-1, 3).astype(int)
    P = scene.read(primitive.attributes.POSITION)
    a, b, c = P[F[:, 0]], P[F[:, 1]], P[F[:, 2]]
    assert (np.cross(b - a, c - a)[:, 2] > 0).all()  # counter-clockwise seen from +Z
    # Sorted triangles, mapped back to the mesh's, are in layer order.
    order = {tuple(sorted(t)): i for i, t in enumerate(F.tolist())}
    layers = triangle_layers(layered.mesh, layered.binding, layered.depth)
    position = np.array([order[tuple(sorted(t))] for t in np.asarray(layered.mesh.F).tolist()])
    assert (np.diff(layers[np.argsort(position)]) >= 0).all() and layers.max() == 2


@pytest.mark.parametrize("skinning", ["one-bone", "weights"])
def test_khronos_validator_finds_no_errors_or_warnings(rigs, tmp_path, skinning):
    if not validator_installed():
        pytest.skip("the glTF validator is not installed: run make test (npm ci)")
    hero = rigs.character(SAMPLE)
    settings = DeformSettings(skinning=skinning)
    animation = animate_character(hero, sample_keyframes(hero.skeleton), settings=settings)
    path = tmp_path / "hero.glb"
    save_animation_glb(path, drawing_rig(hero, animation, settings=settings, unit=PIXELS_PER_METRE))
    report = validator_report(path)
    assert report["numErrors"] == 0 and report["numWarnings"] == 0, report["messages"][:10]


def test_wrong_suffix_and_a_failed_write_keep_the_previous_file(rigs, tmp_path, monkeypatch):
    hero = rigs.character(SAMPLE)
    animation = animate_character(hero, sample_keyframes(hero.skeleton))
    rig = drawing_rig(hero, animation, unit=PIXELS_PER_METRE)
    with pytest.raises(ExportError, match=r"\.glb"):
        save_animation_glb(tmp_path / "hero.gltf", rig)
    path = tmp_path / "hero.glb"
    path.write_bytes(b"previous")

    def broken(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(gl.GLTF2, "save_to_bytes", broken)
    with pytest.raises(KeyboardInterrupt):
        save_animation_glb(path, rig)
    assert path.read_bytes() == b"previous" and sorted(p.name for p in tmp_path.iterdir()) == ["hero.glb"]


@pytest.mark.skipif(shutil.which("blender") is None, reason="Blender is not installed")
def test_blender_imports_the_glb_and_plays_a_frame_as_toonmotion_deforms_it(rigs, tmp_path):
    """Debian's Blender imports the file (armature, skin, shape keys); its evaluated mesh at an
    in-between frame is toonmotion's (Blender's axes: x, -z, y of glTF's)."""
    hero = rigs.character(SAMPLE)
    animation = animate_character(hero, sample_keyframes(hero.skeleton))
    path = tmp_path / "hero.glb"
    save_animation_glb(path, drawing_rig(hero, animation, unit=PIXELS_PER_METRE))
    frame = 9  # an in-between with stage two's offsets
    script = (
        "import bpy, numpy\n"
        # Debian's Blender 3.4 add-ons predate NumPy 1.24.
        "numpy.bool = getattr(numpy, 'bool', bool)\n"
        "bpy.ops.wm.read_homefile(use_empty=True)\n"
        f"bpy.ops.import_scene.gltf(filepath={str(path)!r})\n"
        "scene = bpy.context.scene\n"
        "mesh = [o for o in bpy.data.objects if o.type == 'MESH'][0]\n"
        "print('SHAPE KEYS', len(mesh.data.shape_keys.key_blocks) if mesh.data.shape_keys else 0)\n"
        "fps = scene.render.fps / scene.render.fps_base\n"
        f"scene.frame_set(int(round({frame} / {animation.motion.fps} * fps)) + 0)\n"
        "depsgraph = bpy.context.evaluated_depsgraph_get()\n"
        "evaluated = mesh.evaluated_get(depsgraph)\n"
        "data = evaluated.to_mesh()\n"
        "for v in data.vertices:\n"
        "    p = evaluated.matrix_world @ v.co\n"
        "    print('V', p.x, p.y, p.z)\n"
    )
    done = subprocess.run(["blender", "-b", "--factory-startup", "--python-expr", script],
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    points = np.array([[float(v) for v in line.split()[1:]] for line in done.stdout.splitlines()
                       if line.startswith("V ")])
    gltf_points = np.column_stack([points[:, 0], points[:, 2], -points[:, 1]])
    assert len(points) == len(hero.mesh.V)
    error = np.abs(in_pixels(gltf_points, hero) - animation.meshes[frame][1]).max()
    assert error < 1e-2, f"{error:.3g} px"
