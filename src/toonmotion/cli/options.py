"""Options several commands share, the parsing of option text into values, and progress bars."""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated, Any, TypeVar

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

from toonmotion.animate.cartoon_filter import FilterSettings
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import SettingsError
from toonmotion.render.frame import check_overlays
from toonmotion.render.raster import check_canvas

err = Console(stderr=True)

# DeformSettings' own default, shown by --help.
DEFAULT_JOINT_ANCHOR = DeformSettings.joint_anchor

Project = Annotated[Path, typer.Argument(help="Project folder made by 'toonmotion rig'.")]
Size = Annotated[str | None, typer.Option("--size", help="Output WxH pixels \\[default: the view at 1:1].")]
Overlay = Annotated[str, typer.Option("--overlay", help="Comma list of mesh, skeleton, rest.")]
NoArea = Annotated[bool, typer.Option(
    "--no-area", help="Do not preserve area: needles keep their length when bones stretch and the figure's "
    "area is not held.")]
StageOne = Annotated[bool, typer.Option("--stage-one", help="Needle model only, no joint-area solve.")]
Weights = Annotated[str, typer.Option("--weights", help="Stage-two weights w1,w2,w3.")]
Skinning = Annotated[str, typer.Option(
    "--skinning", help="one-bone (each part follows its own bone, the thesis) or weights (a few bones' "
    "needles blended by smooth heat-diffusion weights: joints bend round).")]
JointWidth = Annotated[
    float, typer.Option("--joint-width", help="Joint-area size, in limb half-thicknesses.", min=0)
]
JointAnchor = Annotated[float, typer.Option(
    "--joint-anchor", help="How firmly the drawing is held at each joint where the skeleton puts it "
    "(0: the thesis, whose joint areas can settle away from the joints).", min=0)]
Strength = Annotated[
    float, typer.Option("--strength", help="Filter strength A (0 leaves the motion as it is).")
]
Sigma = Annotated[float, typer.Option("--sigma", help="Filter width in frames.")]
KeysFile = Annotated[Path, typer.Argument(
    metavar="KEYS.json", help="Key-frames (poses at frame numbers) or a motion (a pose per frame).")]
Fps = Annotated[float | None, typer.Option(
    "--fps", help="Frames per second \\[default: the file's, else 24].")]
Ease = Annotated[str | None, typer.Option(
    "--ease", help="linear, in-out, in or out \\[default: the key file's].")]
Exaggerate = Annotated[float | None, typer.Option(
    "--exaggerate", help="Cartoon filter strength A: anticipation and follow-through.")]
SolveInbetweens = Annotated[bool, typer.Option(
    "--solve-inbetweens", help="Run stage two on every frame, not only the keys.")]
Shift = Annotated[float, typer.Option("--shift", help="Filter time shift in frames (> 0 delays it).")]
AnimationOutput = Annotated[
    Path,
    typer.Option(
        "-o", "--output", help="OUT.gif, OUT.mp4, a folder (or frame_%04d.png pattern) for PNGs, or a "
        "transparent OUT.apng (or .png), OUT.webp or OUT.webm."
    ),
]
AnimationBackground = Annotated[
    str | None,
    typer.Option(
        "--background", help="transparent, white, black or #rrggbb \\[default: white; transparent for PNGs, "
        "APNG, WebP and WebM]."
    ),
]

Report = Callable[[str, int, int], None]


Command = TypeVar("Command", bound=Callable[..., Any])
# The placeholder default of a command's ``deform`` parameter, which deform_options fills in.
DEFAULT_DEFORM = DeformSettings()

# The deformation's options, which every command that deforms the drawing takes: (parameter, its
# typer option, its default, from DeformSettings' own where it has one).
_DEFORM_OPTIONS = (
    ("no_area", NoArea, not DeformSettings.preserve_area),
    ("stage_one_only", StageOne, not DeformSettings.stage_two),
    ("weights", Weights, ",".join(f"{w:g}" for w in DeformSettings.weights)),
    ("joint_width", JointWidth, DeformSettings.joint_width),
    ("joint_anchor", JointAnchor, DeformSettings.joint_anchor),
    ("skinning", Skinning, DeformSettings.skinning),
)


def deform_options(command: Command) -> Command:
    """Give a command the deformation's options (``--no-area``, ``--stage-one``, ``--weights``,
    ``--joint-width``, ``--joint-anchor``, ``--skinning``), after its own; it receives them as one
    ``deform`` argument, a :class:`DeformSettings` (put this decorator under ``@app.command``).

    Refused values raise :class:`SettingsError` when the command runs, as the command's own would.
    """
    signature = inspect.signature(command, eval_str=True)
    own = [p for p in signature.parameters.values() if p.name != "deform"]
    added = [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, annotation=kind, default=default)
             for name, kind, default in _DEFORM_OPTIONS]

    @functools.wraps(command)
    def run(*args: Any, **kwargs: Any) -> Any:
        given = {name: kwargs.pop(name) for name, _, _ in _DEFORM_OPTIONS}
        return command(*args, deform=deform_settings(**given), **kwargs)

    run.__signature__ = signature.replace(parameters=[*own, *added])  # type: ignore[attr-defined]
    run.__annotations__ = {p.name: p.annotation for p in [*own, *added]}
    del run.__wrapped__  # typer reads the signature above, not the command's
    return run  # type: ignore[return-value]


