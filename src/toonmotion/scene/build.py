"""A MuJoCo model of a proxy and its scene elements (section 3.5).

The proxy is **kinematic**: each marker is a body holding its joint sphere and each limb a body
holding its tapered cylinder, drawn as :data:`SEGMENTS` capsules whose radii step from one end's
radius to the other's (MuJoCo has no cone; the steps differ from the taper by at most a sixth of
the radii's difference). Their poses, velocities and sizes are written every sub-step from the
lifted motion (:mod:`toonmotion.scene.simulate`) and they are heavy, so that what they touch
takes their velocity and they do not give way. Proxy geoms collide with the elements but not with
each other or the ground.

Elements (:mod:`toonmotion.scene.elements`) are ordinary bodies: a balloon's string is a chain of
:data:`STRING_LINKS` capsules on ball joints hanging from its marker's body (a child of it, so the
string's end is exactly the marker's point), the balloon a sphere pulled up by gravity
compensation; balls are free spheres on the ground plane Y = 0. Air (MuJoCo's fluid model,
density 1.2 kg/m^3) drags on everything that moves when the scene holds a balloon, balls or rain;
a scene of cloth alone has no fluid model (:func:`_air`).

Scarves and skirts are cloth: a MuJoCo flex (``flexcomp type="direct" dim="2"``) of triangles
whose edges keep their lengths (soft equality constraints), declared inside the marker's body so
that its pinned vertices (a scarf's knotted edge, a skirt's waistband) are points of that body
and move exactly with the marker; every other vertex is a body of its own with three slide
joints. :func:`_scarf_xml` and :func:`_skirt_xml` build them clear of the proxy's volumes over
the whole clip (docs/scene3d.md, cloth). A cape hangs from two markers, so no one body can hold
it: it is declared in the world, and its top row of vertices is **driven** like the proxy (heavy,
its positions written every sub-step along a path that follows both shoulders, :func:`_cape_xml`).

World: +Y up, metres, gravity -9.81 m/s^2 along Y (the proxy's frame).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from toonmotion import limits
from toonmotion.errors import SceneError
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.scene.elements import (
    BALL_RADIUS,
    BALLOON_RADIUS,
    CAPE_LENGTH,
    MAX_SIZE,
    RAIN_RADIUS,
    SCARF_LENGTH,
    SCARF_WIDTH,
    SKIRT_LENGTH,
    SKIRT_RADIUS,
    STRING_LENGTH,
    Balloon,
    Balls,
    Cape,
    Element,
    Rain,
    Scarf,
    Skirt,
)

SEGMENTS = 3  # capsules per tapered cylinder
STRING_LINKS = 8
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
MIN_LINK_MASS = 0.002  # kg: lighter links make the contacts stiff beyond what a sub-step resolves
CHAIN_ARMATURE = 1e-4  # kg m^2 of rotor inertia on a chain's joints: keeps light links stable in contact
# Proxy radii when the proxy has no collision volumes (lifted without drawn frames), as a fraction
# of the figure's height.
DEFAULT_LIMB_RADIUS = 0.035
KINEMATIC_MASS = 1000.0  # kg: the proxy does not give way
BALL_DENSITY = 300.0  # kg/m^3, a light rubber ball
BALLOON_MASS = 0.01  # kg
AIR_DENSITY = 1.2  # kg/m^3
AIR_VISCOSITY = 0.000018  # Pa s
STRING_RADIUS = 0.003  # m, physical; drawn at least api.scene3d.STRING_MIN_PX across
# Collision bits: proxies (2) touch elements (3) only; elements touch the ground (1) and each other.
PROXY_BITS = 'contype="2" conaffinity="0"'
ELEMENT_BITS = 'contype="1" conaffinity="3"'
# Rain (4) touches the proxy, the ground and the elements but not other drops.
DROP_BITS = 'contype="4" conaffinity="3"'
WATER_DENSITY = 1000.0
CONTACT_TIME = 0.004  # seconds: the contacts' time constant (MuJoCo's solref), twice the longest step
CONTACT = f'solref="{CONTACT_TIME} 1" condim="6" friction="0.9 0.005 0.002"'


@dataclass(frozen=True, eq=False)
class SceneModel:
    """A compiled scene: the MuJoCo model and where each part of the proxy and the scene is in it.

    Attributes
    ----------
    model : mujoco.MjModel
    height : float
        The figure's height (metres) that default sizes follow.
    limb_radii : (T, K, 2) float
        The cylinders' radii used (the proxy's, or a default when it has none).
    marker_bodies, limb_bodies : list of int
        The kinematic bodies, one per marker and one per limb (``proxy.limbs`` order).
    limb_geoms : (K, SEGMENTS) int
        Each limb's capsules, parent end first.
    element_geoms : list of int
        The geoms to draw, in drawing order.
    colours : (E, 3) uint8
        Their colours.
    held : list of (int, int)
        ``(geom, marker)``: a string's first capsule and the marker holding it.
    balls : list of int
        The balls' geoms.
    rain : list of (int, (5,) float)
        Each drop's geom and the box it falls in, ``(x0, x1, z0, z1, top)`` metres
        (:func:`rain_box`).
    default_volumes : bool
        Whether the proxy had no volumes and ``limb_radii`` are defaults.
    cloths : list of (int, int)
        ``(flex, marker)``: each cloth's flex and the marker its pinned vertices move with (-1 for a
        cape, which is held by the world and driven).
    driven_bodies : (D,) int
        The capes' top-row vertices, moved by hand every sub-step like the proxy.
    driven_paths : (T, D, 3) float
        Where they are on each frame, metres.
    """

    model: Any
    height: float
    limb_radii: NDArray[np.float64]
    marker_bodies: list[int]
    limb_bodies: list[int]
    limb_geoms: NDArray[np.int64]
    element_geoms: list[int]
    colours: NDArray[np.uint8]
    held: list[tuple[int, int]] = field(default_factory=list)
    balls: list[int] = field(default_factory=list)
    default_volumes: bool = False
    rain: list[tuple[int, NDArray[np.float64]]] = field(default_factory=list)
    cloths: list[tuple[int, int]] = field(default_factory=list)
    driven_bodies: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, np.int64))
    driven_paths: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 0, 3)))


def figure_height(proxy: Proxy) -> float:
    """The figure's height, metres: the largest vertical extent of its points over the clip."""
    Y = proxy.points[..., 1]
    return float(max((Y.max(axis=1) - Y.min(axis=1)).max(), 1e-3))


