"""Tests for toonmotion.cli.app: parser complaints are one line and exit 2, like every user error."""

import re
import subprocess
import sys

import pytest

import toonmotion
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


def test_a_bug_is_one_line_with_a_report_hint_and_its_own_exit_status(capsys, monkeypatch):
    from toonmotion.cli import rigging
    from toonmotion.cli.app import INTERNAL_ERROR

    def broken(*args, **kwargs):
        raise KeyError("oops")

    monkeypatch.setattr(rigging.api, "load_project", broken)
    code, out, err = _run(["show", "somewhere", "-o", "x.png"], capsys)
    assert code == INTERNAL_ERROR == 70
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith("toonmotion: error: internal error (KeyError: 'oops'); this is a bug in toonmotion")


def test_library_warnings_never_reach_the_user(capsys, monkeypatch):
    import warnings

    from toonmotion.cli import rigging
    from toonmotion.errors import ProjectError

    def noisy(*args, **kwargs):
        warnings.warn("overflow encountered", RuntimeWarning, stacklevel=1)
        raise ProjectError("no project at somewhere")

    monkeypatch.setattr(rigging.api, "load_project", noisy)
    code, out, err = _run(["show", "somewhere", "-o", "x.png"], capsys)
    assert (code, err) == (2, "toonmotion: error: no project at somewhere\n")


def test_a_limit_is_raised_for_one_run_with_the_global_option(capsys, tmp_path):
    from toonmotion import limits

    code, out, err = _run(["--limit", "frames=12", "--limit", "joints=9", "edits", tmp_path], capsys)
    assert code == 2 and "no project at" in err
    assert limits.current().frames == 12  # in force until the next run sets its own
    code, out, err = _run(["--limit", "frames=lots", "edits", tmp_path], capsys)
    assert (code, err.strip()) == (2, "toonmotion: error: --limit takes NAME=N, e.g. --limit "
                                      "canvas_pixels=100000000; got 'frames=lots'")
    limits.set_limits(limits.Limits())


def test_negative_coordinates_are_arguments_not_options(capsys, tmp_path):
    code, out, err = _run(["correct", tmp_path, "head", "-100,-100", "-50,-100", "-50,-50"], capsys)
    assert code == 2 and "no project at" in err and "No such option" not in err


def test_help_lists_the_commands_in_workflow_order(capsys):
    code, out, err = _run(["--help"], capsys)
    listed = re.findall(r"^│ (\w+) ", out, flags=re.MULTILINE)
    workflow = ["rig", "show", "sample", "pose", "animate", "tune", "track", "retarget"]
    assert [c for c in listed if c in workflow] == workflow


def test_edit_refuses_a_missing_project_and_a_busy_port_in_one_line(capsys, tmp_path):
    import socket

    code, out, err = _run(["edit", tmp_path / "nothing", "--port", "0"], capsys)
    assert code == 2 and err.startswith("toonmotion: error: no project at") and err.count("\n") == 1
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        code, out, err = _run(["edit", tmp_path, "--port", busy.getsockname()[1]], capsys)
    assert code == 2 and "toonmotion: error: cannot serve on 127.0.0.1:" in err and err.count("\n") == 1


@pytest.mark.parametrize("host", ["0.0.0.0", "::", "192.168.1.9", "example.org"])
def test_edit_refuses_an_address_other_machines_reach_and_says_how_to_forward_one(capsys, tmp_path, host):
    code, out, err = _run(["edit", tmp_path / "nothing", "--host", host], capsys)
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"toonmotion: error: --host {host}: the editor serves this machine only")
    assert "ssh -L" in err


