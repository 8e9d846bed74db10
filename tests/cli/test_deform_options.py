"""The deformation's options are one set (issue 47): every command that deforms the drawing takes
the same six, with DeformSettings' own defaults, and receives exactly what was given.

The probe commands run through click without a test runner (``standalone_mode=False``): the
runner swaps ``sys.stdout``, which another test of the suite may have closed under it."""

import pytest
import typer

from toonmotion.cli import options
from toonmotion.cli.app import app
from toonmotion.deform.deformer import DeformSettings
from toonmotion.errors import SettingsError

DEFORMING = ("pose", "animate", "retarget", "tune", "export")
FLAGS = ("--no-area", "--stage-one", "--weights", "--joint-width", "--joint-anchor", "--skinning")


def _received(*argv):
    """What a command decorated with deform_options gets, given ``argv``."""
    seen = []
    probe = typer.Typer()

    @probe.command()
    @options.deform_options
    def command(name: str, deform: DeformSettings = options.DEFAULT_DEFORM) -> None:
        seen.append((name, deform))

    typer.main.get_command(probe).main(["x", *argv], standalone_mode=False)
    return seen[0]


def test_no_flags_give_the_library_s_own_defaults():
    assert _received() == ("x", DeformSettings())


def test_each_flag_reaches_the_settings():
    name, deform = _received("--no-area", "--stage-one", "--weights", "2,1,1", "--joint-width", "0.5",
                             "--joint-anchor", "3", "--skinning", "weights")
    assert name == "x"
    assert deform == DeformSettings(preserve_area=False, stage_two=False, weights=(2.0, 1.0, 1.0),
                                    joint_width=0.5, joint_anchor=3.0, skinning="weights")


def test_every_deforming_command_lists_the_same_six_options():
    group = typer.main.get_command(app)
    for command in DEFORMING:
        names = {name for param in group.commands[command].params for name in param.opts}
        missing = [flag for flag in FLAGS if flag not in names]
        assert not missing, (command, missing)


def test_a_bad_value_is_one_line_not_a_traceback():
    probe = typer.Typer()

    @probe.command()
    @options.deform_options
    def command(deform: DeformSettings = options.DEFAULT_DEFORM) -> None:
        pass

    with pytest.raises(SettingsError) as refused:
        typer.main.get_command(probe).main(["--weights", "1,2"], standalone_mode=False)
    assert str(refused.value) == "--weights takes 3 comma-separated numbers, got '1,2'"