def scene_bodies(elements: list[Element] | tuple[Element, ...]) -> int:
    """How many bodies the elements make MuJoCo simulate: a drop or a ball is one, a balloon its
    :data:`STRING_LINKS` links and itself, a scarf or a skirt its cloth's free vertices
    (:data:`SCARF_BODIES`; a skirt's ``strands`` columns of ``SKIRT_ROWS - 1``), a cape all its
    vertices (:data:`CAPE_BODIES`, the driven top row too). Counted from the
    elements alone, before anything is built.

    >>> scene_bodies([Rain(count=100), Balloon("hand"), Skirt("hips", strands=16)])
    221
    """
    return sum(_bodies(element) for element in elements)


def skirt_columns(skirt: Skirt) -> int:
    """The vertices round a skirt's ring: its ``strands``, at least :data:`MIN_SKIRT_COLUMNS`."""
    return max(int(skirt.strands), MIN_SKIRT_COLUMNS)


def _bodies(element):
    if isinstance(element, (Rain, Balls)):
        return element.count
    if isinstance(element, Balloon):
        return STRING_LINKS + 1
    if isinstance(element, Scarf):
        return SCARF_BODIES
    if isinstance(element, Skirt):
        return skirt_columns(element) * (SKIRT_ROWS - 1)
    if isinstance(element, Cape):
        return CAPE_BODIES
    raise SceneError(f"a scene element is a Balloon, Balls, Scarf, Skirt, Cape or Rain, got "
                     f"{type(element).__name__}")


# How a refusal names an element whose marker the proxy lacks.
_HELD = {Balloon: "a balloon is held at", Balls: "balls are laid in the path of", Scarf: "a scarf is tied at",
         Skirt: "a skirt hangs round", Cape: "a cape hangs from"}


