"""Simulating a scene around a moving proxy: the drawing's frame rate outside, MuJoCo's sub-steps
inside (section 3.5).

Between drawn frames ``t`` and ``t + 1`` the proxy moves in a straight line: every sub-step writes
each kinematic body's pose and velocity (the frame's displacement times the frame rate) and its
capsules' sizes before MuJoCo steps, so contacts see the proxy's true velocity. At each drawn
frame the proxy is put exactly at its frame's pose before the scene is read, so a string held at
a marker starts exactly at the marker's point.

The result, :class:`SceneMotion`, is the elements as primitives per frame (spheres and capsules,
the form :func:`toonmotion.render.zbuffer.render_primitives` draws, and the cloths' triangles,
which :func:`toonmotion.render.cloth.render_cloth` draws), plus what tests and reports measure:
the balls' centres and how far any ball ended a step inside a proxy capsule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion.errors import SceneError
from toonmotion.progress import Progress
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.scene.build import SEGMENTS, SceneModel, drops_in
from toonmotion.scene.mjcf import load_mujoco

MAX_STEP = 0.002  # seconds: the longest sub-step (the contacts' time constant is twice this)
# Seconds the cloth hangs from the still first pose before frame 0, so it is seen hanging, not in
# the straight sheet it is built as (measured: a 0.7 m scarf settles within 0.6 s).
CLOTH_SETTLE = 0.6
# The fastest a cloth vertex may move: this times the proxy's fastest marker, plus the margin
# (m/s); a whip's tip moves a few times faster than the hand. Measured: a scarf at a hand of a
# six-armed figure, its forearm spinning round it twice a second, was squeezed between the forearm
# and its knot out to 50-120 m without it; with it, it stays hanging.
CLOTH_SPEED_FACTOR = 3.0
CLOTH_SPEED_MARGIN = 2.0


@dataclass(frozen=True, eq=False)
class SceneMotion:
    """The scene's elements per drawn frame.

    Attributes
    ----------
    spheres : (T, S, 4) float
        Centre and radius, metres.
    capsules : (T, C, 7) float
        End a, end b and radius, metres (strings; the string's first capsule starts at its marker).
    colours : (S + C, 3) uint8
        Spheres' then capsules' colours.
    held : (T, H, 3) float
        Each string's held end (its first capsule's end a).
    held_markers : (H,) int
        The marker holding each string.
    balls : (T, B, 4) float
        The balls' centres and radii.
    deepest : float
        The deepest a ball ended a sub-step inside a proxy capsule, metres (0: never).
    substeps : int
        MuJoCo steps per drawn frame.
    cloth_vertices : (T, V, 3) float
        Every scarf's and skirt's vertices, metres, one cloth after another.
    cloth_triangles : (F, 3) int
        Their triangles, indices into ``cloth_vertices``.
    cloth_colours : (F, 3) uint8
        Each triangle's colour.
    cloth_pinned, cloth_markers : (P,) int
        The pinned vertices (a scarf's knot, a skirt's waistband) and the marker each moves with.
    """

    spheres: NDArray[np.float64]
    capsules: NDArray[np.float64]
    colours: NDArray[np.uint8]
    held: NDArray[np.float64]
    held_markers: NDArray[np.int64]
    balls: NDArray[np.float64]
    deepest: float
    substeps: int
    cloth_vertices: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0, 3)))
    cloth_triangles: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    cloth_colours: NDArray[np.uint8] = field(default_factory=lambda: np.zeros((0, 3), np.uint8))
    cloth_pinned: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    cloth_markers: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))


def simulate(scene: SceneModel, proxy: Proxy, *, progress: Progress | None = None) -> SceneMotion:
    """Run the scene through the proxy's frames.

    Parameters
    ----------
    scene : SceneModel
        From :func:`toonmotion.scene.build.build_scene` for this proxy.
    proxy : Proxy
    progress : callable, optional
        ``progress("simulate", done, total)`` per frame.

    Returns
    -------
    SceneMotion
    """
    mujoco = load_mujoco()
    try:
        return _simulate(mujoco, scene, proxy, progress)
    except mujoco.FatalError as error:  # MuJoCo's own errors (its arena full, say): one line
        raise SceneError(f"the simulation stopped: {str(error).splitlines()[0]} (fewer or smaller elements "
                         "may fit)") from None


def _simulate(mujoco: Any, scene: SceneModel, proxy: Proxy, progress: Progress | None) -> SceneMotion:
    model = scene.model
    data = mujoco.MjData(model)
    T = proxy.frame_count
    substeps = max(1, math.ceil(1.0 / (proxy.fps * MAX_STEP)))
    model.opt.timestep = 1.0 / (proxy.fps * substeps)
    kinematic = _Kinematic(scene, proxy, model)
    fastest = float(np.linalg.norm(np.diff(proxy.points, axis=0), axis=-1).max(initial=0.0) * proxy.fps)
    cloth = _Cloth(scene, model, cap=CLOTH_SPEED_FACTOR * fastest + CLOTH_SPEED_MARGIN)
    kinematic.cloth = cloth
    spheres = [g for g in scene.element_geoms if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE]
    capsules = [g for g in scene.element_geoms if model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE]
    order = [scene.element_geoms.index(g) for g in spheres + capsules]
    S, C = len(spheres), len(capsules)
    out_spheres, out_capsules = np.zeros((T, S, 4)), np.zeros((T, C, 7))
    out_balls = np.zeros((T, len(scene.balls), 4))
    held_geoms = [g for g, _ in scene.held]
    out_held = np.zeros((T, len(held_geoms), 3))
    out_cloth = np.zeros((T, len(cloth.vertices), 3))
    rain = _Rain(scene, model)
    kinematic.place(data, 0, 0.0, moving=False)
    mujoco.mj_forward(model, data)
    if scene.cloths:  # the elements settle from the still first pose
        still = kinematic.poses(0, [0.0], moving=False)
        for _ in range(math.ceil(CLOTH_SETTLE / model.opt.timestep)):
            kinematic.write(data, still, 0)
            mujoco.mj_step(model, data)
        kinematic.place(data, 0, 0.0, moving=False)
        rain.respawn(data)
        mujoco.mj_forward(model, data)
    fractions = np.arange(substeps) / substeps
    heard: list[str] = []  # MuJoCo's warnings, kept from its log file and stdout
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(heard.append)
    try:
        deepest = 0.0
        for t in range(T):
            if t > 0:
                poses = kinematic.poses(t - 1, fractions, moving=True)
                for s in range(substeps):
                    kinematic.write(data, poses, s)
                    mujoco.mj_step(model, data)
                    deepest = max(deepest, kinematic.deepest_ball(data))
                kinematic.place(data, t, 0.0, moving=t < T - 1)
                rain.respawn(data)
                mujoco.mj_forward(model, data)
            for i, g in enumerate(spheres):
                out_spheres[t, i] = (*data.geom_xpos[g], model.geom_size[g, 0])
            for i, g in enumerate(capsules):
                out_capsules[t, i] = _capsule(data, model, g)
            for i, g in enumerate(scene.balls):
                out_balls[t, i] = (*data.geom_xpos[g], model.geom_size[g, 0])
            for i, g in enumerate(held_geoms):
                out_held[t, i] = _capsule(data, model, g)[:3]
            out_cloth[t] = data.flexvert_xpos[cloth.vertices]
            if progress is not None:
                progress("simulate", t + 1, T)
    finally:
        mujoco.set_mju_user_warning(previous)
    if data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number > 0:
        speed = float(np.linalg.norm(np.diff(proxy.points, axis=0), axis=-1).max(initial=0.0) * proxy.fps)
        raise SceneError(f"the simulation became unstable ({heard[0].strip() if heard else 'MuJoCo'}); "
                         f"the proxy's markers reach {speed:.1f} m/s (a lift whose camera or depth jumps "
                         "between frames moves it metres at once: check it with proxy-preview), or an "
                         "element is too light or starts inside the body or the ground")
    colours = np.asarray(scene.colours).reshape(-1, 3)[order] if order else np.zeros((0, 3), np.uint8)
    return SceneMotion(out_spheres, out_capsules, colours, out_held,
                       np.array([m for _, m in scene.held], dtype=np.int64), out_balls, deepest, substeps,
                       out_cloth, cloth.triangles, cloth.colours, cloth.pinned, cloth.markers)


class _Cloth:
    """The scene's flexes as one triangle mesh (which of MuJoCo's flex vertices to read, in order),
    and what keeps the cloth in the world's frame while its holder is moved by hand.

    A cloth's free vertices slide on joints of the holding marker's body, so writing the marker's
    position and velocity would carry them along rigidly (a jump in the marker's velocity between
    drawn frames would jerk the whole cloth, and the marker's own fall during a step, undone when
    it is written back, would hide gravity from them). :meth:`carry` takes each write's change off
    the vertices' joints, so they keep their world positions and velocities, and applies air's drag
    on the marker's part of their world velocity (the joints' damping sees only their own part).
    """

    def __init__(self, scene, model, cap=np.inf):
        self.cap = cap  # m/s: the fastest a cloth vertex may move
        empty = np.zeros(0, np.int64)
        vertices, triangles, pinned, markers = [empty], [np.zeros((0, 3), np.int64)], [empty], [empty]
        colours = [np.zeros((0, 3), np.uint8)]
        n = 0
        for f, marker in scene.cloths:
            start, count = int(model.flex_vertadr[f]), int(model.flex_vertnum[f])
            elements = int(model.flex_elemdataadr[f]), int(model.flex_elemnum[f])
            F = model.flex_elem[elements[0]:elements[0] + 3 * elements[1]].reshape(-1, 3)
            vertices.append(start + np.arange(count))
            triangles.append(F + n)
            rgb = np.round(model.flex_rgba[f, :3] * 255).astype(np.uint8)
            colours.append(np.tile(rgb, (len(F), 1)))
            bodies = model.flex_vertbodyid[start:start + count]
            held = np.flatnonzero(bodies == scene.marker_bodies[marker]) if marker >= 0 else empty
            pinned.append(held + n)
            markers.append(np.full(len(held), marker))
            n += count
        self.vertices = np.concatenate(vertices).astype(np.int64)
        self.triangles = np.concatenate(triangles).astype(np.int64)
        self.colours = np.concatenate(colours)
        self.pinned = np.concatenate(pinned).astype(np.int64)
        self.markers = np.concatenate(markers).astype(np.int64)
        # Every cloth's free vertices at once: the marker each hangs from, its slide joints' qpos
        # and qvel addresses (n, 3) and their damping.
        # A cape's vertices hang from the world (marker -1): nothing to carry; its driven top row is
        # written by _Kinematic.
        holders, qposes, dofs = [empty], [np.zeros((0, 3), np.int64)], [np.zeros((0, 3), np.int64)]
        driven = set(scene.driven_bodies.tolist())
        for f, marker in scene.cloths:
            start, count = int(model.flex_vertadr[f]), int(model.flex_vertnum[f])
            holder = scene.marker_bodies[marker] if marker >= 0 else 0
            bodies = [b for b in model.flex_vertbodyid[start:start + count]
                      if b != holder and b not in driven]
            joints = np.array([model.body_jntadr[b] + np.arange(3) for b in bodies], np.int64).reshape(-1, 3)
            holders.append(np.full(len(joints), marker, np.int64))
            qposes.append(model.jnt_qposadr[joints])
            dofs.append(model.jnt_dofadr[joints])
        holder = np.concatenate(holders)
        self.by_marker = (holder >= 0).astype(np.float64)[:, None]  # 0 for a cape's: held by the world
        self.holder = np.maximum(holder, 0)
        self.q, self.v = np.concatenate(qposes), np.concatenate(dofs)
        self.damping = model.dof_damping[self.v]

    def carry(self, data, at, speed, qpos, qvel):
        """Before the markers are written (their positions' and velocities' addresses ``at`` and
        ``speed``, ``(N, 3)``, the new values ``qpos[:N, :3]`` and ``qvel[:N, :3]``): take the change
        off the free vertices' joints so they stay where they are in the world, and drag them by
        air at the marker's velocity."""
        if not len(self.q):
            return
        held = self.holder
        carried = qvel[held, :3] * self.by_marker
        data.qpos[self.q] -= (qpos[held, :3] - data.qpos[at[held]]) * self.by_marker
        data.qvel[self.v] -= carried - data.qvel[speed[held]] * self.by_marker
        data.qfrc_applied[self.v] = -self.damping * carried
        # No vertex moves faster than the cap (a limb that sweeps the cloth against its pinned
        # edge would otherwise squeeze it out at tens of metres a second).
        world = data.qvel[self.v] + carried
        fast = np.sqrt((world * world).sum(axis=1))
        over = fast > self.cap
        if over.any():
            data.qvel[self.v[over]] = world[over] * (self.cap / fast[over])[:, None] - carried[over]


