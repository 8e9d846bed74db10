"""Simulated 3D elements around a 3D proxy, composited with the drawing in depth order (Jain et al.
2012, section 3.5): the calls behind ``scene`` (docs/scene3d.md)."""

from __future__ import annotations

from collections.abc import Iterator, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from toonmotion.animate.animation import Animation
from toonmotion.api.animation import motion_in_frames
from toonmotion.errors import SceneError
from toonmotion.io.frames import lay_on
from toonmotion.progress import Progress
from toonmotion.proxy3d.proxy import Proxy
from toonmotion.render.cloth import draw_cloth
from toonmotion.render.depth_composite import composite, drawing_alpha, drawn_depth
from toonmotion.render.sequence import animation_bones, render_animation
from toonmotion.render.zbuffer import (
    Layer,
    cast_primitives,
    checked_antialias,
    checked_frame,
    layer_passes,
    window_of,
)
from toonmotion.rig.character import Character
from toonmotion.scene.build import build_scene
from toonmotion.scene.elements import Element
from toonmotion.scene.simulate import SceneMotion, simulate

SHADINGS = ("toon", "smooth", "flat")
STRING_MIN_PX = 1.5  # the narrowest a string is drawn, pixels: a line, not dashes
ANTIALIAS = 2  # rays per pixel side in the composited frames and passes (see render_elements)
# A ball inside a limb's volume by more than this share of its radius is worth a warning: the demo's
# balls go 6 mm into 80 mm balls, a leg sweeping at 30 m/s takes a 45 mm ball 24 mm in.
SINK_SHARE = 0.5


def simulate_scene(proxy: Proxy, elements: Sequence[Element], *,
                   progress: Progress | None = None) -> SceneMotion:
    """Simulate scene elements driven by a proxy, one state per drawn frame (MuJoCo).

    The proxy's collision volumes (tapered cylinders and joint spheres; default ones when it was
    lifted without drawn frames) move as it moves and push what they touch; strings are held at
    their markers' points.

    Parameters
    ----------
    proxy : Proxy
        From :func:`toonmotion.api.lift_proxy` or a proxy file.
    elements : sequence of Balloon, Balls, Scarf, Skirt, Cape or Rain
        :mod:`toonmotion.scene.elements`.
    progress : callable, optional
        ``progress("simulate", done, total)``.

    Returns
    -------
    SceneMotion
        The elements as spheres and capsules per frame.

    Raises
    ------
    SceneError
        An element held at a marker the proxy lacks, or given a size over
        :data:`~toonmotion.scene.elements.MAX_SIZE` times the figure's height.
    LimitError
        More bodies (drops, balls, links of strings, scarves and strands) than the limit
        ``scene_bodies``; refused before anything is built.

    Examples
    --------
    A still figure with a ball at its foot: the ball stays where it lies.

    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> from toonmotion.scene.elements import Balls
    >>> cam = PerspectiveCamera(500.0, 160, 120, [[0, 0, 0, 0, 1, 5]] * 6)
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 0.1, 0]]] * 6)
    >>> proxy = Proxy(("hip", "foot"), [-1, 0], 12, cam, pts, None, pts, [[0.0, -0.9, 0]],
    ...               [[[0.0, 0, 0, 1]]] * 6)
    >>> motion = simulate_scene(proxy, [Balls("foot", count=1)])
    >>> float(np.abs(motion.balls[-1] - motion.balls[0]).max()) < 1e-3
    True
    """
    return simulate(build_scene(proxy, list(elements)), proxy, progress=progress)


