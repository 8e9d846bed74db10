"""Scene elements: the 3D things a drawn character moves without anyone drawing them (section 3.5).

- :class:`Balloon`: a balloon on a string, the string's end held at a marker (the paper's fig. 11,
  attached to the single-point proxy of the wrist).
- :class:`Balls`: balls lying on the ground in a marker's path, kicked by the collision volumes
  (fig. 11's balls at the feet).
- :class:`Scarf`: a ribbon tied to a marker that trails behind it and drapes over the body
  (fig. 15's scarves at the wrists).
- :class:`Skirt`: strands hanging in a ring around a marker (the hips) that swing with it and are
  pushed aside by the legs (a grass skirt; the paper's cloth skirts of figs. 9 and 13 need cloth).
- :class:`Cape`: a sheet hanging from two markers (the shoulders) down the figure's back
  (the cloth of the paper's figs. 9 and 13, draped from the shoulders instead of the hips).
- :class:`Rain`: drops falling over the figure that bounce off it (fig. 12's rain), each sent
  back up when it reaches the ground.

Sizes not given follow the figure: its height (the skeleton proxy's largest vertical extent over
the clip) times the fractions below, so a scene looks the same on a child and on a giant, and on a
proxy whose units were guessed. A size given may be at most :data:`MAX_SIZE` figure heights
(:func:`toonmotion.scene.build.check_scene`). Colours are ``(r, g, b)`` bytes.
"""

from __future__ import annotations

from dataclasses import dataclass

from toonmotion.errors import SceneError

# Default sizes as fractions of the figure's height.
BALLOON_RADIUS = 0.07
STRING_LENGTH = 0.3
BALL_RADIUS = 0.05
SCARF_LENGTH = 0.4
SCARF_WIDTH = 0.05
SKIRT_LENGTH = 0.22
SKIRT_RADIUS = 0.1
SKIRT_WIDTH = 0.03
CAPE_LENGTH = 0.35
RAIN_RADIUS = 0.008
# The largest length or radius an element may be given, in figure heights: twelve times the largest
# default (the scarf's 0.4), room for any prop a figure holds or kicks, and already more than the
# camera, framed on the figure, shows; a string of a kilometre (issue 45) or a size in millimetres
# taken for metres is refused.
MAX_SIZE = 5.0


@dataclass(frozen=True)
class Balloon:
    """A lighter-than-air balloon on a string held at ``marker``.

    Attributes
    ----------
    marker : str
        The marker holding the string's end (a wrist, a hand).
    radius, string_length : float, optional
        Metres; default :data:`BALLOON_RADIUS` and :data:`STRING_LENGTH` of the figure's height.
    lift : float
        Upward pull as a multiple of the balloon's weight (1 floats, more rises); the string keeps
        it down.
    colour : (r, g, b)
    """

    marker: str
    radius: float | None = None
    string_length: float | None = None
    lift: float = 3.0
    colour: tuple[int, int, int] = (220, 40, 50)

    def __post_init__(self) -> None:
        _positive(self.radius, "a balloon's radius")
        _positive(self.string_length, "a balloon's string length")
        _positive(self.lift, "a balloon's lift")
        _colour(self.colour)


@dataclass(frozen=True)
class Balls:
    """``count`` balls lying on the ground where ``marker`` passes, to be kicked.

    They are placed on the marker's path over the ground (its point proxy dropped to Y = 0) at
    evenly spaced times, each moved out until it touches no collision volume in the first frame.

    Attributes
    ----------
    marker : str
        A marker near the ground (an ankle, a foot).
    count : int
    radius : float, optional
        Metres; default :data:`BALL_RADIUS` of the figure's height.
    colours : tuple of (r, g, b)
        Used in turn.
    """

    marker: str
    count: int = 3
    radius: float | None = None
    colours: tuple[tuple[int, int, int], ...] = ((250, 200, 40), (40, 150, 230), (60, 190, 90))

    def __post_init__(self) -> None:
        if isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 1:
            raise SceneError(f"a ball count must be a whole number, at least 1, got {self.count!r}")
        _positive(self.radius, "a ball's radius")
        if not self.colours:
            raise SceneError("balls need at least one colour")
        for colour in self.colours:
            _colour(colour)


