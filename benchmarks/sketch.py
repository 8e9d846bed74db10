"""Posing by sketching: how often drawn stick figures give back their pose, and how fast; JSON lines.

    python benchmarks/sketch.py [DRAWING_DIR ...] [--poses N] [--seed S]

Each drawing's skeleton (its char_cfg.yaml; default: every drawing in ../shared/data/drawings,
and the bundled sample) is turned into N poses per case, and each pose is drawn as a hand
would: one stroke per chain of bones (``stroke_chains``), a point every 4 px jittered by 0.8 px,
about half drawn backwards, in shuffled order. The strokes go to ``toonmotion.api``'s matcher
(``rig/sketch.py``), starting from the rest pose. Cases:

  moderate   two joints turned up to 0.6 rad (34 degrees), the figure drawn over the drawing
  hard       three joints turned up to 1.0 rad (57 degrees): limbs fold and cross
  limb       one limb (a chain ending in a free end) turned 0.8 rad at its base, drawn alone
  beside     the moderate poses drawn at half size beside the figure, without jitter

Keys, one line per drawing and case:
  drawing, case, poses, joints
  wrong           poses with some joint farther than 5% of the figure's size from where it was
                  drawn (beside: some bone turned more than 5 degrees from the drawn one)
  error_median    the median over poses of the largest joint error, in figure sizes
  ms_median, ms_p95   time to match one sketch
No peer: no library matches sketched strokes to a skeleton.
"""

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from toonmotion.errors import ToonmotionError
from toonmotion.io.char_cfg import load_char_cfg
from toonmotion.rig.kinematics import bone_angles
from toonmotion.rig.pose import Pose, rotate_about
from toonmotion.rig.sketch import match_sketch, stroke_chains
from toonmotion.samples import sample_character
from toonmotion.testing.sketching import figure_size, strokes_through, turned

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"


def _cases(skeleton, rng, poses):
    """(case, target positions, strokes) for every case."""
    chains = stroke_chains(skeleton)
    ends = set(range(len(skeleton))) - set(skeleton.parents.tolist())
    limbs = [c if c[-1] in ends else c[::-1] for c in chains if len(c) >= 3 and ends & {c[0], c[-1]}]
    for _ in range(poses):
        target = turned(skeleton, rng, turns=2, most=0.6)
        yield "moderate", target, strokes_through(target, chains, rng)
    for _ in range(poses):
        target = turned(skeleton, rng, turns=3, most=1.0)
        yield "hard", target, strokes_through(target, chains, rng)
    for n in range(poses):
        limb = limbs[n % len(limbs)]
        target = skeleton.positions.copy()
        target[limb] = rotate_about(skeleton, skeleton.positions, skeleton.names[limb[0]], 0.8)[limb]
        yield "limb", target, strokes_through(target, [limb], rng)
    for _ in range(poses):
        target = turned(skeleton, rng, turns=2, most=0.6)
        beside = (target - target[0]) * 0.5 + target[0] + [1.2 * figure_size(target), 0]
        yield "beside", target, strokes_through(beside, chains, rng, noise=0)


def _wrong(skeleton, case, found, target):
    """Whether a match is wrong, and its largest joint error in figure sizes."""
    error = float(np.linalg.norm(found - target, axis=1).max()) / figure_size(target)
    if case != "beside":
        return error > 0.05, error
    angles, _ = bone_angles(skeleton, found)
    expected, lengths = bone_angles(skeleton, target)
    turn = np.degrees(np.abs(np.angle(np.exp(1j * (angles - expected)))))[lengths > 1]
    return bool(turn.max() > 5), error


def measure(name, skeleton, poses, seed):
    rng = np.random.default_rng(seed)
    results = {}
    for case, target, strokes in _cases(skeleton, rng, poses):
        started = time.perf_counter()
        try:
            found = match_sketch(skeleton, Pose(skeleton.positions), strokes).pose.positions
            wrong, error = _wrong(skeleton, case, found, target)
        except ToonmotionError:  # refused: counted as wrong
            wrong, error = True, float("nan")
        results.setdefault(case, []).append((wrong, error, 1000 * (time.perf_counter() - started)))
    for case, rows in results.items():
        times = sorted(ms for _, _, ms in rows)
        errors = [e for _, e, _ in rows if e == e]
        yield {"drawing": name, "case": case, "poses": len(rows), "joints": len(skeleton),
               "wrong": sum(w for w, _, _ in rows),
               "error_median": round(statistics.median(errors), 4) if errors else None,
               "ms_median": round(statistics.median(times), 1),
               "ms_p95": round(times[int(0.95 * (len(times) - 1))], 1)}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders holding a char_cfg.yaml")
    parser.add_argument("--poses", type=int, default=40, help="poses per case (default 40)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    folders = args.drawings or sorted(p for p in DEFAULT_DIR.iterdir() if (p / "char_cfg.yaml").is_file())
    skeletons = [(folder.name, load_char_cfg(folder / "char_cfg.yaml")[0]) for folder in folders]
    if not args.drawings:
        skeletons.append(("sample", sample_character()[1]))
    for name, skeleton in skeletons:
        for line in measure(name, skeleton, args.poses, args.seed):
            print(json.dumps(line), flush=True)


if __name__ == "__main__":
    sys.exit(main())
