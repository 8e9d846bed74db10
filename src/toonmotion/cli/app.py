"""The Typer application the command modules register on, and the entry point that runs it.

Every error the user can fix prints one line, ``toonmotion: error: ...``, and exits with status
2: the library's :class:`~toonmotion.errors.ToonmotionError`, an unwritable output, and the option
parser's own complaints (a missing argument, a value out of range), which Click would otherwise
draw as a multi-line box.
"""

from __future__ import annotations

import os
import re
import sys
import traceback
import warnings
from pathlib import Path
from typing import Annotated, NoReturn

import typer

from toonmotion import __version__, limits
from toonmotion.errors import LimitError, ToonmotionError

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="toonmotion: 2D character animation from one drawing.",
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"toonmotion {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    version: Annotated[bool, typer.Option("--version", callback=_version, is_eager=True,
                                          help="Print the version.")] = False,
    limit: Annotated[list[str] | None, typer.Option(
        "--limit", metavar="NAME=N",
        help=f"Raise (or lower) a resource limit for this run; repeatable. Limits: {', '.join(limits.NAMES)}"
        " (see docs/limits.md).",
    )] = None,
) -> None:
    """toonmotion: 2D character animation from one drawing."""
    limits.set_limits(limits.replaced(limits.Limits(), dict(_limit(text) for text in limit or ())))


def _limit(text: str) -> tuple[str, float]:
    """``NAME=N`` from ``--limit``."""
    name, sep, value = text.partition("=")
    try:
        number = float(value)
    except ValueError:
        sep = ""
    if not sep:
        raise LimitError(f"--limit takes NAME=N, e.g. --limit canvas_pixels=100000000; got {text!r}")
    return name.strip(), int(number) if number.is_integer() else number


def main(argv: list[str] | None = None) -> NoReturn:
    """Entry point: run the CLI; every failure is one line on stderr, never a traceback.

    Exit status 0 on success, 2 for anything the user can fix, :data:`INTERNAL_ERROR` for a bug in
    toonmotion, 130 when interrupted. Library warnings are not shown: a problem worth telling is
    a :class:`ToonmotionError` or a note the command prints itself.
    """
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            code = app(args=args, prog_name="toonmotion", standalone_mode=False)
    except ToonmotionError as error:
        _fail(str(error) or type(error).__name__)
    except OSError as error:  # an output that cannot be written, a full disk
        _fail(os_error_message(error))
    except typer.TyperException as error:  # the option parser's: a missing argument, a value out of range
        context = getattr(error, "ctx", None)
        if type(error).__name__ == "NoArgsIsHelpError" and context is not None:
            typer.echo(context.get_help())
            sys.exit(2)
        command = context.command_path if context is not None else "toonmotion"
        _fail(f"{error.format_message()} (see '{command} --help')")
    except (typer.Abort, KeyboardInterrupt):
        _fail("interrupted", status=130)
    except MemoryError:
        _fail("ran out of memory; " + _BUG_HINT, status=INTERNAL_ERROR)
    except Exception as error:  # a bug: say so in one line, not as a stack trace
        _fail(f"internal error ({type(error).__name__}: {error}); {_BUG_HINT}", status=INTERNAL_ERROR)
    sys.exit(code if isinstance(code, int) else 0)


# The exit status of a bug in toonmotion (EX_SOFTWARE in sysexits.h).
INTERNAL_ERROR = 70

_BUG_HINT = (
    "this is a bug in toonmotion, please report it with the command and its input files "
    "(set TOONMOTION_TRACEBACK=1 to see where it happened)"
)


def os_error_message(error: OSError) -> str:
    """An operating system's refusal in the user's words: the file they named (not the temporary
    one it was being written to, :mod:`toonmotion.io.atomic`) and why.

    >>> os_error_message(PermissionError(13, "Permission denied", "/sys/.x.png.123.ab_c.tmp"))
    'cannot write /sys/x.png: permission denied'
    """
    if error.filename is None:
        return str(error) or type(error).__name__
    path = Path(os.fsdecode(error.filename))
    temporary = re.fullmatch(r"\.(.+)\.\d+\..*\.tmp", path.name)
    if isinstance(error, FileExistsError | NotADirectoryError):
        blocking = next((part for part in (path, *path.parents) if part.is_file()), None)
        if blocking is not None:
            return f"{blocking} is a file, not a folder: give a path in a folder"
    reason = (error.strerror or type(error).__name__).lower()
    if temporary:
        return f"cannot write {path.with_name(temporary.group(1))}: {reason}"
    return f"{path}: {reason}"


def _fail(message: str, *, status: int = 2) -> NoReturn:
    if status == INTERNAL_ERROR and os.environ.get("TOONMOTION_TRACEBACK"):
        traceback.print_exc()
    one_line = " ".join(message.split())
    if len(one_line) > 400:
        one_line = one_line[:397] + "..."
    print(f"toonmotion: error: {one_line}", file=sys.stderr)
    sys.exit(status)
