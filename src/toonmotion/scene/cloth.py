"""Cloth in a scene (issue 45): scarves, skirts and capes as MuJoCo flexes.

A cloth is a ``flexcomp type="direct" dim="2"`` of triangles whose edges keep their lengths (soft
equality constraints). A scarf or a skirt is declared inside its marker's body, so that its pinned
vertices (a scarf's knotted edge, a skirt's waistband) are points of that body and move exactly
with the marker; every other vertex is a body of its own with three slide joints.
:func:`scarf_xml` and :func:`skirt_xml` build them clear of the proxy's volumes over the whole
clip (docs/scene3d.md, cloth). A cape hangs from two markers, so no one body can hold it: it is
declared in the world, and its top row of vertices is **driven** like the proxy (heavy, its
positions written every sub-step along a path that follows both shoulders, :func:`cape_xml`).
"""

from __future__ import annotations

import numpy as np

from toonmotion.errors import SceneError
from toonmotion.scene.clearance import (
    across_way,
    directions,
    first_frame_volumes,
    gap_ok,
    marker_reach,
    relative_volumes,
    stack_volumes,
)
from toonmotion.scene.elements import (
    CAPE_LENGTH,
    SCARF_LENGTH,
    SCARF_WIDTH,
    SKIRT_LENGTH,
    SKIRT_RADIUS,
    Skirt,
)
from toonmotion.scene.mjcf import CONTACT_TIME, ELEMENT_BITS, KINEMATIC_MASS, rgba_text

# The chains that scarves and skirts were before they became cloth (issue 45): kept for the record
# of the limits' docs, no longer built.
SCARF_LINKS = 10


SKIRT_LINKS = 4


CLOTH_DENSITY = 0.25  # kg per square metre of scarf or skirt: light cloth


# A scarf's cloth: SCARF_ROWS rows of SCARF_COLUMNS vertices, the first row knotted (pinned).
SCARF_ROWS = 13


SCARF_COLUMNS = 3


SCARF_BODIES = (SCARF_ROWS - 1) * SCARF_COLUMNS


# A skirt's cloth: SKIRT_ROWS rings of ``strands`` vertices (at least MIN_SKIRT_COLUMNS), the
# waistband ring pinned; the hem flares out by SKIRT_FLARE times the skirt's length.
SKIRT_ROWS = 8


MIN_SKIRT_COLUMNS = 6


SKIRT_FLARE = 0.35


# A cape's cloth: CAPE_ROWS rows of CAPE_COLUMNS vertices, the top row driven behind the shoulders.
CAPE_ROWS = 10


CAPE_COLUMNS = 5


CAPE_BODIES = CAPE_ROWS * CAPE_COLUMNS


CLOTH_RADIUS = 0.004  # the cloth's half thickness for contacts, as a fraction of the figure's height


# Each cloth vertex weighs at least this (kg): lighter ones make the contacts and the edge
# constraints stiffer than a 2 ms sub-step resolves (measured: 0.3 g vertices jitter on a fast hand).
MIN_CLOTH_VERTEX_MASS = 0.001


# Viscous damping of each free vertex, per kg of its mass (1/s): air's drag on a sheet. Quadratic
# drag on cloth of CLOTH_DENSITY at 2 m/s, 0.5 * 1.2 * v^2 per square metre, decelerates it at
# ~10 m/s^2, a linear rate of 5/s; lower rates (1.5/s measured) let a skirt on the jumping demo
# fly up over the shoulders. Terminal speed g / 5 = 2 m/s: light cloth.
CLOTH_DAMPING = 5.0


# The cloth's contacts' time constant (s), softer than CONTACT_TIME: measured on a six-armed figure whose
# forearms spin round the scarves' knots, 0.004 and 0.01 let them squeeze a scarf out to metres (even
# with the speed cap of simulate.py); 0.02 keeps every scarf within its length of its knot.
CLOTH_CONTACT_TIME = 0.02


CLOTH_EDGE_DAMPING = 0.002  # the edges' damping (N s/m): kills the stretch modes' ringing