def check_scene(proxy: Proxy, elements: list[Element] | tuple[Element, ...]) -> None:
    """Refuse a scene before anything is built: an element at a marker the proxy lacks, more bodies
    than the limit ``scene_bodies`` (:mod:`toonmotion.limits`), or a size given larger than
    :data:`~toonmotion.scene.elements.MAX_SIZE` times the figure's height (:func:`figure_height`).

    Cheap (it counts and compares; it builds nothing), so a front end calls it before reading the
    drawn frames; :func:`build_scene` calls it first too.

    Raises
    ------
    SceneError
        An unknown marker, an element too large for the figure.
    LimitError
        Too many bodies.
    """
    names = list(proxy.names)
    for element in elements:
        held_at = (element.left, element.right) if isinstance(element, Cape) else (element.marker,)
        for marker in held_at:
            if marker is not None and marker not in names:
                held = _HELD.get(type(element), "an element is held at")
                raise SceneError(f"{held} {marker!r}, which the proxy lacks; its markers are "
                                 f"{', '.join(names)}")
    bodies = scene_bodies(elements)
    if bodies > limits.current().scene_bodies:
        limits.check("scene_bodies", bodies, f"the number of bodies to simulate ({_listed(elements)})",
                     hint="simulate fewer of them")
    height = figure_height(proxy)
    bound = MAX_SIZE * height
    for element in elements:
        for what, value, larger in _given_sizes(element):
            if value is not None and float(value) > bound:
                raise SceneError(
                    f"{what} ({float(value):g} m) is {larger} than {bound:.3g} m, {MAX_SIZE:g} times the "
                    f"figure's height of {height:.3g} m; give sizes in metres, as the proxy's points are, or "
                    "leave it out to follow the figure")


def _listed(elements):
    """The elements' bodies in words: ``"1,000 drops, 3 balls and 2 balloons of 9 bodies"``."""
    def count(kind):
        return sum(1 for e in elements if isinstance(e, kind))

    def plural(n, one, many):
        return f"{n:,} {one if n == 1 else many}"

    parts = []
    drops = sum(e.count for e in elements if isinstance(e, Rain))
    balls = sum(e.count for e in elements if isinstance(e, Balls))
    skirt_points = sum(_bodies(e) for e in elements if isinstance(e, Skirt))
    if drops:
        parts.append(plural(drops, "drop", "drops"))
    if balls:
        parts.append(plural(balls, "ball", "balls"))
    if count(Balloon):
        parts.append(plural(count(Balloon), "balloon", "balloons") + f" of {STRING_LINKS + 1} bodies")
    if count(Scarf):
        parts.append(plural(count(Scarf), "scarf", "scarves") + f" of {SCARF_BODIES} cloth points")
    if count(Skirt):
        cloth = plural(skirt_points, "cloth point", "cloth points")
        parts.append(plural(count(Skirt), "skirt", "skirts") + f" ({cloth})")
    if count(Cape):
        parts.append(plural(count(Cape), "cape", "capes") + f" of {CAPE_BODIES} cloth points")
    return " and ".join([", ".join(parts[:-1]), parts[-1]] if len(parts) > 1 else parts)


def _given_sizes(element):
    """``(what, metres or None, comparative)`` for each size of ``element`` a user may give."""
    if isinstance(element, Balloon):
        return [("a balloon's radius", element.radius, "larger"),
                ("a balloon's string", element.string_length, "longer")]
    if isinstance(element, Balls):
        return [("a ball's radius", element.radius, "larger")]
    if isinstance(element, Scarf):
        return [("a scarf's length", element.length, "longer"), ("a scarf's width", element.width, "wider")]
    if isinstance(element, Skirt):
        return [("a skirt's length", element.length, "longer"),
                ("a skirt's radius", element.radius, "larger"),
                ("a skirt's strand width", element.width, "wider")]
    if isinstance(element, Cape):
        return [("a cape's length", element.length, "longer")]
    return [("a drop's radius", element.radius, "larger")]