@dataclass(frozen=True)
class Scarf:
    """A ribbon tied to ``marker``, hanging down at first.

    Attributes
    ----------
    marker : str
    length, width : float, optional
        Metres; default :data:`SCARF_LENGTH` and :data:`SCARF_WIDTH` of the figure's height.
    colour : (r, g, b)
    """

    marker: str
    length: float | None = None
    width: float | None = None
    colour: tuple[int, int, int] = (70, 100, 220)

    def __post_init__(self) -> None:
        _positive(self.length, "a scarf's length")
        _positive(self.width, "a scarf's width")
        _colour(self.colour)


@dataclass(frozen=True)
class Skirt:
    """``strands`` strands hanging in a ring around ``marker``.

    Attributes
    ----------
    marker : str
        The hips, say.
    strands : int
    length, radius, width : float, optional
        The strands' length, the ring's radius and a strand's width, metres; default
        :data:`SKIRT_LENGTH`, :data:`SKIRT_RADIUS` and :data:`SKIRT_WIDTH` of the figure's height.
    colour : (r, g, b)
    """

    marker: str
    strands: int = 16
    length: float | None = None
    radius: float | None = None
    width: float | None = None
    colour: tuple[int, int, int] = (230, 120, 170)

    def __post_init__(self) -> None:
        if isinstance(self.strands, bool) or not isinstance(self.strands, int) or self.strands < 1:
            raise SceneError(f"a skirt's strand count must be a whole number, at least 1, got "
                             f"{self.strands!r}")
        _positive(self.length, "a skirt's length")
        _positive(self.radius, "a skirt's radius")
        _positive(self.width, "a skirt's strand width")
        _colour(self.colour)


@dataclass(frozen=True)
class Cape:
    """A sheet of cloth hanging from ``left`` to ``right`` (the shoulders) down the figure's back.

    Its top edge runs between the two markers, just behind them, and follows them on every frame:
    it turns when the shoulders turn. "Behind" is the horizontal way of ``(right - left) x up``,
    so ``left`` is the figure's own left: a figure facing the camera has its left shoulder on the
    picture's right. Given the other way round, the cape hangs in front.

    Attributes
    ----------
    left, right : str
        The markers of the figure's left and right shoulders.
    length : float, optional
        Metres; default :data:`CAPE_LENGTH` of the figure's height. Its width is the shoulders'
        median distance over the clip.
    colour : (r, g, b)
    """

    left: str
    right: str
    length: float | None = None
    colour: tuple[int, int, int] = (150, 40, 60)

    def __post_init__(self) -> None:
        if self.left == self.right:
            raise SceneError(f"a cape hangs between two markers, got {self.left!r} twice")
        _positive(self.length, "a cape's length")
        _colour(self.colour)

    @property
    def marker(self) -> str:
        """The first of its two markers (every element names at least one)."""
        return self.left


@dataclass(frozen=True)
class Rain:
    """``count`` drops falling over the figure's whole path, from above its head.

    A drop that reaches the ground is sent back up to fall again, at a new place, so the rain
    keeps falling. Drops bounce off the body and the other elements, not off each other.

    Attributes
    ----------
    count : int
    radius : float, optional
        Metres; default :data:`RAIN_RADIUS` of the figure's height.
    seed : int
        Where the drops fall, reproducibly.
    colour : (r, g, b)
    """

    count: int = 80
    radius: float | None = None
    seed: int = 0
    colour: tuple[int, int, int] = (120, 170, 230)
    marker: None = None  # rain is held by nothing

    def __post_init__(self) -> None:
        if isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 1:
            raise SceneError(f"a rain's drop count must be a whole number, at least 1, got {self.count!r}")
        _positive(self.radius, "a drop's radius")
        _colour(self.colour)


Element = Balloon | Balls | Scarf | Skirt | Cape | Rain


def _positive(value, what):
    if value is None:
        return
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise SceneError(f"{what} must be a number, got {value!r}") from None
    if not (number > 0 and number < float("inf")):
        raise SceneError(f"{what} must be a positive, finite number, got {value!r}")


def _colour(colour):
    if len(colour) != 3 or any(isinstance(c, bool) or not isinstance(c, int) or not 0 <= c <= 255
                                for c in colour):
        raise SceneError(f"a colour must be three whole numbers 0-255, got {colour!r}")
