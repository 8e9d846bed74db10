"""Batch jobs on Dask (``toonmotion batch``): the library in a loop against 1 and 2 workers; JSON lines.

    python benchmarks/batch.py [--drawings DIR ...] [--clips BVH ...] [--motions N]
                               [--frames F] [--size PX] [--vertices V] [--trivial N]

The job: every drawing (default: three of ../shared/data/drawings) x N motions (default 8: pieces
of the shared mocap clips, each seen from the side, ``--frames`` frames at 12 fps from a
different start), GIF and glb each: 24 tasks by default. It runs three ways, each from nothing
(a fresh output folder):

  serial_s      the same work functions (rig each character once, read each motion once, render
                each output) called in this process in a loop: the library without Dask
  workers_1_s   ``run_batch`` on a local cluster of one worker process
  workers_2_s   the same on two worker processes (one per core here)

Each is timed in a fresh Python process of its own, after the library is imported, so that no run
starts with what an earlier one loaded (the workers are forked from the client on Linux and
would inherit it). The report ``speedup_2`` = workers_1_s / workers_2_s (goal >= 1.7 on a 2-core machine),
``overhead`` = workers_1_s / serial_s (goal <= 1.10), the input files' kB (sent once per
character and motion) and the output's kB per task (sent back), and ``tasks_per_s``: 1,000
trivial tasks on the two-worker cluster (the scheduler's own cost per task, what bounds a
cluster's throughput on tiny tasks).
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from toonmotion.batch.plan import plan_job
from toonmotion.batch.run import run_batch
from toonmotion.batch.work import prepare_motion, render_output, rig_character, trivial
from toonmotion.io.batch_job import load_job
from toonmotion.io.bvh import load_bvh

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data"
FPS = 12


def write_job(folder, drawings, clips, motions, frames, size, vertices):
    """A job of every drawing x ``motions`` pieces of the clips, GIF + glb; its path."""
    text = ""
    for drawing in drawings:
        text += f'\n[[character]]\nname = "{drawing.name}"\ndrawing = "{drawing / "texture.png"}"\n'
        if (drawing / "mask.png").is_file():
            text += f'mask = "{drawing / "mask.png"}"\n'
        if (drawing / "char_cfg.yaml").is_file():
            text += f'skeleton = "{drawing / "char_cfg.yaml"}"\n'
        text += f"vertices = {vertices}\n"
    uses = [sum(1 for j in range(motions) if j % len(clips) == i) for i in range(len(clips))]
    for k in range(motions):
        i = k % len(clips)
        clip = load_bvh(clips[i])
        length = max(2, round(frames / FPS / clip.frame_time))  # clip frames for ``frames`` at FPS
        room = max(0, clip.frame_count - 1 - length)
        start = 1 + (k // len(clips)) * room // max(1, uses[i] - 1)  # another stretch of the clip
        text += (f'\n[[motion]]\nname = "m{k}"\nbvh = "{clips[i]}"\nview = [90, 0]\n'
                 f"segment = [{start}, {start + length}]\nfps = {FPS}\n")
    text += f'\n[output]\nformats = ["gif", "glb"]\nsize = [{size}, {size}]\n'
    path = folder / "job.toml"
    path.write_text(text)
    return path


def serial(job_path):
    """The work functions in a loop, in this process: seconds, input bytes and output bytes."""
    start = time.perf_counter()
    plan = plan_job(load_job(job_path))
    rigged = {name: rig_character(spec) for name, spec in plan.characters.items()}
    read = {name: prepare_motion(spec) for name, spec in plan.motions.items()}
    sent = returned = 0
    for task in plan.tasks:
        rendered = render_output(rigged[task.character], read[task.motion], task)
        returned += sum(len(data) for data in rendered.files.values())
    for c in plan.characters.values():
        sent += sum(len(f.data) for f in (c.drawing, c.mask, c.skeleton, *c.project) if f is not None)
    sent += sum(len(m.file.data) for m in plan.motions.values() if m.file is not None)
    return time.perf_counter() - start, len(plan.tasks), sent, returned


def on_cluster(job_path, workers, folder):
    start = time.perf_counter()
    report = run_batch(job_path, output=folder, workers=workers)
    seconds = time.perf_counter() - start
    if report.count("done") != len(report.results):
        failed = [r.message for r in report.results if r.status == "failed"]
        raise SystemExit(f"{len(failed)} tasks failed: {failed[0]}")
    return seconds


def trivial_rate(count):
    import logging

    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=logging.ERROR) as cluster, Client(cluster) as client:
        client.gather(client.map(trivial, range(10), key=[f"warm-{i}" for i in range(10)]))
        start = time.perf_counter()
        client.gather(client.map(trivial, range(count)))
        return count / (time.perf_counter() - start)


def fresh(job, mode, folder):
    """One way of running ``job`` (``mode``: "serial" or a worker count), timed in a new process."""
    argv = [sys.executable, __file__, "--measure", mode, "--job", str(job), "--out", str(folder)]
    done = subprocess.run(argv, check=True, capture_output=True, text=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def measure(mode, job, folder):
    """In the fresh process: run ``job`` one way and print what it took as one JSON line."""
    if mode == "serial":
        seconds, tasks, sent, returned = serial(job)
        print(json.dumps({"seconds": seconds, "tasks": tasks, "sent": sent, "returned": returned}))
    else:
        print(json.dumps({"seconds": on_cluster(job, int(mode), folder)}))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--drawings", nargs="*", type=Path, help="Drawing folders (texture.png, mask.png, "
                        "char_cfg.yaml); default char1, char2, char3 of the shared drawings.")
    parser.add_argument("--clips", nargs="*", type=Path, help="BVH clips; default the shared CMU walk, run "
                        "and jump.")
    parser.add_argument("--motions", type=int, default=8)
    parser.add_argument("--frames", type=int, default=12, help="Frames per motion, at 12 fps.")
    parser.add_argument("--size", type=int, default=256, help="Output pictures' side, pixels.")
    parser.add_argument("--vertices", type=int, default=600, help="Each character's mesh size.")
    parser.add_argument("--trivial", type=int, default=1000, help="Trivial tasks for tasks_per_s.")
    parser.add_argument("--measure", help=argparse.SUPPRESS)
    parser.add_argument("--job", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--out", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    if args.measure:
        return measure(args.measure, args.job, args.out)
    drawings = args.drawings or [SHARED / "drawings" / n for n in ("char1", "char2", "char3")]
    clips = args.clips or [SHARED / "mocap" / n for n in ("cmu_07_01_walk.bvh", "cmu_02_03_run.bvh",
                                                          "cmu_16_07_jump.bvh")]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        job = write_job(folder, drawings, clips, args.motions, args.frames, args.size, args.vertices)
        alone = fresh(job, "serial", folder)
        serial_s, tasks, sent, returned = alone["seconds"], alone["tasks"], alone["sent"], alone["returned"]
        workers_1_s = fresh(job, "1", folder / "one")["seconds"]
        workers_2_s = fresh(job, "2", folder / "two")["seconds"]
    print(json.dumps({
        "tasks": tasks, "characters": len(drawings), "motions": args.motions, "formats": ["gif", "glb"],
        "frames": args.frames, "size": args.size, "vertices": args.vertices,
        "serial_s": round(serial_s, 2), "workers_1_s": round(workers_1_s, 2),
        "workers_2_s": round(workers_2_s, 2),
        "speedup_2": round(workers_1_s / workers_2_s, 2), "speedup_2_goal": 1.7,
        "overhead": round(workers_1_s / serial_s, 3), "overhead_goal": 1.10,
        "input_kb": round(sent / 1024, 1),
        "output_kb_per_task": round(returned / tasks / 1024, 1),
        "cpus": os.cpu_count()}), flush=True)
    print(json.dumps({"trivial_tasks": args.trivial, "workers": 2,
                      "tasks_per_s": round(trivial_rate(args.trivial), 1)}), flush=True)


if __name__ == "__main__":
    main()
