"""Rigging speed and segmentation quality on real drawings; one JSON line per drawing.

    python benchmarks/rig.py [DRAWING_DIR ...]

A drawing folder holds texture.png, and optionally mask.png and char_cfg.yaml. The default
is every drawing in ../shared/data/drawings. Runs on one core (thread pools are pinned to one
thread before NumPy loads). File reading is excluded from the timings.

Keys:
  drawing, width, height, vertices, triangles, joints
  rig_ms        median time to rig to about 1,500 vertices from texture + mask + char_cfg
                skeleton where given (the goal: at most 300 ms for 600x600-class drawings)
  rig_auto_ms   median time to rig from texture.png alone (segmentation and automatic skeleton)
  stage_ms      median time of each stage of the rig_ms run
  iou           IoU of the texture-only silhouette's mask with mask.png (when given)
  fallback      vertices that reached no bone without crossing the outline
"""

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

from toonmotion.io.drawing_folder import load_drawing_folder  # noqa: E402
from toonmotion.rig.character import RigSettings  # noqa: E402
from toonmotion.rig.pipeline import rig_drawing  # noqa: E402

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
REPEATS = 7


def _timed_rig(texture, **kwargs):
    """Median total and per-stage milliseconds over REPEATS runs, and the last character."""
    totals, stages = [], {}
    for _ in range(REPEATS):
        marks = []

        def progress(stage, index, count, marks=marks):
            marks.append((stage, time.perf_counter()))

        start = time.perf_counter()
        character = rig_drawing(texture, progress=progress, **kwargs)
        end = time.perf_counter()
        totals.append((end - start) * 1e3)
        ends = [t for _, t in marks[1:]] + [end]
        for (stage, t0), t1 in zip(marks, ends, strict=True):
            stages.setdefault(stage, []).append((t1 - t0) * 1e3)
    return (
        statistics.median(totals),
        {k: round(statistics.median(v), 1) for k, v in stages.items()},
        character,
    )


def _silhouette_iou(character, mask):
    found = character.silhouette.to_mask(mask.shape)
    return float((found & mask).sum() / (found | mask).sum())


def bench(folder):
    drawing = load_drawing_folder(folder)
    texture, mask, skeleton = drawing.texture, drawing.mask, drawing.skeleton
    size = (texture.shape[1], texture.shape[0])
    settings = RigSettings(vertices=1500)
    rig_ms, stage_ms, character = _timed_rig(
        texture, mask=mask, skeleton=skeleton, settings=settings
    )
    auto_ms, _, auto = _timed_rig(texture, settings=settings)
    row = {
        "drawing": folder.name,
        "width": size[0],
        "height": size[1],
        "vertices": len(character.mesh.V),
        "triangles": len(character.mesh.F),
        "joints": len(character.skeleton),
        "rig_ms": round(rig_ms, 1),
        "rig_auto_ms": round(auto_ms, 1),
        "stage_ms": stage_ms,
        "fallback": int(character.binding.fallback.sum()),
    }
    if mask is not None:
        row["iou"] = round(_silhouette_iou(auto, mask), 4)
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders")
    args = parser.parse_args(argv)
    folders = args.drawings or sorted(
        p for p in DEFAULT_DIR.iterdir() if (p / "texture.png").is_file()
    )
    if not folders:
        sys.exit(f"no drawings found (looked in {DEFAULT_DIR})")
    for folder in folders:
        print(json.dumps(bench(folder)), flush=True)


if __name__ == "__main__":
    main()