def build_scene(proxy: Proxy, elements: list[Element] | tuple[Element, ...]) -> SceneModel:
    """Compile the proxy and the elements into a MuJoCo model.

    The elements are checked first (:func:`check_scene`), before anything is built.

    Raises
    ------
    SceneError
        An element names a marker the proxy lacks or is larger than :data:`MAX_SIZE` times the
        figure's height, or MuJoCo is not installed.
    LimitError
        The elements make more bodies than the limit ``scene_bodies``.
    """
    check_scene(proxy, elements)
    mujoco = _mujoco()
    names = list(proxy.names)
    height = figure_height(proxy)
    radii = _limb_radii(proxy, height)
    default_volumes = proxy.radii is None
    P0 = proxy.points[0]
    volumes = _first_frame_volumes(proxy, radii)  # where elements must not start
    held_xml: dict[int, list[str]] = {}
    element_xml = []
    cloths: list[tuple[str, int]] = []  # each cloth's flex and the marker holding it
    capes: list[tuple[str, NDArray[np.float64]]] = []  # each cape's flex and its top row's path
    for i, element in enumerate(elements):
        if isinstance(element, Rain):
            continue
        if isinstance(element, Cape):
            xml, path = _cape_xml(f"e{i}_cape", element, proxy, names.index(element.left),
                                  names.index(element.right), radii, height)
            element_xml.append(xml)
            cloths.append((f"e{i}_cape", -1))
            capes.append((f"e{i}_cape", path))
            continue
        at = held_xml.setdefault(names.index(element.marker), [])
        if isinstance(element, Balloon):
            at.append(_balloon_xml(i, element, height))
        elif isinstance(element, Scarf):
            marker = names.index(element.marker)
            at.append(_scarf_xml(f"e{i}_scarf", element, proxy, marker, radii, height))
            cloths.append((f"e{i}_scarf", marker))
        elif isinstance(element, Skirt):
            marker = names.index(element.marker)
            at.append(_skirt_xml(f"e{i}_skirt", element, proxy, marker, radii, height))
            cloths.append((f"e{i}_skirt", marker))
    placed: list[tuple[NDArray[np.float64], float]] = []
    ball_names: list[str] = []
    for i, element in enumerate(elements):
        if isinstance(element, Balls):
            r = element.radius or BALL_RADIUS * height
            marker = names.index(element.marker)
            for j, centre in enumerate(_place_balls(proxy, volumes, marker, element.count, r, placed)):
                placed.append((centre, r))
                rgba = _rgba(element.colours[j % len(element.colours)])
                ball_names.append(f"e{i}_ball{j}")
                element_xml.append(
                    f'<body name="e{i}_ball{j}" pos="{_v(centre)}"><freejoint/><geom name="e{i}_ball{j}" '
                    f'type="sphere" size="{r!r}" density="{BALL_DENSITY}" rgba="{rgba}" {ELEMENT_BITS} '
                    f'{CONTACT}/></body>')
    drops: list[tuple[str, NDArray[np.float64]]] = []
    for i, element in enumerate(elements):
        if isinstance(element, Rain):
            r = element.radius or RAIN_RADIUS * height
            box = rain_box(proxy, height)
            rng = np.random.default_rng(element.seed)
            starts = [c for c in drops_in(rng, box, 4 * element.count, full_height=True)
                      if _clear([c], r, volumes)][:element.count]
            starts += list(drops_in(rng, box, element.count - len(starts), full_height=False))
            for j, centre in enumerate(starts):
                drops.append((f"e{i}_drop{j}", box))
                element_xml.append(
                    f'<body name="e{i}_drop{j}" pos="{_v(centre)}"><freejoint/><geom name="e{i}_drop{j}" '
                    f'type="sphere" size="{r!r}" density="{WATER_DENSITY}" rgba="{_rgba(element.colour)}" '
                    f'{DROP_BITS} solref="{CONTACT_TIME} 0.3" friction="0.2 0.005 0.0001"/></body>')
    bodies = []
    for n in range(len(names)):
        bodies.append(
            f'<body name="m{n}" pos="{_v(P0[n])}"><freejoint/><geom name="m{n}" type="sphere" size="0.01" '
            f'mass="{KINEMATIC_MASS}" {PROXY_BITS} {CONTACT}/>{"".join(held_xml.get(n, []))}</body>')
    for k in range(len(proxy.limbs)):
        capsules = "".join(
            f'<geom name="l{k}_{s}" type="capsule" size="0.01 0.01" pos="0 0 {s}" mass="{KINEMATIC_MASS}" '
            f'{PROXY_BITS} {CONTACT}/>' for s in range(SEGMENTS))
        bodies.append(f'<body name="l{k}"><freejoint/>{capsules}</body>')
    xml = (
        '<mujoco model="toonmotion scene"><compiler angle="radian"/>'
        f'<option gravity="0 -9.81 0" {_air(elements)} integrator="implicitfast">'
        '<flag midphase="disable"/></option>'  # the proxy's geoms change size: no compiled bounds
        '<worldbody><geom name="ground" type="plane" size="0 0 1" zaxis="0 1 0" contype="1" '
        f'conaffinity="1" {CONTACT}/>' + "".join(bodies) + "".join(element_xml) + "</worldbody></mujoco>"
    )
    try:
        model = mujoco.MjModel.from_xml_string(xml)
    except ValueError as error:  # pragma: no cover - the XML is ours
        raise SceneError(f"the scene does not compile: {error}") from None
    geom = lambda name: int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name))  # noqa: E731
    # The limbs' capsules are moved within their bodies every sub-step; MuJoCo skips the offset of
    # a geom it compiled at its body's origin ("same frame"), so none of them may be marked so.
    limb_geoms = [geom(f"l{k}_{s}") for k in range(len(proxy.limbs)) for s in range(SEGMENTS)]
    model.geom_sameframe[limb_geoms] = 0
    body = lambda name: int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name))  # noqa: E731
    drawn = [g for g in range(model.ngeom) if mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g)
             and mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, g).startswith("e")]
    colours = np.round(model.geom_rgba[drawn, :3] * 255).astype(np.uint8).reshape(-1, 3)
    held = [(geom(f"e{i}_string0"), names.index(e.marker)) for i, e in enumerate(elements)
            if isinstance(e, Balloon)]
    flex = lambda name: int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_FLEX, name))  # noqa: E731
    flexes = [(flex(name), marker) for name, marker in cloths]
    _damp_cloth(model, [f for f, _ in flexes], [body(f"m{m}") if m >= 0 else 0 for _, m in flexes])
    driven = np.array([_top_row(model, flex(name)) for name, _ in capes], np.int64).reshape(-1)
    if len(driven):
        _drive(mujoco, model, driven)
    balls = [geom(name) for name in ball_names]
    rain = [(geom(name), box) for name, box in drops]
    return SceneModel(
        model=model, height=height, limb_radii=radii,
        marker_bodies=[body(f"m{n}") for n in range(len(names))],
        limb_bodies=[body(f"l{k}") for k in range(len(proxy.limbs))],
        limb_geoms=np.array([[geom(f"l{k}_{s}") for s in range(SEGMENTS)] for k in range(len(proxy.limbs))],
                            dtype=np.int64).reshape(-1, SEGMENTS),
        element_geoms=drawn, colours=colours, held=held, balls=balls, default_volumes=default_volumes,
        rain=rain, cloths=flexes, driven_bodies=driven,
        driven_paths=np.concatenate([path for _, path in capes], axis=1) if capes else np.zeros((0, 0, 3)),
    )


