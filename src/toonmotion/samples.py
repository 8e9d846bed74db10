"""A bundled sample character, drawn by code, for demos, tests and docs.

The figure is original artwork built from simple shapes (ellipses, round-capped limbs and
rounded polygons made with shapely), painted with Pillow on a canvas several times larger than
the result (see :data:`SUPERSAMPLE`) and averaged down over boxes, so each edge pixel's alpha is
the share of it the figure covers. (A box filter, unlike Lanczos, leaves no faint ringing
around the figure: the background stays exactly transparent.) No image file is read: the same
bytes come out on every call and on every machine with the same Pillow.

It is a cheerful kid in a striped shirt, belted jeans and sneakers, standing in an A-pose: arms
held out and down, away from the body, legs apart, so no limb touches another limb or the body
except where it attaches. Every part has a dark outline and a flat fill; stripes, a belt,
buttons, cuffs and a face give a deformation something to show.

Coordinates are (x, y) pixels, x right, y down. ``right_*`` joints are the character's right,
which is on the image's left.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw
from scipy import ndimage as ndi
from shapely import affinity
from shapely.geometry import LineString, Point, Polygon, box
from shapely.ops import unary_union

from toonmotion.rig.character import Character
from toonmotion.rig.skeleton import Skeleton

WIDTH, HEIGHT = 420, 600
"""Size of the sample image at ``scale=1``, pixels."""

SUPERSAMPLE = 4
"""At scale 1 the figure is painted this many times larger, then downsampled; at other scales
on a canvas at least as large (and at least twice the result's size)."""

BACKGROUNDS = ("white", "paper")

MIN_SCALE, MAX_SCALE = 0.05, 4.0

# The character's joints at scale 1: (name, parent, (x, y)). The figure is built around them.
JOINTS = (
    ("root", None, (210.0, 390.0)),
    ("hip", "root", (210.0, 390.0)),
    ("torso", "hip", (210.0, 262.0)),
    ("neck", "torso", (210.0, 198.0)),
    # Beyond the Animated Drawings set: a head bone, so the head follows the neck, not the
    # shoulders (without it the shoulder bones are nearer to the sides of the head).
    ("head", "neck", (210.0, 70.0)),
    ("right_shoulder", "torso", (142.0, 214.0)),
    ("right_elbow", "right_shoulder", (95.0, 249.0)),
    ("right_hand", "right_elbow", (47.0, 284.0)),
    ("left_shoulder", "torso", (278.0, 214.0)),
    ("left_elbow", "left_shoulder", (325.0, 249.0)),
    ("left_hand", "left_elbow", (373.0, 284.0)),
    ("right_hip", "root", (159.0, 396.0)),
    ("right_knee", "right_hip", (142.0, 471.0)),
    ("right_foot", "right_knee", (131.0, 547.0)),
    ("left_hip", "root", (261.0, 396.0)),
    ("left_knee", "left_hip", (278.0, 471.0)),
    ("left_foot", "left_knee", (289.0, 547.0)),
)

_OUTLINE_WIDTH = 4.0  # pixels at scale 1
_QUAD_SEGS = 24  # segments per quarter circle in every round shape

_INK = (44, 32, 52)
_SKIN = (255, 213, 172)
_SKIN_SHADE = (240, 168, 132)
_BLUSH = (255, 160, 150)
_HAIR = (122, 72, 40)
_HAIR_LIGHT = (160, 102, 58)
_SHIRT = (236, 84, 70)
_STRIPE = (255, 238, 205)
_JEANS = (64, 112, 196)
_JEANS_DARK = (44, 80, 152)
_CREASE = (36, 64, 128)
_BELT = (104, 62, 38)
_GOLD = (252, 200, 64)
_SHOE = (64, 176, 120)
_SOLE = (250, 250, 244)
_WHITE = (255, 255, 255)
_MOUTH = (150, 38, 56)
_TONGUE = (246, 116, 128)

_PAPER = (243, 238, 226)


def sample_character(*, scale: float = 1.0) -> tuple[NDArray[np.uint8], Skeleton]:
    """The bundled sample character, on a transparent background, with its skeleton.

    Parameters
    ----------
    scale : float
        Size relative to the :data:`WIDTH` x :data:`HEIGHT` (420 x 600) original, between
        0.05 and 4. Joint positions scale with it.

    Returns
    -------
    rgba : (h, w, 4) uint8
        The drawing: alpha 0 on the background, 255 on the figure, in between only on its
        anti-aliased edge. ``h, w = round(600 * scale), round(420 * scale)``.
    skeleton : Skeleton
        The 16 Animated Drawings joints ``root, hip, torso, neck`` and ``right_/left_``
        ``shoulder, elbow, hand, hip, knee, foot``, plus ``head`` (a child of ``neck`` at the
        middle of the head), at their places on the figure, (x, y) pixels, y down.

    Examples
    --------
    >>> rgba, skeleton = sample_character()
    >>> rgba.shape, rgba.dtype.name
    ((600, 420, 4), 'uint8')
    >>> len(skeleton), skeleton.names[:3]
    (17, ('root', 'hip', 'torso'))
    >>> int(rgba[0, 0, 3]), int(rgba[300, 210, 3])
    (0, 255)
    """
    scale = _check_scale(scale)
    return _render(scale), _skeleton(scale)


def sample_rig(*, scale: float = 0.5) -> Character:
    """The sample character rigged with its skeleton: a :class:`Character` to try things on.

    Parameters
    ----------
    scale : float
        As for :func:`sample_character`; half size by default (210 x 300), which rigs in
        about a third of a second.

    Examples
    --------
    >>> hero = sample_rig()
    >>> hero.size, len(hero.skeleton)
    ((210, 300), 17)
    """
    from toonmotion.rig.pipeline import rig_drawing

    drawing, skeleton = sample_character(scale=scale)
    return rig_drawing(drawing, skeleton=skeleton)


def sample_character_on(
    background: str, *, scale: float = 1.0, seed: int = 0
) -> tuple[NDArray[np.uint8], Skeleton]:
    """The sample character flattened onto an opaque background, like a scan or a photo.

    Parameters
    ----------
    background : {"white", "paper"}
        "white" is flat white, like digital art. "paper" is an off-white page with a gentle
        lighting gradient and mild noise, like a photographed drawing.
    scale : float
        As for :func:`sample_character`.
    seed : int
        Seeds the paper's noise; "white" ignores it.

    Returns
    -------
    rgb : (h, w, 3) uint8
    skeleton : Skeleton
        As for :func:`sample_character`.

    Examples
    --------
    >>> rgb, skeleton = sample_character_on("paper", scale=0.5)
    >>> rgb.shape
    (300, 210, 3)
    """
    if background not in BACKGROUNDS:
        raise ValueError(f"background must be one of {BACKGROUNDS}, got {background!r}")
    rgba, skeleton = sample_character(scale=scale)
    colour = rgba[..., :3].astype(np.float32)
    alpha = rgba[..., 3:].astype(np.float32) / 255.0
    if background == "white":
        rgb = colour * alpha + 255.0 * (1.0 - alpha)
    else:
        paper = np.array(_PAPER, dtype=np.float32)
        rgb = _photograph(colour * alpha + paper * (1.0 - alpha), seed=seed)
    return np.clip(np.rint(rgb), 0, 255).astype(np.uint8), skeleton


def _check_scale(scale):
    try:
        value = float(scale)
    except (TypeError, ValueError):
        raise ValueError(f"scale must be a number, got {scale!r}") from None
    if not MIN_SCALE <= value <= MAX_SCALE:
        raise ValueError(f"scale must be between {MIN_SCALE} and {MAX_SCALE}, got {scale!r}")
    return value


def _size(scale):
    return max(1, round(WIDTH * scale)), max(1, round(HEIGHT * scale))


def _skeleton(scale):
    return Skeleton.from_joints((name, parent, (x * scale, y * scale)) for name, parent, (x, y) in JOINTS)


def _render(scale):
    """Paint the figure large, downsample, return (h, w, 4) uint8."""
    width, height = _size(scale)
    factor = max(2, math.ceil(SUPERSAMPLE / scale - 1e-9))
    big = Image.new("RGBA", (width * factor, height * factor), (0, 0, 0, 0))
    k = scale * factor
    # Output pixel i, centred on x = i, covers canvas pixels factor * i ... factor * i + factor - 1.
    offset = (factor - 1) / 2
    painter = _Painter(big, (k, 0.0, 0.0, k, offset, offset))
    for geometry, colour, outlined in _figure():
        painter.paint(geometry, colour, outlined=outlined)
    return np.array(big.reduce(factor))  # a writable copy


class _Painter:
    """Fills shapely geometries, given at scale 1, on a supersampled RGBA canvas."""

    def __init__(self, image, transform):
        self.image = image
        self.draw = ImageDraw.Draw(image)
        self.transform = transform

    def paint(self, geometry, colour, *, outlined=True):
        if outlined:
            outline = geometry.buffer(_OUTLINE_WIDTH, quad_segs=_QUAD_SEGS)
            self._fill(outline, _INK)
        self._fill(geometry, colour)

    def _fill(self, geometry, colour):
        geometry = affinity.affine_transform(geometry, self.transform)
        fill = (*colour, 255)
        for polygon in _polygons(geometry):
            if not polygon.interiors:
                self.draw.polygon(list(polygon.exterior.coords), fill=fill)
                continue
            mask = Image.new("L", self.image.size, 0)
            mask_draw = ImageDraw.Draw(mask)
            mask_draw.polygon(list(polygon.exterior.coords), fill=255)
            for ring in polygon.interiors:
                mask_draw.polygon(list(ring.coords), fill=0)
            self.image.paste(fill, mask=mask)


def _polygons(geometry):
    if geometry.is_empty:
        return []
    if geometry.geom_type == "Polygon":
        return [geometry]
    if hasattr(geometry, "geoms"):
        return [p for g in geometry.geoms for p in _polygons(g)]
    return []  # points and lines left over from intersections have no area


# --- the drawing ----------------------------------------------------------------------------


def _joint(name):
    for joint, _, position in JOINTS:
        if joint == name:
            return position
    raise KeyError(name)


def _ellipse(cx, cy, rx, ry, angle=0.0):
    shape = affinity.scale(Point(cx, cy).buffer(1.0, quad_segs=_QUAD_SEGS), rx, ry)
    return affinity.rotate(shape, angle, origin=(cx, cy)) if angle else shape


def _limb(points, width, *, cap="round"):
    return LineString(points).buffer(width / 2, quad_segs=_QUAD_SEGS, cap_style=cap)


def _tapered(points, widths):
    """A limb through ``points``, ``widths[i]`` wide at ``points[i]``; flat at both ends."""
    points, half = np.asarray(points, dtype=float), np.asarray(widths, dtype=float) / 2
    pieces = [Point(p).buffer(h, quad_segs=_QUAD_SEGS) for p, h in zip(points[1:-1], half[1:-1], strict=True)]
    for i in range(len(points) - 1):
        d = points[i + 1] - points[i]
        n = np.array([-d[1], d[0]]) / np.hypot(*d)
        a, b = n * half[i], n * half[i + 1]
        pieces.append(Polygon([points[i] + a, points[i + 1] + b, points[i + 1] - b, points[i] - a]))
    return unary_union(pieces)


def _rounded(polygon, radius):
    return polygon.buffer(-radius, quad_segs=_QUAD_SEGS).buffer(radius, quad_segs=_QUAD_SEGS)


def _stroke(points, width):
    """A drawn line (brows, seams, creases): a round-capped band ``width`` wide."""
    return _limb(points, width)


def _arc(cx, cy, rx, ry, start, stop, n=24):
    """Points along an elliptical arc; angles in degrees, clockwise from +x (y down)."""
    t = np.radians(np.linspace(start, stop, n))
    return list(zip(cx + rx * np.cos(t), cy + ry * np.sin(t), strict=True))


def _mirror(geometry):
    return affinity.scale(geometry, -1.0, 1.0, origin=(WIDTH / 2, 0.0))


def _both(geometry):
    return unary_union([geometry, _mirror(geometry)])


def _figure():
    """The figure as ``(geometry, colour, outlined)`` in painting order, back to front."""
    parts = []

    def add(geometry, colour, outlined=True):
        parts.append((geometry, colour, outlined))

    # Sneakers, behind the jeans' hems; toes point outward.
    fx, fy = _joint("right_foot")
    shoe = unary_union([_ellipse(fx - 14, fy + 14, 48, 26), _ellipse(fx + 3, fy + 3, 40, 27)])
    shoe = _rounded(shoe.intersection(box(0, 0, WIDTH, fy + 37)), 5)
    add(_both(shoe), _SHOE)
    add(_both(shoe.intersection(box(0, fy + 25, WIDTH, HEIGHT))), _SOLE, outlined=False)
    add(_both(_stroke([(fx - 80, fy + 25), (fx + 50, fy + 25)], 3.0).intersection(shoe)), _INK, False)
    for dx in (-34, -21):
        add(_both(_stroke([(fx + dx + 7, fy + 2), (fx + dx, fy + 12)], 3.0)), _INK, False)

    # Jeans: hips and both legs as one piece, with cuffs, a seam, pockets and creases.
    legs = []
    for side in ("right", "left"):
        hip, knee, foot = (_joint(f"{side}_{j}") for j in ("hip", "knee", "foot"))
        thigh = np.subtract(hip, knee) * 0.6 + hip  # starts inside the hips: no corner shows
        shin = np.subtract(foot, knee) * 1.3 + knee  # ends below the hem, cut level there
        legs.append(_tapered([thigh, knee, shin], [92, 82, 76]))
    legs = [leg.intersection(box(0, 0, WIDTH, fy - 2)) for leg in legs]
    pelvis = _rounded(Polygon([(124, 300), (296, 300), (302, 428), (118, 428)]), 10)
    jeans = unary_union([pelvis, *legs])
    add(jeans, _JEANS)
    cuff = box(0, fy - 26, WIDTH, HEIGHT).intersection(jeans)
    add(cuff.buffer(_OUTLINE_WIDTH).intersection(jeans), _INK, False)
    add(cuff, _JEANS_DARK, outlined=False)
    add(_stroke([(210, 346), (210, 400)], 3.0), _INK, False)
    add(_both(_stroke(_arc(146, 336, 28, 28, 0, 90, 12), 3.0)), _INK, False)
    for y in (446, 490):  # creases at the knees
        add(_both(_stroke([(166, y), (152, y + 9)], 3.0)), _CREASE, False)

    # Arms and mitten hands (drawn for the right, mirrored for the left).
    shoulder, elbow, hand = (_joint(f"right_{j}") for j in ("shoulder", "elbow", "hand"))
    arm = _limb([(shoulder[0] + 12, shoulder[1] - 6), elbow, hand], 60)
    palm = _ellipse(hand[0] - 2, hand[1] + 2, 34, 33)
    thumb = _ellipse(hand[0] + 13, hand[1] - 23, 11, 15, angle=35)
    fingers = [_stroke(_arc(hand[0] - 2, hand[1] + 2, 22, 22, a, a + 40, 8), 2.5) for a in (110, 160)]
    for geometry, colour, outlined in [
        (arm, _SKIN, True),
        (unary_union([palm, thumb]), _SKIN, True),
        *((finger, _SKIN_SHADE, False) for finger in fingers),
    ]:
        add(_both(geometry), colour, outlined)

    # Striped shirt with short sleeves, tucked in under the belt; buttons down the front.
    cuff_at = (shoulder[0] + 0.5 * (elbow[0] - shoulder[0]), shoulder[1] + 0.5 * (elbow[1] - shoulder[1]))
    sleeve = _limb([(shoulder[0] + 16, shoulder[1] - 10), cuff_at], 70, cap="flat")
    torso = _rounded(Polygon([(138, 186), (282, 186), (296, 336), (124, 336)]), 20)
    shirt = unary_union([torso, _both(sleeve)])
    add(shirt, _SHIRT)
    stripes = unary_union([box(0, y, WIDTH, y + 12) for y in range(204, 330, 27)])
    add(stripes.intersection(shirt), _STRIPE, outlined=False)
    for y in (222, 258, 294):
        add(_ellipse(210, y, 7, 7), _WHITE)
        add(_ellipse(210, y, 1.8, 1.8), _INK, outlined=False)

    # Belt with loops and a buckle.
    body = unary_union([torso, pelvis])
    belt = box(0, 318, WIDTH, 343).intersection(body)
    add(belt.buffer(_OUTLINE_WIDTH).intersection(body.buffer(_OUTLINE_WIDTH)), _INK, False)
    add(belt, _BELT, outlined=False)
    for x in (156, 264):
        add(box(x - 4, 316, x + 4, 345), _BELT)
    add(_rounded(box(191, 312, 229, 349), 5), _GOLD)
    add(_rounded(box(201, 322, 219, 339), 2), _BELT)

    # Head, hair and face.
    head = _ellipse(210, 116, 110, 96)
    add(head, _SKIN)
    xs = np.linspace(100, 320, 55)
    fringe = 64 + 11 * np.abs(np.sin(np.pi * (xs - 100) / 55)) + 62 * ((xs - 210) / 110) ** 6
    cap = Polygon([(80, -10), *zip(xs, fringe, strict=True), (340, -10)])
    tuft = unary_union([_ellipse(197, 29, 12, 24, angle=-30), _ellipse(223, 30, 10, 20, angle=28)])
    hair = unary_union([head.intersection(cap), tuft.difference(_ellipse(210, 122, 96, 88))])
    add(hair, _HAIR)
    add(_stroke(_arc(210, 116, 86, 80, 215, 245, 10), 5.5), _HAIR_LIGHT, False)
    for x in (170, 250):
        add(_ellipse(x, 122, 20, 25), _WHITE)
        add(_ellipse(x + 1.5, 127, 11.5, 15), _INK, outlined=False)
        add(_ellipse(x + 5.5, 120, 4.6, 4.6), _WHITE, outlined=False)
    add(_both(_stroke(_arc(170, 104, 21, 13, 225, 315, 12), 5.0)), _INK, False)
    add(_both(_ellipse(136, 158, 17, 10)), _BLUSH, outlined=False)
    add(_ellipse(210, 147, 10, 8), _SKIN_SHADE, outlined=False)
    add(_stroke(_arc(210, 147, 10, 8, 20, 160, 10), 2.5), _INK, False)
    mouth = _ellipse(210, 161, 29, 23).intersection(box(0, 161, WIDTH, HEIGHT))
    add(mouth, _MOUTH)
    add(_ellipse(214, 180, 15, 9).intersection(mouth), _TONGUE, outlined=False)
    return parts


def _photograph(rgb, *, seed):
    """Light a flat image like a photographed page: a soft gradient, paper grain, noise."""
    rng = np.random.default_rng(seed)
    height, width = rgb.shape[:2]
    y, x = np.mgrid[0:height, 0:width].astype(np.float32)
    u, v = x / max(width - 1, 1), y / max(height - 1, 1)
    # Brightest near the top left; darker toward the bottom right and the corners.
    light = 1.0 - 0.06 * (0.6 * u + v) - 0.05 * ((u - 0.35) ** 2 + (v - 0.3) ** 2)
    sigma = max(height, width) / 150.0
    grain = ndi.gaussian_filter(rng.standard_normal((height, width)).astype(np.float32), sigma)
    grain *= 2.0 / max(float(grain.std()), 1e-6)
    noise = rng.normal(0.0, 1.8, size=(height, width, 3)).astype(np.float32)
    return rgb * light[..., None] + grain[..., None] + noise


__all__ = ["BACKGROUNDS", "HEIGHT", "JOINTS", "WIDTH", "sample_character", "sample_character_on"]
