"""Problems solved in worker processes: ``design(..., workers=k)`` solves its rows k at a time.

The pool is kept between calls (its processes keep the NLPs they built, so a second call is warm) and replaced
when a call asks for another number of workers; it is shut down when the interpreter exits. Its processes are
forked where the system can (a script needs no ``if __name__ == "__main__"`` guard; elsewhere they are spawned),
and each solves with the caller's Solver as it was when forked, or with one built from ``Solver.options()``
(once per option set): a solve's result does not depend on what a solver solved before, so the rows are those
of a solve in this process. A problem travels pickled: one
whose mechanism type a process cannot import by name (defined in ``__main__`` or a notebook, or built at run
time) is solved in this process instead. The largest problems (by free parameters) are given out first.
Ctrl-C is the caller's: the workers ignore it, and the caller's KeyboardInterrupt stops them at once (``stop``).
"""

from __future__ import annotations

import atexit
import concurrent.futures as cf
import importlib
import multiprocessing
import os
import signal

from qropt.errors import ProblemError, QroptError

MAX_WORKERS_PER_CPU = 4  # worker processes (one IPOPT each) per CPU; more only share the same cores
_POOL: dict = {}  # "executor": the pool, "key": its size and the criteria it was started with


def max_workers() -> int:
    """The most worker processes a pool (or a chart's local Dask cluster) may start on this machine."""
    return MAX_WORKERS_PER_CPU * (os.cpu_count() or 1)


def check_workers(workers) -> int:
    """``workers`` as an int in [1, ``max_workers()``], or ProblemError naming what is allowed."""
    limit = max_workers()
    if isinstance(workers, bool) or not isinstance(workers, int) or not 1 <= workers <= limit:
        raise ProblemError(
            f"workers is a number of worker processes in [1, {limit}] ({MAX_WORKERS_PER_CPU} per CPU, "
            f"{os.cpu_count() or 1} CPUs), got {workers!r}"
        )
    return workers


def portable(problem) -> bool:
    """Whether a fresh process imports the problem's mechanism type by its module and name."""
    cls = problem.mechanism
    if cls.__module__ in ("__main__", "__mp_main__") or "<" in cls.__qualname__:
        return False
    try:
        obj = importlib.import_module(cls.__module__)
        for part in cls.__qualname__.split("."):
            obj = getattr(obj, part)
    except (ImportError, AttributeError):
        return False
    return obj is cls


def _executor(workers: int) -> cf.ProcessPoolExecutor:
    """The pool of ``workers`` processes, started anew where the criteria registered here changed since it was
    (a criterion registered after a fork is unknown to the forked processes)."""
    from qropt.synthesis.criteria import CRITERIA

    key = (workers, tuple((name, id(c)) for name, c in CRITERIA.items()))
    if _POOL.get("key") != key:
        shutdown()
        ctx = multiprocessing.get_context("fork" if "fork" in multiprocessing.get_all_start_methods() else "spawn")
        pool = cf.ProcessPoolExecutor(workers, mp_context=ctx, initializer=_quiet)
        _POOL["executor"], _POOL["key"] = pool, key
    return _POOL["executor"]


def _quiet() -> None:
    """In a worker: Ctrl-C is the caller's to handle (it stops the workers), not each worker's."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _taken() -> cf.ProcessPoolExecutor | None:
    """The pool, forgotten here (a later call starts a new one); None where there is none."""
    _POOL.pop("key", None)
    return _POOL.pop("executor", None)


@atexit.register
def shutdown() -> None:
    """Stop the pool's processes (a later call starts new ones)."""
    ex = _taken()
    if ex is not None:
        ex.shutdown(wait=True, cancel_futures=True)


def _solve(problem, options: dict, time_limit=None):
    """Run in a worker: the problem solved by this process's Solver for ``options``."""
    from qropt.synthesis.solver import shared

    return shared(options).solve(problem, time_limit=time_limit)


def solve_all(problems: dict, solver, workers: int, done=None, time_limit=None) -> dict:
    """{key: Result} of every problem, solved by ``workers`` processes with Solvers equal to ``solver`` (the
    largest problems, by free parameters, given out first; a problem that cannot travel solved here); ``done``
    is called with each key as its result arrives; time_limit: each solve's (s), or None. A lost worker is a
    ProblemError naming it."""
    from qropt.synthesis.solver import not_rebuilt, shared

    why = not_rebuilt(solver)
    if why:
        raise ProblemError(f"workers solve with Solvers of their own: {why}; solve in this process (workers=None)")
    options = solver.options()
    shared(options, solver)  # a pool forked from here starts with its formulations
    here = {k: p for k, p in problems.items() if not portable(p)}
    away = sorted((k for k in problems if k not in here), key=lambda k: -len(problems[k].free))
    out = {}
    try:
        ex = _executor(workers)
        futures = {ex.submit(_solve, problems[k], options, time_limit): k for k in away}
        for k, p in here.items():
            out[k] = solver.solve(p, time_limit=time_limit)
            if done:
                done(k)
        for fut in cf.as_completed(futures):
            k = futures[fut]
            out[k] = fut.result()
            if done:
                done(k)
    except QroptError:
        raise
    except Exception as e:  # noqa: BLE001 - a lost worker or a broken pool: one line naming it
        shutdown()
        first = str(e).splitlines()[0] if str(e) else ""
        raise ProblemError(f"a worker process failed ({type(e).__name__}: {first}); the pool is restarted") from None
    except BaseException:  # interrupted (Ctrl-C): the workers stop now, not when their rows are done
        stop()
        raise
    return {k: out[k] for k in problems}


def stop() -> None:
    """Stop the pool's processes at once, their rows unfinished (a later call starts new ones): killed, as a
    worker has nothing to save."""
    ex = _taken()
    if ex is not None:
        for proc in list(getattr(ex, "_processes", {}).values()):
            proc.kill()
        ex.shutdown(wait=False, cancel_futures=True)


__all__ = ["check_workers", "max_workers", "portable", "shutdown", "solve_all", "stop"]
