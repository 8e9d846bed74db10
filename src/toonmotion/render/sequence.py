"""Render an animation's frames in one view and write them as a GIF, an MP4 or PNG frames."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from toonmotion.animate.animation import Animation
from toonmotion.deform.depth import draw_order
from toonmotion.io.video import save_animation
from toonmotion.progress import Progress
from toonmotion.render.frame import check_overlays, fit_view, natural_size, render_frame
from toonmotion.render.raster import render_labels, view_transform
from toonmotion.rig.character import Character

Colour = tuple[int, int, int]
View = tuple[float, float, float, float]

WHITE = (255, 255, 255)


def animation_view(character: Character, animation: Animation) -> View:
    """One view holding the drawing's canvas and every frame's mesh, so the camera stays still."""
    return fit_view(character, [U for _, U in animation.meshes])


def frame_transform(character: Character, animation: Animation, *,
                    size: tuple[int, int] | None = None) -> tuple[float, NDArray[np.float64]]:
    """``(scale, offset)`` taking drawing points to the pixels of the frames :func:`write_animation`
    writes with this ``size``: ``frame point = scale * drawing point + offset``."""
    view = animation_view(character, animation)
    return view_transform(view, natural_size(view, size=size))


def animation_bones(character: Character, animation: Animation, *,
                    size: tuple[int, int] | None = None) -> Iterator[NDArray[np.int32]]:
    """Yield, per frame of ``animation``, which bone each pixel follows: ``(H, W)`` indices into
    ``character.skeleton.bones``, -1 off the figure.

    In the frames :func:`render_animation` makes with this ``size`` (same view, same draw
    order). A drawing pixel follows the bone of its nearest mesh vertex at rest.
    """
    from scipy.spatial import cKDTree

    mesh, binding = character.mesh, character.binding
    h, w = character.mask.shape
    rows, cols = np.mgrid[0:h, 0:w]
    _, nearest = cKDTree(mesh.V).query(np.stack([cols.ravel(), rows.ravel()], axis=1))
    at_rest = np.where(character.mask.ravel(), binding.bone[nearest], -1).reshape(h, w)
    view = animation_view(character, animation)
    out_size = natural_size(view, size=size)
    order = draw_order(mesh, binding, character.depth)
    for _, U in animation.meshes:
        yield render_labels(at_rest, mesh.V, U, mesh.F, size=out_size, view=view, order=order)


def render_animation(
    character: Character,
    animation: Animation,
    *,
    size: tuple[int, int] | None = None,
    background: Colour | None = None,
    overlays: Sequence[str] = (),
    view: View | None = None,
) -> Iterator[NDArray[np.uint8]]:
    """Yield every frame of ``animation`` as an ``(H, W, 4)`` uint8 RGBA picture.

    Every frame shares one view (default :func:`animation_view`) and one output size (default one
    output pixel per drawing pixel of the view). ``overlays`` are as for
    :func:`toonmotion.render.frame.render_frame`.
    """
    overlays = check_overlays(overlays)
    view = animation_view(character, animation) if view is None else view
    out_size = natural_size(view, size=size)
    order = draw_order(character.mesh, character.binding, character.depth)
    for frame, U in animation.meshes:
        posed = animation.motion.pose(frame) if overlays else None
        yield render_frame(character, U, pose=posed, size=out_size, view=view,
                           background=background, overlays=overlays, order=order)


def write_animation(path: str | Path, character: Character, animation: Animation, *,
                    size: tuple[int, int] | None = None, background: Colour | None = None,
                    overlays: Sequence[str] = (), progress: Progress | None = None
                    ) -> tuple[int, tuple[int, int]]:
    """Render ``animation`` and save it to ``path`` (``.gif``, ``.mp4``, a folder or a PNG pattern).

    Parameters
    ----------
    path : str or Path
        ``.gif``, ``.mp4``, ``.webm``, ``.webp``, ``.apng`` or ``.png`` (one animated PNG), a folder
        (numbered PNGs) or a pattern like ``f_%04d.png``; see :func:`toonmotion.io.video.save_animation`.
        Nothing is left half-written if rendering fails.
    character : Character
    animation : Animation
        From :func:`toonmotion.api.animate_character`; its fps is the file's.
    size : (int, int), optional
        ``(width, height)``; by default the view holding every frame, one pixel per drawing pixel.
    background : (int, int, int), optional
        An opaque RGB background. GIF and MP4 have no partial transparency: without one, their
        frames are composited over white.
    overlays : sequence of str, optional
        As for :func:`toonmotion.render.frame.render_frame`.
    progress : callable, optional
        ``progress("rendering", index, count)`` after each frame.

    Returns
    -------
    (int, (int, int))
        The frames written and their ``(width, height)``.

    Examples
    --------
    >>> import tempfile
    >>> from toonmotion.samples import sample_rig
    >>> from toonmotion.api import animate_character, rig_image
    >>> from toonmotion.sample_animation import sample_keyframes
    >>> hero = sample_rig()
    >>> animation = animate_character(hero, sample_keyframes(hero.skeleton, fps=4.0))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     count, size = write_animation(Path(folder) / "hop.gif", hero, animation, size=(80, 100))
    >>> count == len(animation.meshes), size
    (True, (80, 100))
    """
    view = animation_view(character, animation)
    out_size = natural_size(view, size=size)
    count = len(animation.meshes)

    def frames() -> Iterator[NDArray[np.uint8]]:
        pictures = render_animation(
            character, animation, size=out_size, background=background, overlays=overlays, view=view
        )
        for index, picture in enumerate(pictures, start=1):
            yield picture
            if progress is not None:
                progress("rendering", index, count)

    written = save_animation(
        path, frames(), fps=animation.motion.fps, background=background if background is not None else WHITE
    )
    return written, out_size
