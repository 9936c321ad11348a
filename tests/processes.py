"""Processes a test starts (a Dask scheduler and its workers): wait for them, stop them with their children."""

import os
import signal
import subprocess
import time


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
