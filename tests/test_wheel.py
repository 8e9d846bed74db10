"""The wheel works on its own: built from an sdist by ``python -m build``, installed into a fresh
virtual environment with no source tree beside it, the commands a new user runs first work, and
the editor serves its page and every static file the page loads.

The environment gets the wheel's own dependencies at the versions of the environment running the
tests (the lock under ``make test``), so a dependency missing from the wheel's metadata, or a data
file missing from the wheel or the sdist, fails here.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import urllib.request
from importlib import metadata
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _run(command, cwd, env, timeout=600):
    done = subprocess.run([str(c) for c in command], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=timeout, check=False)
    assert done.returncode == 0, f"{command} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"
    return done.stdout


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """``(bin folder, work folder, environment)`` of a fresh venv holding only the built wheel."""
    uv = pytest.importorskip("uv", reason="uv (the dev extra) installs the wheel").find_uv_bin()
    top = tmp_path_factory.mktemp("wheel")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
    env["UV_PYTHON_DOWNLOADS"] = "never"
    # No build isolation: the setuptools of this environment (the locked one) builds the sdist, then
    # the wheel from the sdist, as `python -m build` does.
    _run([sys.executable, "-m", "build", "--no-isolation", "--outdir", top / "dist", ROOT], ROOT, env)
    wheels = sorted((top / "dist").glob("toonmotion-*.whl"))
    sdists = sorted((top / "dist").glob("toonmotion-*.tar.gz"))
    assert len(wheels) == 1 and len(sdists) == 1, sorted((top / "dist").iterdir())
    # Pin every package to the version tested here; the wheel's metadata says which are needed.
    pins = top / "pins.txt"
    pins.write_text("".join(f"{d.metadata['Name']}=={d.version}\n" for d in metadata.distributions()
                            if d.metadata["Name"] and d.metadata["Name"].lower() != "toonmotion"))
    venv = top / "env"
    _run([uv, "venv", "--quiet", "--python", sys.executable, venv], top, env)
    _run([uv, "pip", "install", "--quiet", "--python", venv / "bin" / "python", "--constraint", pins,
          wheels[0]], top, env)
    work = top / "work"
    work.mkdir()
    return venv / "bin", work, env


def test_the_installed_package_is_the_wheel_not_the_source_tree(installed):
    bin_dir, work, env = installed
    where = _run([bin_dir / "python", "-c", "import toonmotion; print(toonmotion.__file__)"], work, env)
    assert "site-packages" in where and not where.startswith(str(ROOT / "src")), where
    version = _run([bin_dir / "toonmotion", "--version"], work, env)
    assert version.strip() == f"toonmotion {metadata.version('toonmotion')}"


def test_the_first_commands_work_from_the_wheel(installed):
    bin_dir, work, env = installed
    tm = bin_dir / "toonmotion"
    _run([tm, "sample", "-o", "hero.png", "--skeleton", "hero.json", "--keys", "keys.json"], work, env)
    _run([tm, "rig", "hero.png", "--skeleton", "hero.json", "-o", "hero"], work, env)
    _run([tm, "animate", "hero", "keys.json", "-o", "walk.gif"], work, env)
    _run([tm, "export", "hero", "keys.json", "-o", "walk.glb"], work, env)
    _run([tm, "export", "hero", "keys.json", "-o", "spine/walk.json", "--format", "spine"], work, env)
    assert (work / "walk.gif").read_bytes()[:6] == b"GIF89a"
    assert (work / "walk.glb").read_bytes()[:4] == b"glTF"
    assert json.loads((work / "spine" / "walk.json").read_text())["skeleton"]["spine"].startswith("4.")
    report = _run([tm, "doctor"], work, env)
    assert re.search(r"^numpy\s+\d", report, re.M) and re.search(r"^ffmpeg\s+\S", report, re.M), report


def test_the_editor_serves_its_page_and_every_file_it_loads(installed):
    bin_dir, work, env = installed
    if not (work / "hero" / "project.json").is_file():
        _run([bin_dir / "toonmotion", "sample", "-o", "hero.png", "--skeleton", "hero.json"], work, env)
        _run([bin_dir / "toonmotion", "rig", "hero.png", "--skeleton", "hero.json", "-o", "hero"], work, env)
    child = subprocess.Popen([bin_dir / "toonmotion", "edit", "hero"], cwd=work, env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = child.stdout.readline()
        match = re.search(r"(http://[^/]+)/\?token=(\S+)", line)
        assert match, f"the editor printed {line!r}"
        base, token = match.groups()
        page = _get(f"{base}/?token={token}").decode()
        assert "<html" in page.lower()
        # Every file the page names, and every module those import, is served.
        pending = re.findall(r'(?:src|href)="(static/[^"]+)"', page)
        seen = set()
        while pending:
            path = pending.pop()
            if path in seen:
                continue
            seen.add(path)
            body = _get(f"{base}/{path}")
            assert body, path
            if path.endswith(".js"):  # the modules it imports, statically or not
                imported = re.findall(r'(?:from\s+|import\(\s*)"\./([^"]+)"', body.decode())
                pending += [f"static/{name}" for name in imported]
        shipped = {p.name for p in (ROOT / "src" / "toonmotion" / "web" / "static").iterdir()}
        assert {p.removeprefix("static/") for p in seen} == shipped - {"index.html"}
        project = json.loads(_get(f"{base}/api/project?token={token}"))
        assert project and _get(f"{base}/api/texture.png?token={token}")[:4] == b"\x89PNG"
    finally:
        child.terminate()
        child.wait(timeout=20)


def _get(url):
    with urllib.request.urlopen(url, timeout=30) as response:
        assert response.status == 200, url
        return response.read()
