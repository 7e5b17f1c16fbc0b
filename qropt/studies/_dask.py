"""The executors of a design chart's tiles: in this process, or on a Dask cluster.

``'local'`` starts a ``dask.distributed.LocalCluster`` for the chart's duration (at most
``_workers.MAX_WORKERS_PER_CPU`` worker processes per CPU); any other string is the address of a running
scheduler (``dask scheduler`` and ``dask worker ADDRESS`` on the machines, or a dask-jobqueue cluster's
``scheduler_address``), which must answer within CONNECT_TIMEOUT seconds. A tile travels as plain numbers to
``worker_tile`` (pickled by reference: it stays importable as ``qropt.studies._dask.worker_tile``), which builds
its Solver once per worker process (IPOPT is not thread-safe: one thread per worker process). Dask is imported
only when a cluster is used.
"""

from __future__ import annotations

import contextlib
import logging
import os

from qropt.errors import ChartError, ProblemError, QroptError
from qropt.studies import _workers
from qropt.studies._chart import Cell
from qropt.studies._continuation import solve_tile

CONNECT_TIMEOUT = 5  # s
# Dask's workers return freed memory to the system at once (MALLOC_TRIM_THRESHOLD_=65536); a solve allocates
# and frees many small arrays, and that setting slows a tile down: the local cluster leaves glibc's
# own threshold (give a running cluster's workers MALLOC_TRIM_THRESHOLD_=1073741824 for the same)
LOCAL_CONFIG = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}


def check_workers(workers: int) -> int:
    """``workers`` for a local cluster (``_workers.check_workers``'s rule), or ChartError naming a Dask cluster
    for more."""
    try:
        return _workers.check_workers(workers)
    except ProblemError as e:
        raise ChartError(f"{e}; use a Dask cluster (scheduler='tcp://...') for more") from None


def run_here(specs: list, solver, progress) -> list:
    """Every tile in this process, in order."""
    return [solve_tile(s, solver, progress) for s in specs]


def worker_tile(spec: dict, options: dict) -> list[dict]:
    """Run on a worker: one tile with this process's Solver for ``options``; the cells as dictionaries."""
    from qropt.synthesis.solver import shared

    return [c.to_dict() for c in solve_tile(spec, shared(options))]


@contextlib.contextmanager
def _client(mode: str, workers: int | None):
    import dask
    from distributed import Client, LocalCluster

    if mode == "local":
        n = check_workers(workers or os.cpu_count() or 1)
        cluster = client = None
        try:
            with dask.config.set(LOCAL_CONFIG):
                cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",
                    silence_logs=logging.ERROR,
                )
            client = Client(cluster)
        except Exception as e:  # noqa: BLE001 - no ports, processes or memory: one line naming the cause
            for started in (client, cluster):
                if started is not None:
                    with contextlib.suppress(Exception):
                        started.close()
            first = str(e).splitlines()[0] if str(e) else ""
            raise ChartError(
                f"cannot start a local Dask cluster of {n} worker processes ({type(e).__name__}: {first})"
            ) from None
        with cluster, client:
            yield client, f"local cluster of {n} worker processes"
        return
    try:
        client = Client(mode, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError, TypeError) as e:
        first = str(e).splitlines()[0] if str(e) else ""
        raise ChartError(
            f"cannot reach the Dask scheduler at {mode!r} within {CONNECT_TIMEOUT} s ({type(e).__name__}: {first})"
        ) from None
    with client:
        yield client, f"Dask cluster at {mode} ({len(client.scheduler_info().get('workers', {}))} workers)"


def run_dask(specs: list, solver, mode: str, workers: int | None, progress) -> tuple[list, str]:
    """Every tile on a Dask cluster, the largest first and one tile per worker thread at a time (each worker takes
    the next tile when it is free, so the load balances without work stealing); (tiles of Cells in the order of
    specs, the cluster)."""
    from distributed import as_completed

    from qropt.synthesis.solver import not_rebuilt

    why = not_rebuilt(solver)
    if why:  # the tiles would be solved with another backend than the one given
        raise ChartError(f"a chart's Dask workers solve with Solvers of their own: {why}; chart in this process")
    options = solver.options()  # plain values: what a worker needs to build the same Solver
    order = sorted(range(len(specs)), key=lambda k: -_size(specs[k]))
    with _client(mode, workers) as (client, where):
        slots = max(1, sum(client.nthreads().values()))
        out: list = [None] * len(specs)
        futures = {}

        def submit(k):
            futures[client.submit(worker_tile, specs[k], options, pure=False)] = k

        pending = iter(order)
        for k in [k for _, k in zip(range(slots), pending, strict=False)]:
            submit(k)
        try:
            running = as_completed(list(futures))
            for fut in running:
                k = futures.pop(fut)
                out[k] = fut.result()
                progress(_size(specs[k]))
                nxt = next(pending, None)
                if nxt is not None:
                    submit(nxt)
                    running.add(next(f for f, j in futures.items() if j == nxt))
        except QroptError:  # raised by a tile: as it is
            raise
        except Exception as e:  # noqa: BLE001 - a lost worker or a broken cluster: one line naming it
            raise ChartError(f"the Dask cluster failed to solve a tile ({type(e).__name__}: {e})") from None
    return [[Cell.from_dict(d) for d in tile] for tile in out], where


def _size(spec) -> int:
    i0, i1, j0, j1 = spec["block"]
    return (i1 - i0) * (j1 - j0)


__all__ = ["run_here", "run_dask", "worker_tile", "check_workers"]