def skirt_columns(skirt: Skirt) -> int:
    """The vertices round a skirt's ring: its ``strands``, at least :data:`MIN_SKIRT_COLUMNS`."""
    return max(int(skirt.strands), MIN_SKIRT_COLUMNS)


def scarf_xml(name, scarf, proxy, marker, radii, height):
    """A scarf: a strip of :data:`SCARF_ROWS` x :data:`SCARF_COLUMNS` vertices hanging from a knot
    beside the marker (in the marker body's frame), its first row pinned.

    The knot sits outside the marker's largest joint sphere over the clip (up to 2.5 times its
    radius out), along the first way (:func:`directions`) on which the knot stays clear of every
    limb's volume on every frame (seen from the marker) and the strip is clear of the first
    frame's volumes and the ground; the strip's width faces the camera.
    """
    width = scarf.width or SCARF_WIDTH * height
    length = scarf.length or SCARF_LENGTH * height
    thick = CLOTH_RADIUS * height
    P = proxy.points
    reach = marker_reach(proxy, marker, radii) + thick + 0.1 * width
    relative = relative_volumes(proxy, marker, radii)
    first = first_frame_volumes(proxy, radii)
    axis = np.asarray(proxy.camera.rotations[0])[2]
    ways = directions(P[0], marker)
    candidates = []  # (way, across, knot, clear on every frame), the first way and nearest knot first
    for way in ways:
        across = across_way(way, axis)
        if P[0, marker, 1] + way[1] * (reach + length) <= width:  # into the ground
            continue
        for d in reach * np.linspace(1.0, 2.5, 7):
            edge = way * d + np.outer(np.linspace(-0.5, 0.5, SCARF_COLUMNS), across * width)
            strip = np.linspace(0.0, 1, 9)[:, None, None] * (way * length) + edge
            if gap_ok(P[0, marker] + strip, thick, [stack_volumes(first)]):
                candidates.append((way, across, way * d, gap_ok(edge, thick, relative)))
    # Clear on every frame if it can be; else clear on the first (a limb may sweep through the knot
    # later: the contacts push the cloth aside); else down (or the first way off the ground), far out.
    best = next((c for c in candidates if c[3]), candidates[0] if candidates else None)
    if best is None:
        way = next((w for w in ways if P[0, marker, 1] + w[1] * (reach + length) > width), ways[0])
        best = (way, across_way(way, axis), way * 2.5 * reach, False)
    way, across, knot, _ = best
    rows = np.linspace(0.0, 1.0, SCARF_ROWS)[:, None, None] * (way * length)
    cols = np.linspace(-0.5, 0.5, SCARF_COLUMNS)[None, :, None] * (across * width)
    V = (knot + rows + cols).reshape(-1, 3)
    F = grid_triangles(SCARF_ROWS, SCARF_COLUMNS, ring=False)
    return flex_xml(name, V, F, range(SCARF_COLUMNS), CLOTH_DENSITY * width * length, scarf.colour, thick)


def skirt_xml(name, skirt, proxy, marker, radii, height):
    """A skirt: :data:`SKIRT_ROWS` rings of vertices round the marker, flaring towards the hem, the
    waistband ring pinned. The waistband widens from the skirt's radius (up to three times it)
    until it is clear of every limb's volume on every frame seen from the marker, and the cloth of
    the first frame's volumes."""
    length = skirt.length or SKIRT_LENGTH * height
    radius = skirt.radius or SKIRT_RADIUS * height
    thick = CLOTH_RADIUS * height
    n = skirt_columns(skirt)
    turns = 2 * np.pi * np.arange(n) / n
    unit = np.stack([np.cos(turns), np.zeros(n), np.sin(turns)], axis=1)
    P = proxy.points
    relative = relative_volumes(proxy, marker, radii)
    first = [stack_volumes(first_frame_volumes(proxy, radii))]
    f = np.linspace(0.0, 1.0, SKIRT_ROWS)

    def rings(r):
        return (r + SKIRT_FLARE * length * f)[:, None, None] * unit + (-length * f)[:, None, None] * [0, 1, 0]

    chosen = None
    for r in np.linspace(radius, 3 * radius, 21):
        V = rings(r)
        if gap_ok(V[0], thick, relative) and gap_ok(P[0, marker] + V[1:].reshape(-1, 3), thick, first):
            chosen = r
            break
    if chosen is None:  # started inside the body, the cloth would be flung out or crushed
        raise SceneError(f"a skirt round {proxy.names[marker]!r} cannot hang clear of the body: its "
                         f"waistband, up to {3 * radius:.2f} m across the marker, meets a limb's volume "
                         "(a figure whose body lies level, or limbs wider than the skirt); give it another "
                         "marker")
    V = rings(chosen).reshape(-1, 3)
    drop = P[0, marker, 1] - length - thick * 2
    if drop < 0:  # the hem would start in the ground: shorten the fall, keep the flare
        V[:, 1] *= max(P[0, marker, 1] - 2 * thick, 1e-3) / (length + thick * 2)
    F = grid_triangles(SKIRT_ROWS, n, ring=True)
    area = 2 * np.pi * (chosen + 0.5 * SKIRT_FLARE * length) * length
    return flex_xml(name, V, F, range(n), CLOTH_DENSITY * area, skirt.colour, thick)