class _Rain:
    """Sends drops that reached the ground (or left their box) back up above it, each frame."""

    def __init__(self, scene, model):
        self.geoms = np.array([g for g, _ in scene.rain], dtype=np.int64)
        self.boxes = np.array([box for _, box in scene.rain]).reshape(-1, 5)
        joints = [model.body_jntadr[model.geom_bodyid[g]] for g in self.geoms]
        self.qpos = np.array([model.jnt_qposadr[j] for j in joints], dtype=np.int64)
        self.qvel = np.array([model.jnt_dofadr[j] for j in joints], dtype=np.int64)
        self.radius = model.geom_size[self.geoms, 0] if len(self.geoms) else np.zeros(0)
        self.rng = np.random.default_rng(len(self.geoms))

    def respawn(self, data):
        if not len(self.geoms):
            return
        at = data.geom_xpos[self.geoms]
        box = self.boxes
        out = ((at[:, 1] < 1.5 * self.radius) | (at[:, 0] < box[:, 0]) | (at[:, 0] > box[:, 1])
               | (at[:, 2] < box[:, 2]) | (at[:, 2] > box[:, 3]))
        for k in np.flatnonzero(out):
            q, v = self.qpos[k], self.qvel[k]
            data.qpos[q:q + 3] = drops_in(self.rng, box[k], 1, full_height=False)[0]
            data.qpos[q + 3:q + 7] = (1.0, 0.0, 0.0, 0.0)
            data.qvel[v:v + 6] = 0.0


