"""The Typer application the command modules register on, and the entry point that runs it.

Every error the user can fix prints one line, ``toonmotion: error: ...``, and exits with status
2: the library's :class:`~toonmotion.errors.ToonmotionError`, an unwritable output, and the option
parser's own complaints (a missing argument, a value out of range), which Click would otherwise
draw as a multi-line box.
"""

from __future__ import annotations

import sys
from typing import Annotated, NoReturn

import typer

from toonmotion import __version__
from toonmotion.errors import ToonmotionError

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
) -> None:
    """toonmotion: 2D character animation from one drawing."""


def main(argv: list[str] | None = None) -> NoReturn:
    """Entry point: run the CLI, turning user errors into one line and exit status 2."""
    args = sys.argv[1:] if argv is None else list(argv)
    try:
        code = app(args=args, prog_name="toonmotion", standalone_mode=False)
    except (ToonmotionError, OSError) as error:  # OSError: an output that cannot be written, a full disk
        _fail(str(error))
    except typer.TyperException as error:  # the option parser's: a missing argument, a value out of range
        context = getattr(error, "ctx", None)
        if type(error).__name__ == "NoArgsIsHelpError" and context is not None:
            typer.echo(context.get_help())
            sys.exit(2)
        command = context.command_path if context is not None else "toonmotion"
        _fail(f"{error.format_message()} (see '{command} --help')")
    except typer.Abort:
        _fail("aborted")
    sys.exit(code if isinstance(code, int) else 0)


def _fail(message: str) -> NoReturn:
    one_line = " ".join(message.split())
    print(f"toonmotion: error: {one_line}", file=sys.stderr)
    sys.exit(2)
