"""GLB export of a proxy (toonmotion.io.exchange.proxy_gltf), read back and evaluated.

The file is read with pygltflib and its scene evaluated here at every keyframe (node transforms
``T R S`` composed from the root, morph weights, skinning, the camera's projection): it must
reproduce the proxy to float32 precision. The Khronos validator checks the file itself.
"""

import shutil
import subprocess

import numpy as np
import pytest

from tests.gltf_reader import validator_installed, validator_report
from tests.proxy3d.synthetic_proxy import BRANCHING, FOREST, synthetic_proxy
from toonmotion.errors import ProxyError
from toonmotion.io.bvh import save_bvh
from toonmotion.io.exchange.proxy_gltf import save_proxy_glb
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.proxy3d.skeleton_bvh import limb_tree, skeleton_clip
from toonmotion.testing.export_playback import GlbScene

# float32 storage: positions to this many metres, pixels to this many.
METRES, PIXELS = 1e-5, 1e-3


@pytest.fixture(scope="module", params=["branching", "forest"])
def exported(request, tmp_path_factory):
    proxy = synthetic_proxy(BRANCHING if request.param == "branching" else FOREST, frames=8, seed=5)
    path = tmp_path_factory.mktemp("glb") / "proxy.glb"
    save_proxy_glb(path, proxy)
    return proxy, GlbScene(path)


def test_one_key_per_frame_at_frame_over_fps(exported):
    proxy, scene = exported
    assert np.array_equal(scene.times, (np.arange(proxy.frame_count) / proxy.fps).astype(np.float32))
    assert all(len(track) % proxy.frame_count == 0 for track in scene.tracks.values())


def test_skeleton_joints_reproduce_the_skeleton(exported):
    proxy, scene = exported
    tree = limb_tree(proxy)
    error = max(np.abs(scene.at(tree.names[tree.markers[n]], t) - proxy.skeleton[t, n]).max()
                for t in range(proxy.frame_count) for n in range(len(proxy.names)))
    assert error < METRES, f"skeleton joints off by {error:.3g} m"
    # The same joints, names and offsets as the BVH clip.
    clip = skeleton_clip(proxy)
    for j, name in enumerate(clip.names):
        node = scene.gltf.nodes[scene.node(name)]
        if clip.parents[j] >= 0:
            assert scene.gltf.nodes[scene.parent[scene.node(name)]].name == clip.names[clip.parents[j]]
            assert np.allclose(node.translation, clip.offsets[j], rtol=0, atol=0)


