"""A small batch job over the shared drawings, for the batch tests."""

import json
from pathlib import Path

from tests.conftest import SHARED_DATA, _require

KEYS = {"format": "toonmotion.keyframes", "version": 1, "fps": 12,
        "keys": [{"frame": 0, "rest": True}, {"frame": 5, "rest": True}]}
# The walk's frames 1..25 at 120 fps, resampled to 30 fps: 6 frames. The rest keys' six frames
# are all alike, which a GIF stores as one.
WALK_FRAMES = 6


def write_job(folder: Path, *, size: int = 64, extra: str = "") -> Path:
    """A job of char1 and char4 (coarse meshes) x a walk clip and rest key-frames, GIF + glb."""
    drawings = _require(SHARED_DATA / "drawings")
    (folder / "keys.json").write_text(json.dumps(KEYS))
    characters = "".join(f"""
[[character]]
name = "{name}"
drawing = "{drawings / name / 'texture.png'}"
mask = "{drawings / name / 'mask.png'}"
skeleton = "{drawings / name / 'char_cfg.yaml'}"
vertices = 100
""" for name in ("char1", "char4"))
    job = folder / "job.toml"
    job.write_text(characters + f"""
[[motion]]
name = "walk"
bvh = "{SHARED_DATA / 'mocap' / 'cmu_07_01_walk.bvh'}"
view = [90, 0]
segment = [1, 25]
fps = 30

[[motion]]
name = "still"
keys = "keys.json"

[output]
formats = ["gif", "glb"]
size = [{size}, {size}]
""" + extra)
    return job


def check_outputs(folder: Path, names=("char1", "char4"), motions=("walk", "still")) -> None:
    """Every GIF decodes with the expected frames; every glb parses with one animation."""
    from PIL import Image
    from pygltflib import GLTF2

    for c in names:
        for m in motions:
            with Image.open(folder / f"{c}-{m}.gif") as gif:
                assert gif.n_frames == WALK_FRAMES if m == "walk" else gif.n_frames >= 1, (c, m)
            glb = GLTF2.load_binary(str(folder / f"{c}-{m}.glb"))
            assert glb.meshes and (len(glb.animations) == 1 or m != "walk"), (c, m)
    assert not [p for p in folder.rglob("*.tmp")], "a temporary file was left"
