"""Running the CLI in-process on generated input, and the property every run must have.

A run ends one of three ways: exit 0 with a valid result, exit 2 with one line
``toonmotion: error: ...`` on stderr, or a failure of the property: any other exit status (70
is toonmotion's own "internal error"), a second line, a traceback or a library warning on
stderr, a refusal that should have been an exit 2 (``must_refuse``), longer than the time limit,
or a pre-existing output changed by a failing run.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import os
import resource
import signal
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

from toonmotion import limits
from toonmotion.cli import main

# Seconds one run may take: a hang is a failure.
TIME_LIMIT = float(os.environ.get("TOONMOTION_FUZZ_TIME_LIMIT", "60"))

# A run that asks for more memory than this fails with MemoryError (exit 70) instead of taking
# the machine down: every limit must hold well below it. Set for each run only, not for the
# rest of the test session (a browser reserves far more address space than it uses).
MEMORY = int(float(os.environ.get("TOONMOTION_FUZZ_MEMORY_GB", "8")) * 2**30)

# Runs per format and outcome, for the long profile's report.
TALLY: Counter[tuple[str, str]] = Counter()


class Hang(BaseException):
    """Raised in a run that outlives :data:`TIME_LIMIT` (a BaseException: the CLI must not catch it)."""


@dataclass(frozen=True)
class Outcome:
    status: int | None  # None: hung
    stdout: str
    stderr: str
    seconds: float


def run_cli(argv: list[str], cwd: Path) -> Outcome:
    """``toonmotion ARGV`` in ``cwd``, in this process, with its output captured."""
    out, err = io.StringIO(), io.StringIO()
    before = os.getcwd()

    def hang(signum, frame):
        raise Hang

    previous = signal.signal(signal.SIGALRM, hang)
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    cap = MEMORY if hard == resource.RLIM_INFINITY else min(MEMORY, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    signal.setitimer(signal.ITIMER_REAL, TIME_LIMIT)
    start = time.perf_counter()
    status: int | None
    try:
        os.chdir(cwd)
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main(argv)
            except SystemExit as done:
                status = done.code if isinstance(done.code, int) else (0 if done.code is None else 1)
            else:  # pragma: no cover - main always exits
                status = 0
    except Hang:
        status = None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))
        os.chdir(before)
        limits.set_limits(limits.Limits())
    return Outcome(status, out.getvalue(), err.getvalue(), time.perf_counter() - start)


def digest(path: Path) -> str | None:
    """A fingerprint of a file or a folder's files (None when absent), to see that nothing changed."""
    if path.is_file():
        return hashlib.sha256(path.read_bytes()).hexdigest()
    if path.is_dir():
        files = sorted(p for p in path.rglob("*") if p.is_file())
        return hashlib.sha256(
            json.dumps([(str(p.relative_to(path)), digest(p)) for p in files]).encode()
        ).hexdigest()
    return None


def check(
    outcome: Outcome, *, kind: str, must_refuse: bool, kept: dict[Path, str | None] | None = None, valid=None
) -> None:
    """Assert the property (module docstring); ``kept`` maps pre-existing outputs to their digest.

    ``valid()`` is called after a successful run to check its result; ``kind`` names the format
    or command for :data:`TALLY`.
    """
    if outcome.status is None:
        TALLY[kind, "hang"] += 1
        raise AssertionError(f"hung: no result after {TIME_LIMIT:g} s")
    lines = outcome.stderr.splitlines()
    if outcome.status == 2:
        TALLY[kind, "refused"] += 1
        assert len(lines) == 1 and lines[0].startswith("toonmotion: error: "), (
            f"a refusal must be one line, got {outcome.stderr!r}"
        )
        for path, before in (kept or {}).items():
            assert digest(path) == before, f"a failed run changed {path.name}: {lines[0]}"
        return
    if outcome.status == 0:
        TALLY[kind, "accepted"] += 1
        assert not must_refuse, f"accepted input that should have been refused; stdout {outcome.stdout!r}"
        assert "Traceback" not in outcome.stderr and "Warning" not in outcome.stderr, outcome.stderr
        if valid is not None:
            valid()
        return
    TALLY[kind, f"exit {outcome.status}"] += 1
    raise AssertionError(f"exit status {outcome.status}: {outcome.stderr!r}")