def _mujoco():
    try:
        import mujoco
    except ImportError:  # a required dependency, but a broken install must still say so
        raise SceneError("scenes need the MuJoCo physics engine: pip install mujoco") from None
    return mujoco


def _limb_radii(proxy, height):
    if proxy.radii is not None:
        return np.array(proxy.radii)
    return np.full((proxy.frame_count, len(proxy.limbs), 2), DEFAULT_LIMB_RADIUS * height)


def _balloon_xml(i, balloon, height):
    """A string of capsules straight up from the holding marker's body, the balloon at its top."""
    radius = balloon.radius or BALLOON_RADIUS * height
    link = (balloon.string_length or STRING_LENGTH * height) / STRING_LINKS
    rgba = _rgba(balloon.colour)
    inner = (f'<body name="e{i}_balloon" pos="0 {link!r} 0" gravcomp="{balloon.lift!r}">'
             f'<joint type="ball" damping="0.0002"/><geom name="e{i}_balloon" type="sphere" '
             f'pos="0 {radius!r} 0" size="{radius!r}" mass="{BALLOON_MASS}" rgba="{rgba}" {ELEMENT_BITS} '
             f'{CONTACT}/></body>')
    for s in reversed(range(STRING_LINKS)):
        pos = "0 0 0" if s == 0 else f"0 {link!r} 0"
        inner = (f'<body name="e{i}_link{s}" pos="{pos}"><joint type="ball" damping="0.00005"/>'
                 f'<geom name="e{i}_string{s}" type="capsule" pos="0 {link / 2!r} 0" zaxis="0 1 0" '
                 f'size="{STRING_RADIUS} {link / 2!r}" mass="0.0005" rgba="0.15 0.15 0.15 1" contype="0" '
                 f'conaffinity="0"/>'
                 f'{inner}</body>')
    return inner