def render_elements(proxy: Proxy, motion: SceneMotion, frame: int, *, shading: str = "toon",
                    antialias: int = ANTIALIAS) -> Layer:
    """The elements seen from the proxy's camera on one frame: colour, depth and occlusion maps.

    The proxy itself is not drawn.

    Parameters
    ----------
    proxy : Proxy
    motion : SceneMotion
        From :func:`simulate_scene`.
    frame : int
    shading : str
        ``"toon"`` (Lambert light in three bands, to sit with a drawing), ``"smooth"`` or
        ``"flat"``.
    antialias : int
        Rays per pixel side, 1 (one ray a pixel: hard edges) to 4: ``k x k`` rays a pixel, their
        fraction that hit is the layer's ``alpha`` and edges are blended. The default, 2, takes
        about twice the time of one ray a pixel (the demo: 3.0 -> 7.4 ms a 640 x 480 frame).

    Returns
    -------
    Layer
        :class:`toonmotion.render.zbuffer.Layer`: ``colour``, ``depth`` (metres along the camera's
        axis, ``inf`` where nothing is seen), ``coverage`` (the occlusion map), ``ids`` (spheres,
        then capsules, then cloth triangles: :func:`toonmotion.render.cloth.render_cloth`) and
        ``alpha`` (the fraction of each pixel covered).

    Raises
    ------
    SceneError
        An unknown shading, a frame the proxy does not have, an ``antialias`` out of range.

    Examples
    --------
    A ball on the ground 5 m in front of a camera half a metre up:

    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> from toonmotion.scene.elements import Balls
    >>> cam = PerspectiveCamera(500.0, 160, 120, [[0, 0, 0, 0, 0.5, 5]] * 2)
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 0.1, 0]]] * 2)
    >>> proxy = Proxy(("hip", "foot"), [-1, 0], 12, cam, pts, None, pts, [[0.0, -0.9, 0]],
    ...               [[[0.0, 0, 0, 1]]] * 2)
    >>> layer = render_elements(proxy, simulate_scene(proxy, [Balls("foot", count=1)]), 1)
    >>> bool(layer.coverage.any()), bool(4.8 < layer.depth[layer.coverage].min() < 5.2)
    (True, True)
    """
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}, got {shading!r}")
    camera = proxy.camera
    t = checked_frame(camera, frame)
    spheres, strings = motion.spheres[t], _drawn_strings(proxy, motion.capsules[t], t)
    cloth = motion.cloth_vertices[t] if len(motion.cloth_triangles) else None
    # Rays only where an element may be seen: the spheres', capsules' and cloth's box on the picture.
    window = window_of(camera, t, spheres=spheres, capsules=strings, points=cloth)
    rays = cast_primitives(camera, t, spheres=spheres, capsules=strings, colours=motion.colours,
                           shading=shading, antialias=antialias, window=window)
    if cloth is not None:
        draw_cloth(rays, camera, t, cloth, motion.cloth_triangles, motion.cloth_colours, shading=shading,
                   first_id=motion.spheres.shape[1] + motion.capsules.shape[1])
    return rays.layer()


def _drawn_strings(proxy: Proxy, capsules: NDArray[np.float64], frame: int) -> NDArray[np.float64]:
    """The strings' capsules at least :data:`STRING_MIN_PX` across on the picture: a string a few
    millimetres thick is thinner than a pixel a few metres away, and one ray a pixel caught it on
    some pixels and not others, a dashed line."""
    C = np.array(capsules, dtype=np.float64).reshape(-1, 7)
    if not len(C):
        return C
    camera = proxy.camera
    depth = ((C[:, 0:3] + C[:, 3:6]) / 2 - camera.centres[frame]) @ camera.rotations[frame][2]
    least = STRING_MIN_PX / 2 * np.maximum(depth, 0.0) / camera.focal  # metres at that depth
    C[:, 6] = np.maximum(C[:, 6], least)
    return C


def composite_scene(proxy: Proxy, frames: ArrayLike, motion: SceneMotion, *, shading: str = "toon",
                    background: tuple[int, int, int] = (255, 255, 255), limbs: ArrayLike | None = None,
                    progress: Progress | None = None, antialias: int = ANTIALIAS
                    ) -> Iterator[NDArray[np.uint8]]:
    """The drawn frames with the simulated elements, in depth order (eq. 23-26), frame by frame.

    Parameters
    ----------
    proxy : Proxy
    frames : (T, H, W, 3 or 4) uint8
        The drawn frames, as many as the proxy's and of its camera's size. With an alpha channel
        (transparent PNGs), the figure is where it is not transparent; otherwise they are taken as
        line art on white (:func:`toonmotion.render.depth_composite.drawing_alpha`).
    motion : SceneMotion
        From :func:`simulate_scene`.
    shading : str
        As :func:`render_elements`.
    background : (r, g, b)
        What transparent drawn frames are laid on.
    limbs : (T, H, W) int, optional
        Which of the proxy's limbs each pixel of the figure belongs to (-1: the nearest limb in
        the picture), as :func:`animation_frames` gives for a rigged character.
    progress : callable, optional
        ``progress("composite", done, total)``.
    antialias : int
        Rays per pixel side, as :func:`render_elements`.

    Returns
    -------
    iterator of (H, W, 3) uint8
        Each composited frame, made as it is asked for. Where no element is seen, the drawing
        (laid on ``background`` if it is transparent) is kept bit for bit.

    Raises
    ------
    SceneError
        Frames whose count or size differ from the proxy's, an unknown shading or an ``antialias``
        out of range (at the call, before any frame is made).

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> cam = PerspectiveCamera(500.0, 160, 120, [[0, 0, 0, 0, 1, 5]] * 2)
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 0.1, 0]]] * 2)
    >>> proxy = Proxy(("hip", "foot"), [-1, 0], 12, cam, pts, None, pts, [[0.0, -0.9, 0]],
    ...               [[[0.0, 0, 0, 1]]] * 2)
    >>> drawing = np.full((2, 120, 160, 3), 255, np.uint8)
    >>> out = list(composite_scene(proxy, drawing, simulate_scene(proxy, [])))
    >>> all(np.array_equal(o, d) for o, d in zip(out, drawing))
    True
    """
    pictures = check_frames(proxy, frames)
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}, got {shading!r}")
    labels = None if limbs is None else np.asarray(limbs)
    if labels is not None and labels.shape != pictures.shape[:3]:
        raise SceneError(f"the limb labels must be one per pixel of every frame, {pictures.shape[:3]}, got "
                         f"{labels.shape}")
    checked_antialias(antialias)
    return _composited(proxy, pictures, motion, shading, background, labels, progress, antialias)


