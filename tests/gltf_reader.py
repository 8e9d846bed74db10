"""The Khronos glTF validator's report on a file, for the glTF exporters' tests (the files are read
back with :class:`toonmotion.testing.export_playback.GlbScene`)."""

import json
import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
VALIDATE = Path(__file__).with_name("validate_gltf.mjs")


def validator_installed():
    """True when node and node_modules/gltf-validator are there; skip (fail under CI=true) if not."""
    missing = None
    if shutil.which("node") is None:
        missing = "node is not installed"
    elif not (ROOT / "node_modules" / "gltf-validator").is_dir():
        missing = "node_modules/gltf-validator is not installed (make test runs npm ci)"
    if missing is None:
        return True
    if os.environ.get("CI") == "true":
        pytest.fail(f"the glTF validator is missing under CI: {missing}")
    return False


def validator_report(path):
    done = subprocess.run(["node", str(VALIDATE), str(path)], cwd=ROOT, capture_output=True, text=True,
                          timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)