def _scarf_xml(name, scarf, proxy, marker, radii, height):
    """A scarf: a strip of :data:`SCARF_ROWS` x :data:`SCARF_COLUMNS` vertices hanging from a knot
    beside the marker (in the marker body's frame), its first row pinned.

    The knot sits outside the marker's largest joint sphere over the clip (up to 2.5 times its
    radius out), along the first way (:func:`_directions`) on which the knot stays clear of every
    limb's volume on every frame (seen from the marker) and the strip is clear of the first
    frame's volumes and the ground; the strip's width faces the camera.
    """
    width = scarf.width or SCARF_WIDTH * height
    length = scarf.length or SCARF_LENGTH * height
    thick = CLOTH_RADIUS * height
    P = proxy.points
    reach = _marker_reach(proxy, marker, radii) + thick + 0.1 * width
    relative = _relative_volumes(proxy, marker, radii)
    first = _first_frame_volumes(proxy, radii)
    axis = np.asarray(proxy.camera.rotations[0])[2]
    ways = _directions(P[0], marker)
    candidates = []  # (way, across, knot, clear on every frame), the first way and nearest knot first
    for way in ways:
        across = _across(way, axis)
        if P[0, marker, 1] + way[1] * (reach + length) <= width:  # into the ground
            continue
        for d in reach * np.linspace(1.0, 2.5, 7):
            edge = way * d + np.outer(np.linspace(-0.5, 0.5, SCARF_COLUMNS), across * width)
            strip = np.linspace(0.0, 1, 9)[:, None, None] * (way * length) + edge
            if _gap_ok(P[0, marker] + strip, thick, [_stack(first)]):
                candidates.append((way, across, way * d, _gap_ok(edge, thick, relative)))
    # Clear on every frame if it can be; else clear on the first (a limb may sweep through the knot
    # later: the contacts push the cloth aside); else down (or the first way off the ground), far out.
    best = next((c for c in candidates if c[3]), candidates[0] if candidates else None)
    if best is None:
        way = next((w for w in ways if P[0, marker, 1] + w[1] * (reach + length) > width), ways[0])
        best = (way, _across(way, axis), way * 2.5 * reach, False)
    way, across, knot, _ = best
    rows = np.linspace(0.0, 1.0, SCARF_ROWS)[:, None, None] * (way * length)
    cols = np.linspace(-0.5, 0.5, SCARF_COLUMNS)[None, :, None] * (across * width)
    V = (knot + rows + cols).reshape(-1, 3)
    F = _grid_triangles(SCARF_ROWS, SCARF_COLUMNS, ring=False)
    return _flex_xml(name, V, F, range(SCARF_COLUMNS), CLOTH_DENSITY * width * length, scarf.colour, thick)


def _skirt_xml(name, skirt, proxy, marker, radii, height):
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
    relative = _relative_volumes(proxy, marker, radii)
    first = [_stack(_first_frame_volumes(proxy, radii))]
    f = np.linspace(0.0, 1.0, SKIRT_ROWS)

    def rings(r):
        return (r + SKIRT_FLARE * length * f)[:, None, None] * unit + (-length * f)[:, None, None] * [0, 1, 0]

    chosen = None
    for r in np.linspace(radius, 3 * radius, 21):
        V = rings(r)
        if _gap_ok(V[0], thick, relative) and _gap_ok(P[0, marker] + V[1:].reshape(-1, 3), thick, first):
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
    F = _grid_triangles(SKIRT_ROWS, n, ring=True)
    area = 2 * np.pi * (chosen + 0.5 * SKIRT_FLARE * length) * length
    return _flex_xml(name, V, F, range(n), CLOTH_DENSITY * area, skirt.colour, thick)


def _cape_xml(name, cape, proxy, left, right, radii, height):
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
    reach = max(_marker_reach(proxy, left, radii), _marker_reach(proxy, right, radii)) + 2 * thick
    width = float(np.median(np.linalg.norm(across, axis=1)))
    way = across / np.maximum(np.linalg.norm(across, axis=1), 1e-300)[:, None]
    s = np.linspace(-0.5, 0.5, CAPE_COLUMNS) * width
    top = (P[:, left] + P[:, right])[:, None] / 2 + s[None, :, None] * way[:, None]  # (T, CAPE_COLUMNS, 3)
    fall = np.linspace(0.0, 1.0, CAPE_ROWS)[:, None, None] * [0.0, -length, 0.0]
    first = [_stack(_first_frame_volumes(proxy, radii))]
    for d in reach * np.linspace(1.0, 2.5, 7):
        V = top[0] + back[0] * d + fall
        if _gap_ok(V, thick, first):
            break
    else:
        raise SceneError(f"a cape from {cape.left!r} to {cape.right!r} cannot hang clear of the body behind "
                         f"them (set back up to {2.5 * reach:.2f} m): a figure whose body runs level behind "
                         "its shoulders, or the shoulders swapped (the cape hangs behind (right - left) x "
                         "up: give the figure's own left first)")
    if V[-1, 0, 1] < thick:  # the hem would start in the ground: shorten the fall
        V[1:, :, 1] = V[0, :, 1] + (V[1:, :, 1] - V[0, :, 1]) * max(V[0, 0, 1] - 2 * thick, 1e-3) / length
    F = _grid_triangles(CAPE_ROWS, CAPE_COLUMNS, ring=False)
    xml = _flex_xml(name, V.reshape(-1, 3), F, (), CLOTH_DENSITY * width * length, cape.colour, thick)
    return xml, top + back[:, None] * d


def _top_row(model, flex):
    """A cape's driven vertices' bodies: the first :data:`CAPE_COLUMNS` of its flex."""
    start = model.flex_vertadr[flex]
    return model.flex_vertbodyid[start:start + CAPE_COLUMNS]