def _composited(proxy, pictures, motion, shading, background, labels, progress, antialias):
    T = proxy.frame_count
    pixels = proxy.camera.project(proxy.points)
    depths = proxy.camera.depth(proxy.points)
    for t in range(T):
        layer = render_elements(proxy, motion, t, shading=shading, antialias=antialias)
        alpha, figure = drawing_alpha(pictures[t])
        # The drawing's depth matters only where an element is seen over the figure.
        drawn = drawn_depth(np.where(layer.coverage, figure, 0.0), pixels[t], depths[t], proxy.limbs,
                            labels=None if labels is None else labels[t])
        yield composite(lay_on(pictures[t], background), layer, drawn, alpha=alpha, figure=figure)
        if progress is not None:
            progress("composite", t + 1, T)


def scene_warnings(motion: SceneMotion) -> list[str]:
    """One-line warnings about a simulated scene that deserves a second look.

    - balls sank into the proxy's volumes deeper than :data:`SINK_SHARE` of their radius: the
      volumes swept through them faster than contact pushes them out (limbs much wider or faster
      than a figure's; a lift that warned of a poor fit gives such volumes).

    Parameters
    ----------
    motion : SceneMotion
        From :func:`simulate_scene`.

    Returns
    -------
    list of str
        One line each, none when the scene looks sound.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> sunk = SimpleNamespace(balls=np.full((2, 1, 4), 0.05), deepest=0.04)
    >>> scene_warnings(sunk)  # doctest: +ELLIPSIS
    ["balls sank up to 40 mm into the proxy's volumes, more than 50% of their radius (50 mm): ..."]
    >>> scene_warnings(SimpleNamespace(balls=np.full((2, 1, 4), 0.05), deepest=0.002))
    []
    """
    warnings = []
    radius = float(motion.balls[..., 3].min()) if motion.balls.shape[1] else np.inf
    if motion.deepest > SINK_SHARE * radius:
        warnings.append(
            f"balls sank up to {motion.deepest * 1000:.0f} mm into the proxy's volumes, more than "
            f"{SINK_SHARE:.0%} of their radius ({radius * 1000:.0f} mm): its limbs sweep through them faster "
            "than contact pushes them out; check the lift's warnings (volumes far wider or faster than "
            "the drawing's limbs) or give the balls elsewhere")
    return warnings


def check_frames(proxy: Proxy, frames: ArrayLike) -> NDArray[np.uint8]:
    """The drawn frames as an array, checked against the proxy's frame count and image size."""
    pictures = np.asarray(frames)
    if pictures.ndim != 4 or pictures.shape[3] not in (3, 4) or pictures.dtype != np.uint8:
        raise SceneError(f"drawn frames must be (frames, height, width, 3 or 4) bytes, got {pictures.shape} "
                         f"{pictures.dtype}")
    if len(pictures) != proxy.frame_count:
        raise SceneError(f"the drawing has {len(pictures)} frames but the proxy {proxy.frame_count}; "
                         "give the frames the proxy was lifted from")
    H, W = pictures.shape[1:3]
    cam = proxy.camera
    if (W, H) != (cam.width, cam.height):
        raise SceneError(f"the frames are {W}x{H} pixels but the proxy's camera sees "
                         f"{cam.width}x{cam.height}; give the frames the proxy was lifted from")
    return pictures


