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

Scarves, skirts and capes are cloth, built by :mod:`toonmotion.scene.cloth`; where an element may
start is :mod:`toonmotion.scene.clearance`'s.

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
from toonmotion.scene.clearance import clear, directions, first_frame_volumes, overlap
from toonmotion.scene.cloth import (
    CAPE_BODIES,
    SCARF_BODIES,
    SKIRT_ROWS,
    cape_xml,
    damp_cloth,
    drive,
    scarf_xml,
    skirt_columns,
    skirt_xml,
    top_row,
)
from toonmotion.scene.elements import (
    BALL_RADIUS,
    BALLOON_RADIUS,
    MAX_SIZE,
    RAIN_RADIUS,
    STRING_LENGTH,
    Balloon,
    Balls,
    Cape,
    Element,
    Rain,
    Scarf,
    Skirt,
)
from toonmotion.scene.mjcf import (
    CONTACT,
    CONTACT_TIME,
    DROP_BITS,
    ELEMENT_BITS,
    KINEMATIC_MASS,
    PROXY_BITS,
    load_mujoco,
    rgba_text,
    vec,
)

SEGMENTS = 3  # capsules per tapered cylinder
STRING_LINKS = 8
MIN_LINK_MASS = 0.002  # kg: lighter links make the contacts stiff beyond what a sub-step resolves
CHAIN_ARMATURE = 1e-4  # kg m^2 of rotor inertia on a chain's joints: keeps light links stable in contact
# Proxy radii when the proxy has no collision volumes (lifted without drawn frames), as a fraction
# of the figure's height.
DEFAULT_LIMB_RADIUS = 0.035
BALL_DENSITY = 300.0  # kg/m^3, a light rubber ball
BALLOON_MASS = 0.01  # kg
AIR_DENSITY = 1.2  # kg/m^3
AIR_VISCOSITY = 0.000018  # Pa s
STRING_RADIUS = 0.003  # m, physical; drawn at least api.scene3d.STRING_MIN_PX across
WATER_DENSITY = 1000.0


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
    mujoco = load_mujoco()
    names = list(proxy.names)
    height = figure_height(proxy)
    radii = _limb_radii(proxy, height)
    default_volumes = proxy.radii is None
    P0 = proxy.points[0]
    volumes = first_frame_volumes(proxy, radii)  # where elements must not start
    held_xml: dict[int, list[str]] = {}
    element_xml = []
    cloths: list[tuple[str, int]] = []  # each cloth's flex and the marker holding it
    capes: list[tuple[str, NDArray[np.float64]]] = []  # each cape's flex and its top row's path
    for i, element in enumerate(elements):
        if isinstance(element, Rain):
            continue
        if isinstance(element, Cape):
            xml, path = cape_xml(f"e{i}_cape", element, proxy, names.index(element.left),
                                  names.index(element.right), radii, height)
            element_xml.append(xml)
            cloths.append((f"e{i}_cape", -1))
            capes.append((f"e{i}_cape", path))
            continue
        at = held_xml.setdefault(names.index(element.marker), [])
        if isinstance(element, Balloon):
            way = balloon_way(proxy, names.index(element.marker), element, volumes, height)
            at.append(_balloon_xml(i, element, height, way))
        elif isinstance(element, Scarf):
            marker = names.index(element.marker)
            at.append(scarf_xml(f"e{i}_scarf", element, proxy, marker, radii, height))
            cloths.append((f"e{i}_scarf", marker))
        elif isinstance(element, Skirt):
            marker = names.index(element.marker)
            at.append(skirt_xml(f"e{i}_skirt", element, proxy, marker, radii, height))
            cloths.append((f"e{i}_skirt", marker))
    placed: list[tuple[NDArray[np.float64], float]] = []
    ball_names: list[str] = []
    for i, element in enumerate(elements):
        if isinstance(element, Balls):
            r = element.radius or BALL_RADIUS * height
            marker = names.index(element.marker)
            for j, centre in enumerate(_place_balls(proxy, volumes, marker, element.count, r, placed)):
                placed.append((centre, r))
                rgba = rgba_text(element.colours[j % len(element.colours)])
                ball_names.append(f"e{i}_ball{j}")
                element_xml.append(
                    f'<body name="e{i}_ball{j}" pos="{vec(centre)}"><freejoint/><geom name="e{i}_ball{j}" '
                    f'type="sphere" size="{r!r}" density="{BALL_DENSITY}" rgba="{rgba}" {ELEMENT_BITS} '
                    f'{CONTACT}/></body>')
    drops: list[tuple[str, NDArray[np.float64]]] = []
    for i, element in enumerate(elements):
        if isinstance(element, Rain):
            r = element.radius or RAIN_RADIUS * height
            box = rain_box(proxy, height)
            rng = np.random.default_rng(element.seed)
            starts = [c for c in drops_in(rng, box, 4 * element.count, full_height=True)
                      if clear([c], r, volumes)][:element.count]
            starts += list(drops_in(rng, box, element.count - len(starts), full_height=False))
            for j, centre in enumerate(starts):
                drops.append((f"e{i}_drop{j}", box))
                element_xml.append(
                    f'<body name="e{i}_drop{j}" pos="{vec(centre)}"><freejoint/><geom name="e{i}_drop{j}" '
                    f'type="sphere" size="{r!r}" density="{WATER_DENSITY}" '
                    f'rgba="{rgba_text(element.colour)}" {DROP_BITS} solref="{CONTACT_TIME} 0.3" '
                    'friction="0.2 0.005 0.0001"/></body>')
    bodies = []
    for n in range(len(names)):
        bodies.append(
            f'<body name="m{n}" pos="{vec(P0[n])}"><freejoint/><geom name="m{n}" type="sphere" size="0.01" '
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
    damp_cloth(model, [f for f, _ in flexes], [body(f"m{m}") if m >= 0 else 0 for _, m in flexes])
    driven = np.array([top_row(model, flex(name)) for name, _ in capes], np.int64).reshape(-1)
    if len(driven):
        drive(mujoco, model, driven)
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


def _limb_radii(proxy, height):
    if proxy.radii is not None:
        return np.array(proxy.radii)
    return np.full((proxy.frame_count, len(proxy.limbs), 2), DEFAULT_LIMB_RADIUS * height)


def balloon_way(proxy: Proxy, marker: int, balloon: Balloon, volumes: list,
                height: float) -> NDArray[np.float64]:
    """Which way a balloon's string starts from its marker: straight up, unless that starts the
    balloon inside a limb's volume on the first frame (a balloon held at the chest, under the
    head), which flings it out and can blow the simulation up; then the first that starts it
    clear of leaning out away from the figure's middle, to either side or back, at 45 degrees,
    then lower, then level (its lift then carries it up on its own). Up when none does."""
    radius = balloon.radius or BALLOON_RADIUS * height
    length = balloon.string_length or STRING_LENGTH * height
    up = np.array([0.0, 1.0, 0.0])
    outs = directions(proxy.points[0], marker)[1:5]
    for way in [up] + [rise * up + w for rise in (1.0, 0.5, 0.0) for w in outs]:
        way = way / np.linalg.norm(way)
        if clear([proxy.points[0][marker] + way * (length + radius)], radius, volumes):
            return way
    return up


def _balloon_xml(i, balloon, height, way):
    """A string of capsules from the holding marker's body along ``way``, the balloon at its top."""
    radius = balloon.radius or BALLOON_RADIUS * height
    link = (balloon.string_length or STRING_LENGTH * height) / STRING_LINKS
    rgba = rgba_text(balloon.colour)
    inner = (f'<body name="e{i}_balloon" pos="0 {link!r} 0" gravcomp="{balloon.lift!r}">'
             f'<joint type="ball" damping="0.0002"/><geom name="e{i}_balloon" type="sphere" '
             f'pos="0 {radius!r} 0" size="{radius!r}" mass="{BALLOON_MASS}" rgba="{rgba}" {ELEMENT_BITS} '
             f'{CONTACT}/></body>')
    turn = _turn_from_up(way)
    for s in reversed(range(STRING_LINKS)):
        pos = "0 0 0" if s == 0 else f"0 {link!r} 0"
        quat = f' quat="{vec(turn)}"' if s == 0 else ""
        inner = (f'<body name="e{i}_link{s}" pos="{pos}"{quat}><joint type="ball" damping="0.00005"/>'
                 f'<geom name="e{i}_string{s}" type="capsule" pos="0 {link / 2!r} 0" zaxis="0 1 0" '
                 f'size="{STRING_RADIUS} {link / 2!r}" mass="0.0005" rgba="0.15 0.15 0.15 1" contype="0" '
                 f'conaffinity="0"/>'
                 f'{inner}</body>')
    return inner


def _turn_from_up(way):
    """MuJoCo's quaternion (w, x, y, z) turning +Y onto the unit vector ``way``."""
    up = np.array([0.0, 1.0, 0.0])
    axis = np.cross(up, way)
    w = 1.0 + float(up @ way)
    if w < 1e-9:  # straight down: half a turn about X
        return np.array([0.0, 1.0, 0.0, 0.0])
    q = np.array([w, *axis])
    return q / np.linalg.norm(q)


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
            push = overlap(c, r, volumes, placed + [(o, r) for o in out])
            if push is None:
                break
            c += push
        out.append(c)
    return out