def cape_xml(name, cape, proxy, left, right, radii, height):
    """A cape: :data:`CAPE_ROWS` x :data:`CAPE_COLUMNS` vertices hanging straight down from a top
    row that runs from the ``left`` marker to the ``right`` one, set back behind them; and that top
    row's path over the clip, ``(T, CAPE_COLUMNS, 3)``.

    The top row keeps one width, the shoulders' median distance over the clip, centred between them
    on every frame: a lifted clip's shoulders may come closer or part (measured on the demo's proxy:
    0.46 m on its first frame, 0.23 m on the next), and a top row squeezed to half its width buckled
    the cape and flung it over the head.

    Behind is the horizontal way of ``(right - left) x up`` on each frame (the previous frame's
    while the shoulders are one above the other), so the top row turns as the shoulders turn. It is
    set back by the shoulders' largest joint sphere and the cloth's thickness, further (up to 2.5
    times) until the sheet is clear of the first frame's volumes.

    Raises
    ------
    SceneError
        The shoulders are one above the other on the first frame, or no set-back clears the body.
    """
    length = cape.length or CAPE_LENGTH * height
    thick = CLOTH_RADIUS * height
    P = proxy.points
    across = P[:, right] - P[:, left]
    back = np.stack([-across[:, 2], np.zeros(len(P)), across[:, 0]], axis=1)  # (right - left) x up
    size = np.linalg.norm(back, axis=1)
    if size[0] < 1e-3 * height:
        raise SceneError(f"a cape hangs from two markers side by side, but {cape.left!r} and {cape.right!r} "
                         "are one above the other on the first frame; give the shoulders")
    for t in range(len(P)):  # a frame whose shoulders are one above the other keeps the last way
        back[t] = back[t] / size[t] if size[t] >= 1e-3 * height else back[t - 1]
    reach = max(marker_reach(proxy, left, radii), marker_reach(proxy, right, radii)) + 2 * thick
    width = float(np.median(np.linalg.norm(across, axis=1)))
    way = across / np.maximum(np.linalg.norm(across, axis=1), 1e-300)[:, None]
    s = np.linspace(-0.5, 0.5, CAPE_COLUMNS) * width
    top = (P[:, left] + P[:, right])[:, None] / 2 + s[None, :, None] * way[:, None]  # (T, CAPE_COLUMNS, 3)
    fall = np.linspace(0.0, 1.0, CAPE_ROWS)[:, None, None] * [0.0, -length, 0.0]
    first = [stack_volumes(first_frame_volumes(proxy, radii))]
    for d in reach * np.linspace(1.0, 2.5, 7):
        V = top[0] + back[0] * d + fall
        if gap_ok(V, thick, first):
            break
    else:
        raise SceneError(f"a cape from {cape.left!r} to {cape.right!r} cannot hang clear of the body behind "
                         f"them (set back up to {2.5 * reach:.2f} m): a figure whose body runs level behind "
                         "its shoulders, or the shoulders swapped (the cape hangs behind (right - left) x "
                         "up: give the figure's own left first)")
    if V[-1, 0, 1] < thick:  # the hem would start in the ground: shorten the fall
        V[1:, :, 1] = V[0, :, 1] + (V[1:, :, 1] - V[0, :, 1]) * max(V[0, 0, 1] - 2 * thick, 1e-3) / length
    F = grid_triangles(CAPE_ROWS, CAPE_COLUMNS, ring=False)
    xml = flex_xml(name, V.reshape(-1, 3), F, (), CLOTH_DENSITY * width * length, cape.colour, thick)
    return xml, top + back[:, None] * d