def animation_frames(character: Character, animation: Animation,
                     proxy: Proxy) -> tuple[NDArray[np.uint8], NDArray[np.int32]]:
    """A rigged character's animation as the frames to composite, and each pixel's proxy limb.

    The frames are rendered as ``animate`` writes them at the proxy camera's size, transparent
    around the figure. Each figure pixel's limb is the proxy limb that ends at the child joint of
    the bone the pixel follows (a bone whose joint the proxy lacks gives -1: the nearest limb).

    Parameters
    ----------
    character : Character
    animation : Animation
        From :func:`toonmotion.api.animate_character`: the one the proxy was lifted from
        (its joints in the frames, :func:`toonmotion.api.motion_in_frames`).
    proxy : Proxy

    Returns
    -------
    frames : (T, H, W, 4) uint8
    limbs : (T, H, W) int32

    Raises
    ------
    SceneError
        The animation's frame count, or its joints in the frames, differ from the proxy's (it was
        lifted from another animation or at another size).

    Examples
    --------
    See :func:`composite_scene`; ``tests/scene/test_scene.py`` runs it on the bundled character.
    """
    cam = proxy.camera
    size = (cam.width, cam.height)
    if len(animation.meshes) != proxy.frame_count:
        raise SceneError(f"the animation has {len(animation.meshes)} frames but the proxy "
                         f"{proxy.frame_count}; give the key-frames the proxy was lifted from")
    _check_lifted_from(proxy, motion_in_frames(character, animation, size=size))
    skeleton = character.skeleton
    ends = {name: k for k, name in enumerate(proxy.names[c] for c in proxy.limbs[:, 1])}
    to_limb = np.array([ends.get(skeleton.names[c], -1) for _, c in skeleton.bones] + [-1], np.int32)
    frames = np.stack(list(render_animation(character, animation, size=size)))
    limbs = np.stack([to_limb[bones] for bones in animation_bones(character, animation, size=size)])
    return frames, limbs


def _check_lifted_from(proxy, seen):
    """Refuse an animation whose joints, in its frames, are not where the proxy's markers are."""
    shared = [n for n in proxy.names if n in seen.skeleton.names]
    if not shared:
        raise SceneError("the animation's joints share no name with the proxy's markers; give the "
                         "animation the proxy was lifted from")
    ours = proxy.camera.project(proxy.points)[:, [proxy.names.index(n) for n in shared]]
    theirs = seen.positions[:, [seen.skeleton.names.index(n) for n in shared]]
    off = float(np.abs(ours - theirs).max())
    if off > 1.0:
        raise SceneError(f"the animation's joints are up to {off:.0f} px from the proxy's markers; lift the "
                         "proxy from this animation's frames (animate --save-frame-motion) at the same size")


def scene_passes(proxy: Proxy, motion: SceneMotion, *, shading: str = "toon", antialias: int = ANTIALIAS
                 ) -> Iterator[tuple[NDArray[np.uint8], NDArray[np.uint16], NDArray[np.uint8]]]:
    """The elements' beauty, depth and occlusion passes per frame, for compositing elsewhere.

    Parameters
    ----------
    proxy : Proxy
    motion : SceneMotion
        From :func:`simulate_scene`.
    shading : str
        As :func:`render_elements`.
    antialias : int
        Rays per pixel side, as :func:`render_elements`.

    Returns
    -------
    iterator of (beauty, depth, occlusion)
        Per frame :func:`toonmotion.render.zbuffer.layer_passes`: RGBA (its alpha the fraction of
        the pixel covered), depth in millimetres (16 bits; 0 where nothing is seen) and the
        coverage as a 0-255 matte.

    Examples
    --------
    >>> from toonmotion.proxy3d.camera import PerspectiveCamera
    >>> from toonmotion.scene.elements import Balls
    >>> cam = PerspectiveCamera(500.0, 160, 120, [[0, 0, 0, 0, 0.5, 5]] * 2)
    >>> pts = np.array([[[0.0, 1, 0], [0.0, 0.1, 0]]] * 2)
    >>> proxy = Proxy(("hip", "foot"), [-1, 0], 12, cam, pts, None, pts, [[0.0, -0.9, 0]],
    ...               [[[0.0, 0, 0, 1]]] * 2)
    >>> beauty, depth, seen = next(scene_passes(proxy, simulate_scene(proxy, [Balls("foot", count=1)])))
    >>> bool((seen > 0).any()), bool(4800 < depth[seen > 0].min() < 5200)
    (True, True)
    """
    if shading not in SHADINGS:
        raise SceneError(f"shading must be one of {', '.join(SHADINGS)}, got {shading!r}")
    checked_antialias(antialias)
    frames = range(proxy.frame_count)
    return (layer_passes(render_elements(proxy, motion, t, shading=shading, antialias=antialias))
            for t in frames)
