"""A real ``dask scheduler`` and ``dask worker`` processes on 127.0.0.1: ``--scheduler`` runs the
job there, and killing a worker mid-batch leaves every output complete (issue 46)."""

import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tests.batch.jobs import check_outputs, write_job
from toonmotion.batch import run_batch
from toonmotion.cli.app import main

DASK = Path(sys.executable).parent / "dask"


def _port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def cluster():
    """A scheduler and two single-thread workers without nannies: ``(address, {worker: process})``."""
    from distributed import Client

    address = f"tcp://127.0.0.1:{_port()}"
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    port = address.rsplit(":", 1)[1]
    command = [str(DASK), "scheduler", "--host", "127.0.0.1", "--port", port, "--no-dashboard"]
    procs = [subprocess.Popen(command, **quiet)]
    workers = {}
    try:
        for _ in range(2):
            port = _port()
            proc = subprocess.Popen([str(DASK), "worker", address, "--nthreads", "1", "--no-nanny",
                                     "--host", "127.0.0.1", "--worker-port", str(port), "--no-dashboard"],
                                    **quiet)
            procs.append(proc)
            workers[f"tcp://127.0.0.1:{port}"] = proc
        with Client(address, timeout="30s") as client:
            client.wait_for_workers(2, timeout=60)
        yield address, workers
    finally:
        for proc in reversed(procs):
            proc.kill()
            proc.wait()


def test_a_running_cluster_runs_the_job(cluster, tmp_path):
    job = write_job(tmp_path)
    with pytest.raises(SystemExit) as done:
        main(["batch", str(job), "--scheduler", cluster[0], "-o", str(tmp_path / "out")])
    assert done.value.code == 0
    check_outputs(tmp_path / "out")


def test_a_worker_killed_mid_batch_leaves_every_output_complete(cluster, tmp_path):
    from distributed import Client

    address, workers = cluster
    job = write_job(tmp_path, size=160)
    result = {}
    thread = threading.Thread(target=lambda: result.setdefault("report", run_batch(job, scheduler=address)))
    killed = None
    with Client(address) as watcher:
        thread.start()
        deadline = time.monotonic() + 60
        while killed is None and time.monotonic() < deadline:
            for worker, keys in watcher.processing().items():
                if any(str(k).startswith("render-") for k in keys) and worker in workers:
                    workers[worker].kill()
                    killed = worker
                    break
            time.sleep(0.02)
    thread.join(timeout=120)
    assert killed is not None, "no render task was seen running"
    report = result["report"]
    assert report.count("done") == 4, [r.message for r in report.results]
    check_outputs(tmp_path / "job_outputs")
