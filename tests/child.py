"""Python code run in a child process, so that a crash or a hang is the calling test's failure, not the run's."""

from __future__ import annotations

import multiprocessing
import os
import subprocess
import sys
import tempfile


def run_child(code: str, timeout: float, **kw) -> str:
    """The stdout of ``python -c code`` (``kw``: subprocess.run's cwd, env); a non-zero exit fails the test with
    the end of its stderr, and a run past ``timeout`` seconds is killed and fails it."""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=timeout, **kw)
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-2000:]}"
    return done.stdout


_FORKS = multiprocessing.get_context("forkserver")
_FORKS.set_forkserver_preload(["qropt.cli", "tests.child"])


def _cli(argv: list[str], cwd: str, out: str) -> None:
    from qropt.cli import main  # imported already: the fork server preloads it

    os.chdir(cwd)
    with open(out, "wb") as f:  # the command's stdout and stderr, from Python and from C
        os.dup2(f.fileno(), 1)
        os.dup2(f.fileno(), 2)
    sys.exit(main(argv))


def run_cli(argv: list[str], cwd, timeout: float) -> tuple[int, str]:
    """``qropt ARGV`` run by the entry point's function (``qropt.cli.main``) in a new process forked from one that
    has imported qropt (a fresh process without the interpreter's and the imports' start-up), in ``cwd``: its exit
    code and its output (stdout and stderr together). A run past ``timeout`` seconds is killed and fails the test."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out")
        p = _FORKS.Process(target=_cli, args=(list(argv), str(cwd), out))
        p.start()
        p.join(timeout)
        if p.is_alive():
            p.kill()
            p.join()
            raise AssertionError(f"qropt {' '.join(argv)}: still running after {timeout} s")
        with open(out, encoding="utf-8", errors="replace") as f:
            return p.exitcode, f.read()