def _drive(mujoco, model, bodies):
    """Make ``bodies`` (cape vertices moved by hand) as heavy as the proxy and undamped, so the cloth
    they hold does not drag them off their path within a sub-step."""
    model.body_mass[bodies] = KINEMATIC_MASS
    for b in bodies:
        model.dof_damping[model.body_dofadr[b] + np.arange(model.body_dofnum[b])] = 0.0
    mujoco.mj_setConst(model, mujoco.MjData(model))


def _air(elements):
    """The ``<option>`` attributes of air: MuJoCo's fluid model when a balloon, balls or rain are in
    the scene, none for cloth alone.

    Cloth has its own drag (:data:`CLOTH_DAMPING`), and the fluid model's velocity derivatives,
    which the implicit integrator takes over every body, cost more than the rest of a step with a
    cloth's vertices as bodies (measured on the demo with a scarf and a skirt, 167 vertices: a
    step of 2.4 ms, 0.8 ms without it). A cloth scene with a balloon, balls or rain pays it.
    """
    if any(isinstance(e, Balloon | Balls | Rain) for e in elements):
        return f'density="{AIR_DENSITY}" viscosity="{AIR_VISCOSITY}"'
    return 'density="0" viscosity="0"'


def _flex_xml(name, V, F, pinned, mass, colour, thick):
    """A ``flexcomp`` of vertices ``V`` (in its body's frame) and triangles ``F``, ``pinned`` vertices
    fixed to the body, edges of constant length, colliding with the proxy, the ground and the other
    elements but not itself."""
    mass = max(float(mass), MIN_CLOTH_VERTEX_MASS * len(V))
    points = " ".join(repr(float(c)) for c in np.asarray(V).ravel())
    elements = " ".join(str(int(k)) for k in np.asarray(F).ravel())
    pins = f'<pin id="{" ".join(str(k) for k in pinned)}"/>' if len(pinned) else ""  # a cape has none
    return (f'<flexcomp name="{name}" type="direct" dim="2" point="{points}" element="{elements}" '
            f'mass="{mass!r}" radius="{thick!r}" rgba="{_rgba(colour)}">'
            f'<contact {ELEMENT_BITS} selfcollide="none" solref="{CLOTH_CONTACT_TIME} 1" '
            f'friction="0.6 0.005 0.001"/>'
            f'<edge equality="true" solref="{CONTACT_TIME} 1" damping="{CLOTH_EDGE_DAMPING}"/>'
            f'{pins}</flexcomp>')


def _grid_triangles(rows, columns, ring):
    """Two triangles per cell of a ``rows`` x ``columns`` grid of vertices (row major); ``ring``
    joins the last column to the first (a cylinder)."""
    cells = columns if ring else columns - 1
    i, j = np.meshgrid(np.arange(rows - 1), np.arange(cells), indexing="ij")
    a = i * columns + j
    b = i * columns + (j + 1) % columns
    c, d = a + columns, b + columns
    return np.stack([np.stack([a, c, b], -1), np.stack([b, c, d], -1)], axis=2).reshape(-1, 3)


def _damp_cloth(model, flexes, holders):
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


def _across(way, axis):
    """A unit vector across ``way`` facing the camera's ``axis`` as far as it can."""
    c = np.cross(way, axis)
    if np.linalg.norm(c) < 1e-6:
        c = np.cross(way, [0.0, 1.0, 0.0]) if abs(way[1]) < 0.9 else np.cross(way, [1.0, 0.0, 0.0])
    return c / np.linalg.norm(c)


def _marker_reach(proxy, marker, radii):
    """The largest radius of any limb end at ``marker`` over the clip (its joint sphere's)."""
    L = np.asarray(proxy.limbs)
    ends = [radii[:, k, e] for k in range(len(L)) for e in (0, 1) if L[k, e] == marker]
    return float(max((np.max(r) for r in ends), default=0.0))


def _relative_volumes(proxy, marker, radii):
    """Every frame's limb volumes ``(A, B, r)`` seen from ``marker`` (its point at the origin),
    stacked: where a point that moves with the marker must not be."""
    P = proxy.points - proxy.points[:, marker:marker + 1]
    L = np.asarray(proxy.limbs)
    R = np.asarray(radii).max(axis=2)
    return [(P[:, L[:, 0]].reshape(-1, 3), P[:, L[:, 1]].reshape(-1, 3), R.reshape(-1))]


def _stack(volumes):
    if not volumes:
        return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0)
    a, b, r = zip(*volumes, strict=True)
    return np.array(a), np.array(b), np.array(r)