class _Kinematic:
    """Writes the proxy's pose at (frame + fraction) into the model and data, all bodies at once.

    :meth:`poses` works out a frame's sub-steps together; :meth:`write` puts one in place.
    """

    def __init__(self, scene, proxy, model):
        self.model = model
        self.P = proxy.points
        self.fps = proxy.fps
        self.limbs = proxy.limbs
        self.radii = scene.limb_radii
        sphere = np.zeros((proxy.frame_count, len(proxy.names)))
        for end in (0, 1):  # a marker's sphere is as large as the largest cylinder end at it
            np.maximum.at(sphere.T, self.limbs[:, end], self.radii[:, :, end].T)
        self.sphere = np.maximum(sphere, 1e-4)
        joints = [model.body_jntadr[b] for b in scene.marker_bodies + scene.limb_bodies]
        self.qpos = np.array([model.jnt_qposadr[j] for j in joints], dtype=np.int64)[:, None] + np.arange(7)
        self.qvel = np.array([model.jnt_dofadr[j] for j in joints], dtype=np.int64)[:, None] + np.arange(6)
        marker_geoms = np.array([model.body_geomadr[b] for b in scene.marker_bodies], dtype=np.int64)
        self.geoms = np.concatenate([marker_geoms, scene.limb_geoms.ravel()])  # markers', then limbs'
        self.u = (np.arange(SEGMENTS) + 0.5) / SEGMENTS
        self.identity = np.tile([1.0, 0.0, 0.0, 0.0], (len(proxy.names), 1))
        # Each limb's angular velocity from each frame to the next, (T, K, 3).
        D = self.P[:, self.limbs[:, 1]] - self.P[:, self.limbs[:, 0]]
        spin = np.zeros(D.shape)
        spin[:-1] = _turn(D[:-1], D[1:]) * self.fps
        self.limb_spin = spin
        is_ball = np.zeros(model.ngeom, bool)
        is_ball[scene.balls] = True
        is_proxy = np.zeros(model.ngeom, bool)
        is_proxy[self.geoms] = True
        self.is_ball, self.is_proxy = is_ball, is_proxy
        self.has_balls = bool(len(scene.balls))
        self.cloth = None
        # The capes' driven top rows: their slide joints' addresses (D, 3) and their paths as joint
        # positions (offsets from where each body was built).
        bodies = scene.driven_bodies
        joints = np.array([model.body_jntadr[b] + np.arange(3) for b in bodies], np.int64).reshape(-1, 3)
        self.driven_q, self.driven_v = model.jnt_qposadr[joints], model.jnt_dofadr[joints]
        self.driven = scene.driven_paths - model.body_pos[bodies] if len(bodies) else None

    def poses(self, t, fractions, moving):
        """The kinematic state at (t + each fraction): qpos, qvel and geom sizes, positions, bounds."""
        nxt = min(t + 1, len(self.P) - 1)
        f = np.asarray(fractions, dtype=np.float64)
        F = len(f)
        P = self.P[t] + f[:, None, None] * (self.P[nxt] - self.P[t])  # (F, N, 3)
        radii = self.radii[t] + f[:, None, None] * (self.radii[nxt] - self.radii[t])  # (F, K, 2)
        sphere = self.sphere[t] + f[:, None] * (self.sphere[nxt] - self.sphere[t])  # (F, N)
        L = self.limbs
        N, K = P.shape[1], len(L)
        axis = P[:, L[:, 1]] - P[:, L[:, 0]]
        length = np.linalg.norm(axis, axis=-1)  # (F, K)
        direction = np.where(length[..., None] > 1e-12, axis / np.maximum(length, 1e-300)[..., None],
                             [0.0, 0, 1])
        quats = _quat_z_to(direction.reshape(-1, 3)).reshape(F, K, 4)
        qpos = np.concatenate([np.concatenate([P, np.broadcast_to(self.identity, (F, N, 4))], axis=2),
                               np.concatenate([P[:, L[:, 0]], quats], axis=2)], axis=1)
        V = (self.P[nxt] - self.P[t]) * self.fps if moving else np.zeros((N, 3))
        spin = self.limb_spin[t] if moving else np.zeros((K, 3))
        qvel = np.concatenate([np.concatenate([V, np.zeros((N, 3))], axis=1),
                               np.concatenate([V[L[:, 0]], spin], axis=1)])
        r = np.maximum(radii[..., :1] + self.u * (radii[..., 1:] - radii[..., :1]), 1e-4)  # (F, K, SEGMENTS)
        half = np.broadcast_to(np.maximum(length / (2 * SEGMENTS), 1e-6)[..., None], r.shape)
        size = np.zeros((F, N + K * SEGMENTS, 3))
        size[:, :N, 0] = sphere
        size[:, N:, 0] = r.reshape(F, -1)
        size[:, N:, 1] = half.reshape(F, -1)
        pos = np.zeros((F, N + K * SEGMENTS, 3))
        pos[:, N:, 2] = (self.u * length[..., None]).reshape(F, -1)
        rbound = size[..., 0] + size[..., 1]
        aabb = np.zeros((F, N + K * SEGMENTS, 6))
        aabb[..., 3] = aabb[..., 4] = size[..., 0]
        aabb[..., 5] = rbound
        driven = None
        if self.driven is not None:
            at = self.driven[t] + f[:, None, None] * (self.driven[nxt] - self.driven[t])  # (F, D, 3)
            driven = at, (self.driven[nxt] - self.driven[t]) * self.fps if moving else np.zeros(at.shape[1:])
        return qpos, qvel, size, pos, rbound, aabb, driven

    def write(self, data, poses, s):
        """Sub-step ``s`` of :meth:`poses` into the data and model."""
        qpos, qvel, size, pos, rbound, aabb, driven = poses
        if driven is not None:
            data.qpos[self.driven_q] = driven[0][s]
            data.qvel[self.driven_v] = driven[1]
        if self.cloth is not None:
            N = len(self.sphere[0])
            self.cloth.carry(data, self.qpos[:N, :3], self.qvel[:N, :3], qpos[s], qvel)
        data.qpos[self.qpos] = qpos[s]
        data.qvel[self.qvel] = qvel
        m, g = self.model, self.geoms
        # Sizes change frame to frame: the broad phase's bounds (sphere and local box) with them.
        m.geom_size[g] = size[s]
        m.geom_pos[g] = pos[s]
        m.geom_rbound[g] = rbound[s]
        m.geom_aabb[g] = aabb[s]

    def place(self, data, t, fraction, moving):
        self.write(data, self.poses(t, [fraction], moving), 0)

    def deepest_ball(self, data):
        """How far any ball is inside any proxy volume at the step's start, metres (0 when none is)."""
        n = data.ncon
        if n == 0 or not self.has_balls:
            return 0.0
        pairs = data.contact.geom[:n]
        touching = (self.is_ball[pairs[:, 0]] & self.is_proxy[pairs[:, 1]]) | (
            self.is_ball[pairs[:, 1]] & self.is_proxy[pairs[:, 0]])
        if not touching.any():
            return 0.0
        return max(0.0, float(-data.contact.dist[:n][touching].min()))


