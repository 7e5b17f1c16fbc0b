"""Long solves in worker processes (IPOPT is not thread-safe) behind a bounded queue, with progress,
cancellation and a time limit.

Each worker slot is a thread of the server that owns one child process (started with ``spawn``, so nothing of
the server's state is shared) and hands it one job at a time through a pipe. A cancelled or overdue job's process
is killed and a new one started for the next job. The child loads the problem files the app was started with, so
that a user's types are known there too. Finished jobs are kept (the last ``KEEP``) for their results.
"""

from __future__ import annotations

import itertools
import multiprocessing
import queue
import threading
import time
import traceback

KEEP = 200  # finished jobs remembered


def _solve(payload: dict, progress) -> dict:
    """A Problem (its dict) solved: the Result's dict."""
    from qropt.synthesis.problem import Problem
    from qropt.synthesis.result import json_safe
    from qropt.synthesis.solver import solve

    progress(0, 1)
    r = solve(Problem.from_dict(payload))
    progress(1, 1)
    return json_safe(r.to_dict())


def _design(payload: dict, progress) -> dict:
    """``design``'s arguments (masses, loads and drive as dicts; ``time_limit`` the budget of the whole comparison): the
    Comparison's JSON, each row with the type its design opens as ("mechanism"), that type's parameter kinds
    ("kinds"), its certificate's global claim ("claim": with a budget, it names the strategies the budget left
    out), why it has no design in a sentence ("words", ``api.row_words``) and what makes a design doubtful
    ("warnings", ``api.row_warnings``)."""
    import json

    from qropt.app.api import row_warnings, row_words
    from qropt.dynamics.drive import Drive
    from qropt.dynamics.model import Loads, Masses
    from qropt.mechanisms import type_reference
    from qropt.studies import design
    from qropt.studies._design import TYPES, _types

    args = dict(payload)
    if args.get("masses") is not None:
        args["masses"] = Masses.from_dict(args["masses"])
    if args.get("loads") is not None:
        args["loads"] = Loads.from_dict(args["loads"])
    if args.get("drive") is not None:
        args["drive"] = Drive.from_dict(args["drive"])
    total, done = len(_types(args.get("types") or list(TYPES))), [0]

    def step(k=1):
        done[0] += k
        progress(done[0], total)

    c = design(progress=step, **args)
    out = json.loads(c.to_json())
    for row, r in zip(out["rows"], c.rows, strict=True):
        m, cert = r.result.mechanism, r.result.certificate
        row["mechanism"] = None if m is None else type_reference(type(m))
        row["claim"] = cert.global_claim if cert is not None else None
        row["kinds"] = None if m is None else type(m).kinds()
        if r.success:
            row["words"], row["warnings"] = "", row_warnings(row, c.time_ratio, c.stroke, c.omega2)
        else:
            found = r.result.reachable
            row["words"] = row_words(r.result.status, found, c.time_ratio, c.stroke, c.units)
            row["warnings"] = []
    return out


def _pareto(payload: dict, progress) -> dict:
    """``{problem, objectives, n}``: the front's criteria, values and each point's design."""
    from qropt.studies import pareto
    from qropt.synthesis.problem import Problem
    from qropt.synthesis.result import json_safe

    n, done = payload["n"], [0]

    def tick(k=1):
        done[0] += k
        progress(done[0], n)

    f = pareto(Problem.from_dict(payload["problem"]), tuple(payload["objectives"]), n, progress=tick)
    return json_safe(
        {
            "objectives": list(f.objectives),
            "criteria": list(f.criteria),
            "values": [list(v) for v in f.values],
            "points": [{"status": r.status, "params": dict(r.params)} for r in f.points],
            "removed": [list(r) for r in f.removed],
            "units": f.problem.units,
        }
    )


def _report(payload: dict, progress) -> dict:
    """``{type, params, units?, theta2?, omega2?}``: the design's HTML report (``report.design_page``)."""
    from qropt.app.api import mechanism, report_input
    from qropt.io.report import design_page

    d = report_input(payload)
    return {"html": design_page(mechanism(d), d["theta2"], d["omega2"])}


WORK = {"solve": _solve, "design": _design, "pareto": _pareto, "report": _report}  # kind -> what a worker runs


def _child(conn, files) -> None:  # pragma: no cover - runs in the worker process
    from qropt.cli import load_problem
    from qropt.errors import QroptError

    for f in files:
        load_problem(f)
    while True:
        try:
            job = conn.recv()
        except (EOFError, KeyboardInterrupt):
            return
        if job is None:
            return
        kind, payload = job
        try:
            out = WORK[kind](payload, lambda d, t: conn.send(("progress", d, t)))
            conn.send(("done", out))
        except QroptError as e:
            conn.send(("error", f"{type(e).__name__}: {e}"))
        except Exception as e:  # a bug, not the input: said in one line, the traceback in the server's log
            traceback.print_exc()
            conn.send(("error", f"internal error ({type(e).__name__}): {e}"))