def top_row(model, flex):
    """A cape's driven vertices' bodies: the first :data:`CAPE_COLUMNS` of its flex."""
    start = model.flex_vertadr[flex]
    return model.flex_vertbodyid[start:start + CAPE_COLUMNS]


def drive(mujoco, model, bodies):
    """Make ``bodies`` (cape vertices moved by hand) as heavy as the proxy and undamped, so the cloth
    they hold does not drag them off their path within a sub-step."""
    model.body_mass[bodies] = KINEMATIC_MASS
    for b in bodies:
        model.dof_damping[model.body_dofadr[b] + np.arange(model.body_dofnum[b])] = 0.0
    mujoco.mj_setConst(model, mujoco.MjData(model))


def flex_xml(name, V, F, pinned, mass, colour, thick):
    """A ``flexcomp`` of vertices ``V`` (in its body's frame) and triangles ``F``, ``pinned`` vertices
    fixed to the body, edges of constant length, colliding with the proxy, the ground and the other
    elements but not itself."""
    mass = max(float(mass), MIN_CLOTH_VERTEX_MASS * len(V))
    points = " ".join(repr(float(c)) for c in np.asarray(V).ravel())
    elements = " ".join(str(int(k)) for k in np.asarray(F).ravel())
    pins = f'<pin id="{" ".join(str(k) for k in pinned)}"/>' if len(pinned) else ""  # a cape has none
    return (f'<flexcomp name="{name}" type="direct" dim="2" point="{points}" element="{elements}" '
            f'mass="{mass!r}" radius="{thick!r}" rgba="{rgba_text(colour)}">'
            f'<contact {ELEMENT_BITS} selfcollide="none" solref="{CLOTH_CONTACT_TIME} 1" '
            f'friction="0.6 0.005 0.001"/>'
            f'<edge equality="true" solref="{CONTACT_TIME} 1" damping="{CLOTH_EDGE_DAMPING}"/>'
            f'{pins}</flexcomp>')


def grid_triangles(rows, columns, ring):
    """Two triangles per cell of a ``rows`` x ``columns`` grid of vertices (row major); ``ring``
    joins the last column to the first (a cylinder)."""
    cells = columns if ring else columns - 1
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(cells), indexing="ij")
    a = i * columns + j
    b = i * columns + (j + 1) % columns
    c, d = a + columns, b + columns
    return np.stack([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], axis=2).reshape(-1, 3)


def damp_cloth(model, flexes, holders):
    """Damp each cloth vertex's slide joints by :data:`CLOTH_DAMPING` times its mass (air's drag),
    and take the vertex out of MuJoCo's fluid model.

    The fluid model takes a body without geoms for the box of its inertia: a cloth vertex became a
    1 cm cube of water whose drag, with the implicit integrator, blew the simulation up (measured:
    a scarf on a circling hand, QACC at a cloth vertex's DOF after 0.23 s). Its inertia is unused
    otherwise (a vertex only slides), so it is shrunk a million times, which shrinks the box to
    nothing, and the damping stands in for air.
    """
    for f, holder in zip(flexes, holders, strict=True):
        start, count = model.flex_vertadr[f], model.flex_vertnum[f]
        for b in model.flex_vertbodyid[start:start + count]:
            if b == holder:  # a pinned vertex: a point of its holder's body
                continue
            dofs = model.body_dofadr[b] + np.arange(model.body_dofnum[b])
            model.dof_damping[dofs] = CLOTH_DAMPING * model.body_mass[b]
            model.body_inertia[b] *= 1e-6