def test_edit_opens_the_browser_with_a_one_time_code_not_the_token(capsys, tmp_path, monkeypatch):
    """The browser's command line (visible in ps) carries a sign-in code good once; the token is
    printed to the terminal only."""
    import uvicorn

    from toonmotion.io.project import save_project
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character

    drawing, skeleton = sample_character(scale=0.4)
    save_project(tmp_path / "hero", rig_drawing(drawing, skeleton=skeleton))
    opened, served = [], []
    monkeypatch.setattr("webbrowser.open", opened.append)
    monkeypatch.setattr(uvicorn.Server, "run", lambda server, sockets: served.append(server.config.app))
    code, out, err = _run(["edit", tmp_path / "hero", "--open"], capsys)
    assert code == 0 and len(opened) == 1 and len(served) == 1
    token = re.search(r"\?token=(\S+)", out).group(1)
    assert "?code=" in opened[0] and token not in opened[0]
    code_given = opened[0].split("?code=")[1]
    assert code_given in served[0].state.sign_in_codes


def test_edit_offers_the_clips_of_its_mocap_folder_as_the_3d_panel_s_priors(capsys, tmp_path, monkeypatch):
    import uvicorn

    from toonmotion.io.project import save_project
    from toonmotion.rig.pipeline import rig_drawing
    from toonmotion.samples import sample_character
    from toonmotion.web import server
    from toonmotion.web.editing import Editing
    from toonmotion.web.proxy_requests import priors

    drawing, skeleton = sample_character(scale=0.4)
    save_project(tmp_path / "hero", rig_drawing(drawing, skeleton=skeleton))
    clips = tmp_path / "clips"
    code, out, err = _run(["edit", tmp_path / "hero", "--mocap", clips], capsys)
    said = f"toonmotion: error: --mocap must be a folder of .bvh clips; {clips} is not a folder\n"
    assert (code, err) == (2, said)
    clips.mkdir()
    for name in ("walk.bvh", "run.bvh", "notes.txt"):
        (clips / name).write_text("")
    given = []
    create_app = server.create_app

    def creating(*args, **kw):
        given.append(kw["library"])
        return create_app(*args, **kw)

    monkeypatch.setattr(server, "create_app", creating)
    monkeypatch.setattr(uvicorn.Server, "run", lambda server, sockets: None)
    monkeypatch.setenv("TOONMOTION_MOCAP", str(clips))  # the variable stands for --mocap
    code, out, err = _run(["edit", tmp_path / "hero"], capsys)
    assert code == 0 and given == [clips]
    offered = priors(Editing.open(tmp_path / "hero", library=given[0]))
    assert offered == ["library/run.bvh", "library/walk.bvh"]


def test_edit_rigs_a_drawing_into_a_project_beside_it_once(capsys, tmp_path):
    import socket

    from toonmotion.io.image import save_png
    from toonmotion.io.project import load_project
    from toonmotion.samples import sample_character

    save_png(tmp_path / "hero.png", sample_character(scale=0.4)[0])
    with socket.socket() as busy:  # the server cannot start: the command ends after the rigging
        busy.bind(("127.0.0.1", 0))
        busy.listen(1)
        port = busy.getsockname()[1]
        code, out, err = _run(["edit", tmp_path / "hero.png", "--port", port], capsys)
        assert code == 2 and out.startswith("rigged hero.png: ") and "cannot serve on" in err
        rigged = load_project(tmp_path / "hero")
        code, out, err = _run(["edit", tmp_path / "hero.png", "--port", port], capsys)
        assert out.startswith("opening ") and "made from hero.png" in out
    assert load_project(tmp_path / "hero").mesh.V.tolist() == rigged.mesh.V.tolist()


def test_doctor_lists_the_versions_a_bug_report_needs(capsys, tmp_path, monkeypatch):
    import numpy
    import PIL

    monkeypatch.chdir(tmp_path)  # no node_modules here or above: the validator is missing, not an error
    code, out, err = _run(["doctor"], capsys)
    assert code == 0 and not err
    rows = {line.split()[0]: line for line in out.splitlines()}
    assert rows["toonmotion"].split()[1] == toonmotion.__version__
    assert rows["numpy"].split()[1] == numpy.__version__ and rows["pillow"].split()[1] == PIL.__version__
    assert {"scipy", "opencv", "mujoco", "ffmpeg", "chromium", "python"} <= rows.keys()
    assert "not found" in rows["gltf-validator"] and "(missing)" in rows["gltf-validator"]