class Job:
    """One job's state: queued, running, done, failed, cancelled or timeout."""

    def __init__(self, jid: str, kind: str, payload: dict):
        self.id, self.kind, self.payload = jid, kind, payload
        self.state, self.progress, self.result, self.error = "queued", [0, None], None, None
        self.created, self.started, self.finished = time.time(), None, None
        self.cancel = threading.Event()
        self.ended = threading.Event()

    def to_dict(self, result: bool = True) -> dict:
        now = self.finished or time.time()
        d = {
            "id": self.id,
            "kind": self.kind,
            "state": self.state,
            "progress": {"done": self.progress[0], "total": self.progress[1]},
            "seconds": round(now - (self.started or now), 3),
            "error": self.error,
        }
        if result and self.state == "done":
            d["result"] = self.result
        return d


class Busy(Exception):
    """The queue is full."""


class Jobs:
    """``workers`` worker processes, at most ``queue_size`` jobs waiting, each job at most ``time_limit`` s."""

    def __init__(self, workers: int = 1, queue_size: int = 8, time_limit: float = 300.0, files=()):
        self.time_limit, self.files = float(time_limit), tuple(files)
        self._queue: queue.Queue = queue.Queue(maxsize=queue_size)
        self._jobs: dict[str, Job] = {}
        self._ids = itertools.count(1)
        self._lock = threading.Lock()
        self._ctx = multiprocessing.get_context("spawn")
        self._slots = [_Slot(self) for _ in range(workers)]
        for s in self._slots:
            s.start()

    def submit(self, kind: str, payload: dict) -> Job:
        if kind not in WORK:
            raise ValueError(kind)
        with self._lock:
            job = Job(str(next(self._ids)), kind, payload)
            try:
                self._queue.put_nowait(job)
            except queue.Full:
                raise Busy(f"{self._queue.maxsize} jobs are waiting; try again when one has finished") from None
            self._jobs[job.id] = job
            done = [j for j in self._jobs.values() if j.ended.is_set()]
            for j in done[: max(0, len(done) - KEEP)]:
                del self._jobs[j.id]
        return job

    def get(self, jid: str) -> Job | None:
        return self._jobs.get(jid)

    def cancel(self, jid: str) -> Job | None:
        job = self._jobs.get(jid)
        if job is not None and not job.ended.is_set():
            job.cancel.set()
            if job.state == "queued":
                self._end(job, "cancelled", "cancelled before it started")
        return job

    def _end(self, job: Job, state: str, error: str | None = None, result=None) -> None:
        with self._lock:
            if job.ended.is_set():
                return
            job.state, job.error, job.result, job.finished = state, error, result, time.time()
            job.ended.set()

    def close(self) -> None:
        for s in self._slots:
            s.stop()


class _Slot(threading.Thread):
    """A worker slot: takes jobs from the queue and runs each in its child process."""

    def __init__(self, jobs: Jobs):
        super().__init__(daemon=True)
        self.jobs, self.proc, self.conn, self._stop = jobs, None, None, threading.Event()

    def _spawn(self) -> None:
        parent, child = self.jobs._ctx.Pipe()
        self.proc = self.jobs._ctx.Process(target=_child, args=(child, self.jobs.files), daemon=True)
        self.proc.start()
        self.conn = parent

    def _kill(self) -> None:
        proc, self.proc, self.conn = self.proc, None, None
        if proc is not None and proc.pid is not None:  # (a process still starting is a daemon: it ends with us)
            proc.kill()
            proc.join(5)

    def stop(self) -> None:
        self._stop.set()
        self._kill()

    def run(self) -> None:
        self._spawn()  # warm: the first job does not wait for the imports
        while not self._stop.is_set():
            try:
                job = self.jobs._queue.get(timeout=0.2)
            except queue.Empty:
                continue
            if job.ended.is_set():
                continue
            self._run(job)

    def _run(self, job: Job) -> None:
        jobs = self.jobs
        if self.proc is None or not self.proc.is_alive():
            self._spawn()
        job.state, job.started = "running", time.time()
        deadline = job.started + jobs.time_limit
        self.conn.send((job.kind, job.payload))
        while True:
            if job.cancel.is_set():
                self._kill()
                return jobs._end(job, "cancelled", "cancelled while running")
            if time.time() > deadline:
                self._kill()
                return jobs._end(job, "timeout", f"stopped at the time limit of {jobs.time_limit:g} s")
            try:
                ready = self.conn.poll(0.05)
            except (OSError, EOFError):
                ready = False
            if not ready:
                if not self.proc.is_alive():
                    self._kill()
                    return jobs._end(job, "failed", "the worker process ended unexpectedly")
                continue
            try:
                msg = self.conn.recv()
            except (OSError, EOFError):
                self._kill()
                return jobs._end(job, "failed", "the worker process ended unexpectedly")
            if msg[0] == "progress":
                job.progress = [msg[1], msg[2]]
            elif msg[0] == "done":
                return jobs._end(job, "done", result=msg[1])
            else:
                return jobs._end(job, "failed", msg[1])