def test_the_skin_moves_each_limb_with_its_joint(exported):
    proxy, scene = exported
    tree = limb_tree(proxy)
    (skin,) = scene.gltf.skins
    (mesh_node,) = [n for n in scene.gltf.nodes if n.skin is not None]
    assert mesh_node.translation is None and mesh_node.rotation is None  # a root with no transform
    primitive = scene.gltf.meshes[mesh_node.mesh].primitives[0]
    V = scene.read(primitive.attributes.POSITION)
    joints = scene.read(primitive.attributes.JOINTS_0)
    weights = scene.read(primitive.attributes.WEIGHTS_0)
    assert np.all(weights == [1, 0, 0, 0])
    ibm = scene.read(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    assert len(ibm) == len(skin.joints)
    # Octahedra in the tree's order of limb joints: the first vertex at the limb's start, the last
    # at its end; every vertex bound to its limb's joint.
    limb_joints = np.flatnonzero(tree.limbs >= 0)
    assert len(V) == 6 * len(limb_joints)
    for t in range(proxy.frame_count):
        for i, j in enumerate(limb_joints):
            p, c = proxy.limbs[tree.limbs[j]]
            assert np.all(joints[6 * i:6 * i + 6, 0] == skin.joints.index(scene.node(tree.names[j])))
            M = scene.world(skin.joints[joints[6 * i, 0]], t) @ ibm[joints[6 * i, 0]]
            skinned = (M @ np.c_[V[6 * i:6 * i + 6], np.ones(6)].T).T[:, :3]
            assert np.abs(skinned[0] - proxy.skeleton[t, p]).max() < METRES
            assert np.abs(skinned[5] - proxy.skeleton[t, c]).max() < METRES


def test_cylinders_span_their_markers_with_their_radii(exported):
    proxy, scene = exported
    for k, (p, c) in enumerate(proxy.limbs):
        node = scene.node(f"cylinder/{proxy.names[p]}-{proxy.names[c]}")
        primitive = scene.gltf.meshes[scene.gltf.nodes[node].mesh].primitives[0]
        base = scene.read(primitive.attributes.POSITION)
        targets = [scene.read(target["POSITION"]) for target in primitive.targets]
        bottom, top = (np.flatnonzero(np.abs(target).sum(1) > 0) for target in targets)
        assert len(bottom) == len(top) >= 8
        for t in range(proxy.frame_count):
            M = scene.world(node, t)
            w = scene.weights(node, t)
            assert np.abs(w - proxy.radii[t, k]).max() < METRES
            V = base + w[0] * targets[0] + w[1] * targets[1]
            world = (M @ np.c_[V, np.ones(len(V))].T).T[:, :3]
            ends = proxy.cylinders[t, k]
            assert np.abs(M @ [0, 0, 0, 1] - [*ends[0], 1]).max() < METRES
            assert np.abs(M @ [0, 1, 0, 1] - [*ends[1], 1]).max() < METRES
            axis = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
            for ring, centre, radius in zip((bottom, top), ends, proxy.radii[t, k], strict=True):
                offsets = world[ring] - centre
                assert np.abs(np.linalg.norm(offsets, axis=1) - radius).max() < METRES
                assert np.abs(offsets @ axis).max() < METRES  # the ring is square to the limb


def test_spheres_and_points_follow_the_markers(exported):
    proxy, scene = exported
    sphere_radii = proxy.sphere_radii
    for n, name in enumerate(proxy.names):
        sphere = scene.node(f"sphere/{name}")
        V = scene.read(scene.gltf.meshes[scene.gltf.nodes[sphere].mesh].primitives[0].attributes.POSITION)
        for t in range(proxy.frame_count):
            assert np.abs(scene.at(f"point/{name}", t) - proxy.points[t, n]).max() < METRES
            world = (scene.world(sphere, t) @ np.c_[V, np.ones(len(V))].T).T[:, :3]
            distance = np.linalg.norm(world - proxy.points[t, n], axis=1)
            assert np.abs(distance - sphere_radii[t, n]).max() < METRES


def test_the_camera_sees_points_where_the_proxy_camera_projects_them(exported):
    proxy, scene = exported
    node = scene.node("camera")
    camera = scene.gltf.cameras[scene.gltf.nodes[node].camera]
    assert camera.type == "perspective"
    yfov, aspect = camera.perspective.yfov, camera.perspective.aspectRatio
    W, H = proxy.camera.width, proxy.camera.height
    assert aspect == W / H
    expected = proxy.camera.project(proxy.points)
    worst = 0.0
    for t in range(proxy.frame_count):
        view = np.linalg.inv(scene.world(node, t))
        P = (view @ np.c_[proxy.points[t], np.ones(len(proxy.names))].T).T[:, :3]
        assert np.all(P[:, 2] < 0)  # glTF cameras look down their -Z
        ndc = P[:, :2] / -P[:, 2:] / np.tan(yfov / 2) / [aspect, 1]
        pixels = np.stack([(ndc[:, 0] + 1) / 2 * W, (1 - ndc[:, 1]) / 2 * H], axis=1)
        worst = max(worst, np.abs(pixels - expected[t]).max())
    assert worst < PIXELS, f"the glTF camera is {worst:.3g} px off"


def test_no_limbs_no_radii_and_one_frame(tmp_path):
    proxy = synthetic_proxy({"ball": None}, frames=1, radii=False)
    save_proxy_glb(tmp_path / "ball.glb", proxy)
    scene = GlbScene(tmp_path / "ball.glb")
    assert not scene.gltf.skins and "collision" not in scene.by_name
    assert np.abs(scene.at("ball", 0) - proxy.skeleton[0, 0]).max() < METRES
    assert np.abs(scene.at("point/ball", 0) - proxy.points[0, 0]).max() < METRES
    if validator_installed():
        report = validator_report(tmp_path / "ball.glb")
        assert report["numErrors"] == 0 and report["numWarnings"] == 0, report["messages"][:10]


def test_values_beyond_float32_are_refused_and_nothing_is_written(tmp_path):
    proxy = synthetic_proxy({"ball": None}, frames=1, radii=False)
    far = Proxy(proxy.names, proxy.parents, proxy.fps, proxy.camera, points=proxy.points + 1e39, radii=None,
                skeleton=proxy.skeleton, rest=proxy.rest, limb_rotations=proxy.limb_rotations)
    with pytest.raises(ProxyError, match="32-bit floats"):
        save_proxy_glb(tmp_path / "far.glb", far)
    assert list(tmp_path.iterdir()) == []


# -- the Khronos validator and Blender -----------------------------------------------------------


@pytest.mark.parametrize("radii", [True, False], ids=["radii", "no radii"])
def test_khronos_validator_finds_no_errors(tmp_path, radii):
    if not validator_installed():
        pytest.skip("the glTF validator is not installed: run make test (npm ci)")
    path = tmp_path / "proxy.glb"
    save_proxy_glb(path, synthetic_proxy(FOREST, frames=5, radii=radii, gimbal=True))
    report = validator_report(path)
    assert report["numErrors"] == 0 and report["numWarnings"] == 0, (
        f"{report['numErrors']} errors, {report['numWarnings']} warnings: {report['messages'][:10]}")


@pytest.mark.skipif(shutil.which("blender") is None, reason="Blender is not installed")
def test_blender_imports_the_glb_and_the_bvh_and_poses_them_as_the_skeleton(tmp_path):
    """Debian's Blender imports both files; at every frame each limb's bone starts at its parent
    joint of the skeleton proxy (Blender's axes: x, -z, y of ours), in the glTF (frame t) and in
    the BVH (frame t + 1)."""
    proxy = synthetic_proxy(FOREST, frames=4)
    save_proxy_glb(tmp_path / "proxy.glb", proxy)
    save_bvh(tmp_path / "proxy.bvh", skeleton_clip(proxy))
    script = (
        "import bpy, builtins, numpy\n"
        # Debian's Blender 3.4 add-ons predate NumPy 1.24 and Python 3.11: numpy.bool and open(.., 'rU').
        "numpy.bool = getattr(numpy, 'bool', bool)\n"
        "import io_anim_bvh.import_bvh as ib\n"
        "ib.open = lambda f, mode='r', *a, **k: builtins.open(f, mode.replace('U', ''), *a, **k)\n"
        "bpy.ops.wm.read_homefile(use_empty=True)\n"
        f"bpy.ops.import_scene.gltf(filepath={str(tmp_path / 'proxy.glb')!r})\n"
        "gltf = [o for o in bpy.data.objects if o.type == 'ARMATURE']\n"
        f"bpy.ops.import_anim.bvh(filepath={str(tmp_path / 'proxy.bvh')!r})\n"
        "bvh = [o for o in bpy.data.objects if o.type == 'ARMATURE' and o not in gltf]\n"
        "print('ARMATURES', len(gltf) + len(bvh), 'CAMERAS', len(bpy.data.cameras))\n"
        "for kind, arm, shift in (('glb', gltf[0], 0), ('bvh', bvh[0], 1)):\n"
        f"    for t in range({proxy.frame_count}):\n"
        "        bpy.context.scene.frame_set(t + shift)\n"
        "        for bone in arm.pose.bones:\n"
        "            h = arm.matrix_world @ bone.head\n"
        "            print('HEAD', kind, t, bone.name, h.x, h.y, h.z)\n"
    )
    done = subprocess.run(["blender", "-b", "--factory-startup", "--python-expr", script],
                          capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stderr[-2000:]
    assert "ARMATURES 2 CAMERAS 1" in done.stdout, done.stdout[-2000:]
    heads = {}
    for line in done.stdout.splitlines():
        if line.startswith("HEAD "):
            _, kind, t, name, x, y, z = line.split()
            heads[kind, int(t), name] = np.array([float(x), float(y), float(z)])
    checked = 0
    for kind in ("glb", "bvh"):
        for t in range(proxy.frame_count):
            for p, c in proxy.limbs:
                x, y, z = proxy.skeleton[t, p]
                np.testing.assert_allclose(heads[kind, t, proxy.names[c]], [x, -z, y], atol=1e-4)
                checked += 1
    assert checked == 2 * proxy.frame_count * len(proxy.limbs)
