"""Python code run in a child process, so that a crash or a hang is the calling test's failure, not the run's."""

from __future__ import annotations

import subprocess
import sys


def run_child(code: str, timeout: float, **kw) -> str:
    """The stdout of ``python -c code`` (``kw``: subprocess.run's cwd, env); a non-zero exit fails the test with
    the end of its stderr, and a run past ``timeout`` seconds is killed and fails it."""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, **kw)
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-2000:]}"
    return done.stdout
