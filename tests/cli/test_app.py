"""Tests for toonmotion.cli.app: parser complaints are one line and exit 2, like every user error."""

import re
import subprocess
import sys

import pytest

from toonmotion.cli import main


def _run(argv, capsys):
    capsys.readouterr()
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return (info.value.code or 0), out, err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["rig", "x.png", "-o", "p", "--vertices", "0"],
            r"'--vertices'.*greater than or equal to 3.*toonmotion rig --help",
        ),
        (["rig", "x.png", "-o", "p", "--spacing", "0.5"], r"'--spacing'.*greater than or equal to 1"),
        (["rig", "x.png", "-o", "p", "--max-pixels", "many"], r"'--max-pixels'.*valid integer"),
        (["show", "p", "-o", "x.png", "--height", "10"], r"'--height'.*greater than or equal to 64"),
        (["pose", "p", "pose.json", "-o", "x.png", "--joint-width", "-1"], r"'--joint-width'"),
        (["pose"], r"Missing argument 'project'.*toonmotion pose --help"),
        (["show", "p"], r"Missing option '-o'"),
        (["show", "p", "-o", "x.png", "--heigth", "80"], r"No such option: --heigth"),
        (["dance"], r"No such command 'dance'"),
    ],
)
def test_parser_errors_are_one_line_and_exit_2(capsys, argv, message):
    code, out, err = _run(argv, capsys)
    assert code == 2
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("toonmotion: error: "), err
    assert re.search(message, lines[0]), lines[0]
    assert "╭" not in err and "Traceback" not in err + out


def test_no_command_prints_the_help_and_exits_2(capsys):
    code, out, err = _run([], capsys)
    assert code == 2 and "Usage: toonmotion" in out and "rig" in out and not err


def test_help_exits_0(capsys):
    code, out, _ = _run(["pose", "--help"], capsys)
    assert code == 0 and "--accel" in out


def test_the_module_runs_as_the_command():
    done = subprocess.run(
        [sys.executable, "-m", "toonmotion.cli", "--version"], capture_output=True, text=True
    )
    assert done.returncode == 0 and done.stdout.startswith("toonmotion ")
