"""Overview picture of a rigged character, for checking a rig at a glance.

Left panel: the drawing with its silhouette, the curve skeleton and the suggested joints (end
points green, junctions blue, along long branches orange). Right panel: the mesh coloured by
decomposition (each bone's interior triangles in its colour, joint triangles pale with the
joint vertices as dots, vertices that could reach no bone without crossing the outline in
red) under the animation skeleton.
"""

from __future__ import annotations

import colorsys

import numpy as np
from numpy.typing import NDArray
from PIL import Image, ImageDraw, ImageFont

from toonmotion.render.raster import check_canvas
from toonmotion.rig.binding import JOINT
from toonmotion.rig.character import Character
from toonmotion.shape.curve_skeleton import joint_suggestions

_SUPERSAMPLE = 2
_SUGGESTION_COLOURS = {
    "end": (40, 160, 60),
    "junction": (40, 90, 220),
    "along": (245, 140, 20),
    "loop": (200, 40, 200),
    "point": (0, 0, 0),
}


def bone_colours(count: int) -> NDArray[np.uint8]:
    """``count`` distinct, saturated RGB colours (golden-ratio hues), ``(count, 3)`` uint8."""
    hues = (np.arange(count) * 0.618033988749895) % 1.0
    return np.array(
        [[round(255 * c) for c in colorsys.hsv_to_rgb(h, 0.65, 0.92)] for h in hues],
        dtype=np.uint8,
    ).reshape(-1, 3)


def render_overview(character: Character, *, height: int = 720) -> Image.Image:
    """Draw the two-panel overview of a rigged character.

    Parameters
    ----------
    character : Character
    height : int
        Height in pixels of each panel's drawing area.

    Returns
    -------
    PIL.Image.Image
        RGB.
    """
    w, h = character.size
    scale = height / h
    # The limit is on the picture written; its panels are drawn at twice the size, then shrunk.
    check_canvas(2 * w * scale + 30, height * 1.1, why="choose a smaller height")
    left = _panel_curve_skeleton(character, scale)
    right = _panel_rig(character, scale)
    title_h = max(28, height // 22)
    out = Image.new("RGB", (left.width + right.width + 30, left.height + title_h + 10), "white")
    out.paste(left, (10, title_h))
    out.paste(right, (20 + left.width, title_h))
    draw = ImageDraw.Draw(out)
    font = _font(title_h * 0.6)
    draw.text((10, 4), "silhouette + curve skeleton", fill=(20, 20, 20), font=font)
    mesh, skel = character.mesh, character.skeleton
    fallback = int(character.binding.fallback.sum())
    caption = (
        f"mesh {len(mesh.V)} vertices, {len(mesh.F)} triangles, h={mesh.spacing:.1f}px; "
        f"{len(skel)} joints" + (f"; {fallback} fallback" if fallback else "")
    )
    draw.text((20 + left.width, 4), caption, fill=(20, 20, 20), font=font)
    return out


def _canvas(character, scale, fade):
    """The drawing, scaled by ``scale * _SUPERSAMPLE``, faded towards white, on white."""
    s = scale * _SUPERSAMPLE
    w, h = character.size
    size = (max(1, round(w * s)), max(1, round(h * s)))
    rgba = Image.fromarray(character.texture).resize(size, Image.Resampling.BILINEAR)
    base = Image.new("RGBA", size, (255, 255, 255, 255))
    base.alpha_composite(rgba)
    faded = Image.blend(base, Image.new("RGBA", size, (255, 255, 255, 255)), fade)
    return faded.convert("RGB"), s


def _finish(image):
    return image.resize(
        (image.width // _SUPERSAMPLE, image.height // _SUPERSAMPLE), Image.Resampling.LANCZOS
    )


def _xy(points, s):
    return [(float(x) * s, float(y) * s) for x, y in np.asarray(points)]


def _panel_curve_skeleton(character, scale):
    image, s = _canvas(character, scale, fade=0.45)
    draw = ImageDraw.Draw(image)
    line = max(2, round(1.5 * _SUPERSAMPLE))
    for loop in character.silhouette.loops:
        pts = _xy(loop, s)
        draw.line(pts + pts[:1], fill=(30, 30, 120), width=line)
    for path in character.curve_skeleton.paths:
        draw.line(_xy(path, s), fill=(220, 30, 30), width=line + 1, joint="curve")
    if len(character.curve_skeleton.nodes):
        points, kinds = joint_suggestions(character.curve_skeleton)
        r = 4.5 * _SUPERSAMPLE
        for (x, y), kind in zip(_xy(points, s), kinds, strict=True):
            draw.ellipse([x - r, y - r, x + r, y + r], fill=_SUGGESTION_COLOURS[kind],
                         outline="white", width=_SUPERSAMPLE)
    return _finish(image)


def _panel_rig(character, scale):
    image, s = _canvas(character, scale, fade=0.75)
    mesh, binding, skeleton = character.mesh, character.binding, character.skeleton
    colours = bone_colours(len(skeleton.bones))
    overlay = Image.new("RGBA", image.size, (0, 0, 0, 0))
    draw = ImageDraw.Draw(overlay)
    V = mesh.V * s
    for f, is_joint in zip(mesh.F, binding.joint_triangle, strict=True):
        c = colours[binding.bone[f[0]]]
        fill = (230, 230, 230, 150) if is_joint else (*map(int, c), 150)
        draw.polygon([tuple(V[i]) for i in f], fill=fill, outline=(90, 90, 90, 170))
    image = Image.alpha_composite(image.convert("RGBA"), overlay).convert("RGB")
    draw = ImageDraw.Draw(image)
    r = 1.6 * _SUPERSAMPLE
    for i in np.flatnonzero(binding.vertex_kind == JOINT):
        x, y = V[i]
        c = tuple(int(v) for v in colours[binding.bone[i]])
        draw.ellipse([x - r, y - r, x + r, y + r], fill=c)
    for i in np.flatnonzero(binding.fallback):
        x, y = V[i]
        draw.ellipse([x - 2 * r, y - 2 * r, x + 2 * r, y + 2 * r], outline=(230, 0, 0),
                     width=_SUPERSAMPLE)
    P = skeleton.positions * s
    for k, (a, b) in enumerate(skeleton.bones):
        c = tuple(int(v) for v in colours[k])
        draw.line([tuple(P[a]), tuple(P[b])], fill=(20, 20, 20), width=7 * _SUPERSAMPLE // 2)
        draw.line([tuple(P[a]), tuple(P[b])], fill=c, width=3 * _SUPERSAMPLE // 2)
    rj = 4 * _SUPERSAMPLE
    for x, y in P:
        draw.ellipse([x - rj, y - rj, x + rj, y + rj], fill="white", outline=(20, 20, 20),
                     width=_SUPERSAMPLE)
    return _finish(image)


def _font(size):
    try:
        return ImageFont.load_default(size=max(10, int(size)))
    except TypeError:  # Pillow < 10.1 has only the fixed bitmap font
        return ImageFont.load_default()