def _capsule(data, model, g):
    centre = data.geom_xpos[g]
    axis = data.geom_xmat[g].reshape(3, 3)[:, 2]
    half = model.geom_size[g, 1]
    return np.concatenate([centre - half * axis, centre + half * axis, [model.geom_size[g, 0]]])


def _quat_z_to(d):
    """The shortest rotations taking +Z to unit vectors ``d`` ``(n, 3)``, MuJoCo's (w, x, y, z)."""
    w = 1.0 + d[:, 2]
    q = np.stack([w, -d[:, 1], d[:, 0], np.zeros(len(d))], axis=1)  # (1 + z.d, z x d)
    opposite = w < 1e-9
    q[opposite] = (0.0, 1.0, 0.0, 0.0)  # half a turn about X
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _turn(a, b):
    """Rotation vectors turning directions ``a`` to ``b`` (``(..., 3)``), about their common normal."""
    na, nb = np.linalg.norm(a, axis=-1, keepdims=True), np.linalg.norm(b, axis=-1, keepdims=True)
    ok = (na > 1e-12) & (nb > 1e-12)
    a, b = a / np.where(ok, na, 1.0), b / np.where(ok, nb, 1.0)
    axis = np.cross(a, b)
    s = np.linalg.norm(axis, axis=-1, keepdims=True)
    angle = np.arctan2(s, (a * b).sum(-1, keepdims=True))
    return np.where(ok & (s > 1e-12), axis / np.maximum(s, 1e-300) * angle, 0.0)