def deform_settings(no_area: bool, stage_one_only: bool, weights: str, joint_width: float,
                    skinning: str = "one-bone", joint_anchor: float = DEFAULT_JOINT_ANCHOR) -> DeformSettings:
    """The deformation's options as settings (:func:`deform_options`)."""
    return DeformSettings(
        preserve_area=not no_area,
        stage_two=not stage_one_only,
        weights=numbers(weights, 3, "--weights"),
        joint_width=joint_width,
        skinning=skinning,
        joint_anchor=joint_anchor,
    )


def filter_settings(strength: float | None, sigma: float, shift: float) -> FilterSettings | None:
    """The cartoon filter's settings, or None when no (or a zero) strength is given.

    The width and shift are checked either way: a bad value is refused, not silently unused.
    """
    settings = FilterSettings(strength=strength or 0.0, sigma=sigma, shift=shift)
    return settings if strength else None


def numbers(text: str, count: int, option: str) -> tuple[float, ...]:
    """``count`` finite comma-separated numbers."""
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != count or not all(np.isfinite(values)):
        raise SettingsError(f"{option} takes {count} comma-separated numbers, got {text!r}")
    return values


def point(text: str, option: str) -> tuple[float, float]:
    x, y = numbers(text, 2, option)
    return x, y


def names(text: str) -> tuple[str, ...]:
    """Comma-separated joint names, at least one."""
    found = tuple(n.strip() for n in text.split(",") if n.strip())
    if not found:
        raise SettingsError(f"give one or more joint names separated by commas, got {text!r}")
    return found


def named_point(text: str, option: str) -> tuple[str, tuple[float, float]]:
    """``NAME=X,Y``."""
    name, sep, rest = text.partition("=")
    if not sep or not name.strip():
        raise SettingsError(f"{option} takes NAME=X,Y, got {text!r}")
    return name.strip(), point(rest, f"{option} {name.strip()}=X,Y")


def size(text: str | None) -> tuple[int, int] | None:
    """``WxH`` in pixels, each 1 to 16384, within the picture limits (checked at once: a command
    gives it before its work, not after)."""
    if text is None:
        return None
    w, _, h = text.lower().partition("x")
    try:
        wh = int(w), int(h)
    except ValueError:
        wh = (0, 0)
    if min(wh) < 1 or max(wh) > 16384:
        raise SettingsError(f"--size takes WxH in pixels, each 1 to 16384, e.g. 1024x1024; got {text!r}")
    check_canvas(*wh, why="give a smaller --size")
    return wh


def colour(text: str) -> tuple[int, int, int] | None:
    """``transparent`` (None), ``white``, ``black`` or ``#rrggbb``."""
    named: dict[str, tuple[int, int, int] | None] = {
        "transparent": None,
        "white": (255, 255, 255),
        "black": (0, 0, 0),
    }
    if text.lower() in named:
        return named[text.lower()]
    hexa = text.lstrip("#")
    if len(hexa) == 6:
        try:
            r, g, b = (int(hexa[i : i + 2], 16) for i in (0, 2, 4))
            return r, g, b
        except ValueError:
            pass
    raise SettingsError(f"--background takes transparent, white, black or #rrggbb, got {text!r}")


def overlays(text: str) -> tuple[str, ...]:
    return check_overlays(o.strip() for o in text.split(",") if o.strip())


def suffix(path: Path, wanted: str | tuple[str, ...], what: str, *, why: str = "") -> None:
    """Refuse a file whose name does not end in ``wanted`` (e.g. ``".png"``); ``why`` leads the message."""
    endings = (wanted,) if isinstance(wanted, str) else wanted
    if path.suffix.lower() not in endings:
        raise SettingsError(f"{why}give {what} ending in {' or '.join(endings)}, not {path.name}")


@contextmanager
def progress(description: str) -> Iterator[Report]:
    """A progress bar on a terminal's stderr (nothing otherwise), fed by ``report(stage, index, count)``."""
    bar = Progress(
        TextColumn("{task.description:<15}"),
        BarColumn(),
        TimeElapsedColumn(),
        console=err,
        transient=True,
        disable=not err.is_terminal,
    )
    with bar:
        task = bar.add_task(description, total=None)

        def report(stage: str, index: int, count: int) -> None:
            bar.update(task, completed=index, total=count, description=stage)

        yield report


def warn(message: str) -> None:
    typer.echo(message, err=True)
