"""The editor's live posing: the round trip of a joint drag over the WebSocket; JSON lines.

    python benchmarks/editor.py [DRAWING_DIR ...]

Each drawing (default: every drawing in ../shared/data/drawings, with its char_cfg.yaml
skeleton) is rigged to about 1,500 vertices and served by the editor (``toonmotion.web``) on a
free loopback port. A client then drags one joint through a sweep of poses, as a pointer does,
one message at a time: each message is sent when the previous reply has arrived.

Then CLIENTS clients at once drag the joint on the same server, each MESSAGES messages, each
waiting for its reply before sending the next (a load test, on loopback). Each client starts
its sweep at its own step, so that no two send the same pose at once (a server that remembered
its last pose would otherwise answer 49 of 50 for free).

Keys, one line per drawing:
  drawing, vertices       mesh size
  drags                   messages timed
  roundtrip_median_ms     message sent -> deformed vertices received (goal: at most 15)
  roundtrip_p99_ms        the 99th percentile (goal: at most 50)
  updates_per_s           1000 / median (goal: at least 30)
  load_clients            clients at once
  load_messages           messages answered in all, and load_errors: error replies or lost messages
  load_per_client_per_s   replies each client got per second, the median client
  load_p99_ms             the 99th percentile round trip under load
  peak_rss_mb             the benchmark process's peak memory (server included)
"""

import argparse
import asyncio
import json
import math
import resource
import statistics
import sys
import tempfile
import time
from pathlib import Path

import websockets

from toonmotion import api
from toonmotion.io.drawing_folder import load_drawing_folder
from toonmotion.rig.character import RigSettings
from toonmotion.web.background import serving

DEFAULT_DIR = Path(__file__).resolve().parents[2] / "shared" / "data" / "drawings"
DRAGS = 300
CLIENTS = 50
MESSAGES = 40


def _sweep(character, count, start=0):
    """Poses of the first joint with a child turning its subtree back and forth, as a drag, from
    step ``start`` of its 60-step period."""
    skeleton = character.skeleton
    moving = [n for i, n in enumerate(skeleton.names) if skeleton.parents[i] >= 0 and i in skeleton.parents]
    joint = moving[len(moving) // 2]
    for step in range(start, start + count):
        angle = 0.8 * math.sin(2 * math.pi * step / 60)
        yield api.rotate_joint(character, joint, angle).positions.tolist()


async def _load(url, sweeps):
    """CLIENTS clients dragging at once, each its own sweep; returns (per-client rates, all round
    trips, errors)."""

    async def client(poses):
        times, errors = [], 0
        async with websockets.connect(url, max_size=None) as socket_:
            started = time.perf_counter()
            for ident, positions in enumerate(poses):
                sent = time.perf_counter()
                await socket_.send(json.dumps({"id": ident, "type": "pose", "positions": positions}))
                reply = json.loads(await socket_.recv())
                times.append((time.perf_counter() - sent) * 1000)
                errors += reply.get("type") != "mesh" or reply.get("id") != ident
            return len(poses) / (time.perf_counter() - started), times, errors

    results = await asyncio.gather(*(client(poses) for poses in sweeps))
    return [r[0] for r in results], [t for r in results for t in r[1]], sum(r[2] for r in results)


async def _drag(url, poses):
    times = []
    async with websockets.connect(url, max_size=None) as socket_:
        for ident, positions in enumerate(poses):
            started = time.perf_counter()
            await socket_.send(json.dumps({"id": ident, "type": "pose", "positions": positions}))
            reply = json.loads(await socket_.recv())
            times.append((time.perf_counter() - started) * 1000)
            if reply["type"] != "mesh":
                raise RuntimeError(reply["message"])
    return times[10:]  # the first replies warm the solver


def bench(folder):
    drawing = load_drawing_folder(folder)
    character = api.rig_image(drawing.texture, mask=drawing.mask, skeleton=drawing.skeleton,
                              settings=RigSettings(vertices=1500))
    with tempfile.TemporaryDirectory() as scratch:
        project = Path(scratch) / "project"
        api.save_project(project, character)
        with serving(project) as served:
            times = asyncio.run(_drag(served.live, list(_sweep(character, DRAGS))))
            sweeps = [list(_sweep(character, MESSAGES, start=7 * k)) for k in range(CLIENTS)]
            rates, loaded, errors = asyncio.run(_load(served.live, sweeps))
    median = statistics.median(times)
    return {
        "drawing": folder.name,
        "vertices": len(character.mesh.V),
        "drags": len(times),
        "roundtrip_median_ms": round(median, 2),
        "roundtrip_p99_ms": round(statistics.quantiles(times, n=100)[98], 2),
        "updates_per_s": round(1000 / median, 1),
        "load_clients": CLIENTS,
        "load_messages": len(loaded),
        "load_errors": errors,
        "load_per_client_per_s": round(statistics.median(rates), 1),
        "load_p99_ms": round(statistics.quantiles(loaded, n=100)[98], 1),
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1),
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("drawings", nargs="*", type=Path, help="drawing folders")
    args = parser.parse_args(argv)
    folders = args.drawings or sorted(p for p in DEFAULT_DIR.iterdir() if (p / "texture.png").is_file())
    if not folders:
        sys.exit(f"no drawings found (looked in {DEFAULT_DIR})")
    for folder in folders:
        print(json.dumps(bench(folder)), flush=True)


if __name__ == "__main__":
    main()