def _gap_ok(points, radius, volumes, gap=1e-3):
    """Whether balls of ``radius`` at ``points`` ``(..., 3)`` touch none of the capsules in
    ``volumes`` (a list of stacked ``(A, B, r)``), vectorised."""
    q = np.asarray(points, dtype=float).reshape(-1, 3)
    for A, B, r in volumes:
        if len(A) == 0:
            continue
        AB = B - A
        den = np.maximum((AB * AB).sum(-1), 1e-300)
        s = np.clip(((q[:, None] - A) * AB).sum(-1) / den, 0.0, 1.0)
        d = np.linalg.norm(q[:, None] - (A + s[..., None] * AB), axis=-1)
        if (d < r + radius + gap).any():
            return False
    return True


def _directions(P, marker):
    """Ways a chain may hang from a marker, best first: down, then out sideways away from the
    figure's middle, then the other horizontal ways and up."""
    away = P[marker] - P.mean(axis=0)
    away[1] = 0.0
    n = np.linalg.norm(away)
    away = away / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])
    side = np.array([-away[2], 0.0, away[0]])
    return [np.array([0.0, -1.0, 0.0]), away, side, -side, -away, np.array([0.0, 1.0, 0.0])]


def _clear(points, radius, volumes, gap=1e-3):
    """Whether balls of ``radius`` at ``points`` touch none of ``volumes`` ``(a, b, r)``."""
    for q in points:
        for a, b, r in volumes:
            if np.linalg.norm(q - _closest_on_segment(q, a, b)) < r + radius + gap:
                return False
    return True


def rain_box(proxy: Proxy, height: float) -> NDArray[np.float64]:
    """Where rain falls: ``(x0, x1, z0, z1, top)``, the figure's ground path over the clip widened
    by half its height each way, and from half a height above its highest point."""
    P = proxy.points
    lo, hi = P.reshape(-1, 3).min(axis=0), P.reshape(-1, 3).max(axis=0)
    margin = 0.5 * height
    return np.array([lo[0] - margin, hi[0] + margin, lo[2] - margin, hi[2] + margin, hi[1] + margin])


def drops_in(rng, box, count, full_height):
    """Drop centres in ``box``: at every height down to the ground, or just above the top."""
    x = rng.uniform(box[0], box[1], count)
    z = rng.uniform(box[2], box[3], count)
    if full_height:
        y = rng.uniform(0.05 * box[4], box[4], count)
    else:
        y = box[4] + rng.uniform(0, 0.1 * box[4], count)
    return np.stack([x, y, z], axis=1)


def _place_balls(proxy, volumes, marker, count, r, placed):
    """Centres on the marker's ground path at evenly spaced times, moved clear of the first frame's
    volumes and of balls already placed."""
    T = proxy.frame_count
    path = proxy.points[:, marker].copy()
    out = []
    for k in range(count):
        c = path[int(round((k + 1) * (T - 1) / (count + 1)))].copy()
        c[1] = r
        for _ in range(50):
            push = _overlap(c, r, volumes, placed + [(o, r) for o in out])
            if push is None:
                break
            c += push
        out.append(c)
    return out


def _first_frame_volumes(proxy, radii):
    """Frame 0's capsules ``(a, b, radius)``, one per limb at its larger radius."""
    P = proxy.points[0]
    return [(P[p], P[c], float(radii[0, k].max())) for k, (p, c) in enumerate(proxy.limbs)]


def _overlap(c, r, capsules, balls, gap=1e-3):
    """A horizontal move that takes the ball at ``c`` out of the first thing it overlaps, or None."""
    for a, b, radius in capsules:
        q = _closest_on_segment(c, a, b)
        d = c - q
        depth = radius + r + gap - np.linalg.norm(d)
        if depth > 0:
            return _horizontal(d) * depth
    for o, ro in balls:
        d = c - o
        depth = ro + r + gap - np.linalg.norm(d)
        if depth > 0:
            return _horizontal(d) * depth
    return None


def _horizontal(d):
    h = np.array([d[0], 0.0, d[2]])
    n = np.linalg.norm(h)
    return h / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])


def _closest_on_segment(p, a, b):
    ab = b - a
    denominator = float(ab @ ab)
    s = 0.0 if denominator == 0 else float(np.clip((p - a) @ ab / denominator, 0, 1))
    return a + s * ab


def _v(x):
    return " ".join(repr(float(c)) for c in x)


def _rgba(colour):
    return " ".join(f"{c / 255:.6g}" for c in colour) + " 1"

