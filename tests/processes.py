"""Processes a test starts (a Dask scheduler and its workers): wait for them, stop them with their children."""

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

#: where the test interpreter's console scripts (``dask``) are
VENV_BIN = Path(sys.executable).parent


def wait_for(predicate, timeout: float, what: str):
    """``predicate()`` once it is truthy, polling every 50 ms; an AssertionError after ``timeout`` s."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"timed out waiting for {what}")


def stop(proc: subprocess.Popen) -> None:
    """End a process this test started, with the processes it started (its own process group)."""
    if proc.poll() is None:
        os.killpg(proc.pid, signal.SIGTERM)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@contextlib.contextmanager
def dask_cluster(directory: Path, workers: int = 2, env: dict | None = None):
    """A Dask cluster started as docs/validation.md says: ``dask scheduler --scheduler-file``, then ``dask worker``
    (``workers`` processes, one thread each); yields the scheduler file once its address is written, and stops
    scheduler and workers on exit."""
    path = directory / "scheduler.json"
    common = dict(cwd=directory, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    procs = []
    try:
        procs.append(subprocess.Popen([str(VENV_BIN / "dask"), "scheduler", "--scheduler-file", str(path),
                                       "--host", "127.0.0.1", "--port", "0", "--no-dashboard"], **common))
        wait_for(lambda: scheduler_address(path), 60, "the scheduler file")
        procs.append(subprocess.Popen([str(VENV_BIN / "dask"), "worker", "--scheduler-file", str(path),
                                       "--nthreads", "1", "--nworkers", str(workers), "--no-dashboard"],
                                      env=env, **common))
        yield path
    finally:
        for p in reversed(procs):
            stop(p)


def scheduler_address(path: Path) -> str | None:
    """The address in a scheduler file, None while it is not (completely) written."""
    try:
        return json.loads(path.read_text())["address"]
    except (OSError, ValueError, KeyError):
        return None
