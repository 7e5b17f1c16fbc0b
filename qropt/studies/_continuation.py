"""The continuation over one tile of a design chart: plain data in (a tile spec), solved cells out.

In a tile, cells are visited in a serpentine (each next to the last); a cell starts one local solve from the
design of its best certified neighbour. The full default solve runs at the tile's first cell, at the centre of
every ``check`` x ``check`` block (and the better of both designs stays), wherever the warm start fails or
jumps branch, and where no neighbour has a design; a design better than the continuation's is carried to the
cells around it while it stays better. A tile is plain numbers, so it runs in this process or on a Dask worker
alike (``_dask``).
"""

from __future__ import annotations

import inspect
import time

from qropt.studies._chart import Axis, Cell, axis_kind, problem_at
from qropt.synthesis import starts
from qropt.synthesis.certificate import better
from qropt.synthesis.criteria import sense
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result

JUMP_FLOOR = 0.02  # a step moving the design by less (relative to its largest length) is never a jump
JUMP_RATIO = 4.0  # a jump moves the design this many times faster than the step before it on the same line
BETTER = 1e-7  # relative objective difference that counts as a better design


def solve_tile(spec: dict, solver, progress=None) -> list[Cell]:
    """Solve the block of cells a tile spec describes (plain numbers: ``problem`` as Problem.to_dict, ``x`` and
    ``y`` as [name, values] or None, ``block`` [i0, i1, j0, j1], ``check``) with a Solver; cells in (j, i) order."""
    return _Tile(spec, solver, progress).run()


class _Tile:
    def __init__(self, spec, solver, progress):
        self.problem = Problem.from_dict(spec["problem"])
        self.axes = [Axis(n, tuple(v), axis_kind(self.problem, n)) for n, v in (spec["x"], spec["y"] or ("", ())) if n]
        self.i0, self.i1, self.j0, self.j1 = spec["block"]
        self.check, self.solver, self.progress = spec["check"], solver, progress
        given = inspect.signature(solver.solve).parameters
        self.quiet = {"diagnose": False} if "diagnose" in given else {}
        self.continues = "continue_from" in given
        self.cells: dict[tuple, Cell] = {}

    def run(self) -> list[Cell]:
        for j in range(self.j0, self.j1):
            row = range(self.i0, self.i1)
            for i in row if (j - self.j0) % 2 == 0 else reversed(row):  # serpentine: every cell next to the last
                self.solve_cell((i, j))
                if self.progress:
                    self.progress(1)
        return [self.cells[(i, j)] for j in range(self.j0, self.j1) for i in range(self.i0, self.i1)]

    def at(self, ij, towards=None) -> Problem:
        """The problem at a cell (or halfway to the cell ``towards``)."""
        values = [a.values[k] for a, k in zip(self.axes, ij, strict=False)]
        if towards is not None:
            values = [0.5 * (v + a.values[k]) for v, a, k in zip(values, self.axes, towards, strict=False)]
        return problem_at(self.problem, self.axes, values)

    def warm(self, problem, src: Cell) -> Result:
        """One local solve from a certified neighbour's design, continued from its optimum where the solver can
        (a failure is not explained: the full solve follows)."""
        start = {k: src.params[k] for k in self.problem.free}
        kw = {**self.quiet, "continue_from": src.result} if self.continues else self.quiet
        return self.solver.solve(problem, starts_n=0, use_analytic=False, extra_starts=[start], **kw)

    def neighbours(self, ij):
        i, j = ij
        for n in ((i - 1, j), (i + 1, j), (i, j - 1), (i, j + 1)):
            if self.i0 <= n[0] < self.i1 and self.j0 <= n[1] < self.j1:
                yield n

    def source(self, ij) -> tuple | None:
        """The certified neighbour with the best objective (the first found on a tie)."""
        best = None
        for n in self.neighbours(ij):
            c = self.cells.get(n)
            if c is not None and c.success and (best is None or better(self.problem, c.objective, best.objective)):
                best = c
        return None if best is None else (best.i, best.j)

    def beats(self, a: Result, b: Result) -> bool:
        """Result a is certified and better than b by more than rounding."""
        if not a.success:
            return False
        if not b.success:
            return True
        if a.objective is None or b.objective is None:
            return False
        tol = BETTER * max(1.0, abs(b.objective))
        return better(self.problem, a.objective, b.objective + tol * sense(self.problem.objective))

    def full(self, problem) -> Result:
        """The default solve; a cell it cannot give a design is explained (a closed form that gives every design
        proves it at once, otherwise the reachable ranges are found)."""
        r = self.solver.solve(problem, **self.quiet)
        return self.solver.solve(problem) if r.status == "failed" and self.quiet else r

    def solve_cell(self, ij):
        t0 = time.perf_counter()
        problem = self.at(ij)
        if starts.plan(problem).kind == "enumeration":  # a closed form gives every solution: nothing to continue
            self.cells[ij] = Cell.of(
                *ij, self.full(problem), "full", why="closed form", seconds=time.perf_counter() - t0
            )
            return
        src = self.source(ij)
        warm = self.warm(problem, self.cells[src]) if src else None
        jump = bool(warm is not None and warm.success and self.jumped(ij, src, warm))
        half = self.check // 2
        check = ij[0] % self.check == half and (len(self.axes) == 1 or ij[1] % self.check == half)
        if src is None:
            why = "tile start" if ij == (self.i0, self.j0) else "no certified neighbour"
        else:
            why = "warm start failed" if not warm.success else "jump" if jump else "check" if check else ""
        if not why:
            self.cells[ij] = Cell.of(*ij, warm, "continued", source=src, seconds=time.perf_counter() - t0)
            return
        full = self.full(problem)
        keep_warm = warm is not None and self.beats(warm, full)
        switched = warm is not None and warm.success and self.beats(full, warm)
        kept, method = (warm, "continued") if keep_warm else (full, "full")
        self.cells[ij] = Cell.of(
            *ij, kept, method, why=why, source=src, jump=jump, switched=switched, seconds=time.perf_counter() - t0
        )
        if self.cells[ij].success and (switched or why in ("no certified neighbour", "warm start failed", "jump")):
            self.spread(ij)

    def spread(self, ij):
        """Carry a design that did not come from its neighbours' branch to them, as long as it is better there."""
        queue = [ij]
        while queue:
            u = queue.pop(0)
            for v in self.neighbours(u):
                old = self.cells.get(v)
                if old is None or not old.success:  # unsolved: it starts from the best neighbour in its turn
                    continue
                t0 = time.perf_counter()
                r = self.warm(self.at(v), self.cells[u])
                if self.beats(r, old.result):
                    self.cells[v] = Cell.of(
                        *v, r, "continued", source=u, switched=True, seconds=old.seconds + time.perf_counter() - t0
                    )
                    queue.append(v)

    def jumped(self, ij, src, r: Result) -> bool:
        """Whether the continuation from src to ij left src's branch: the design moves by more than JUMP_FLOOR of
        its size and JUMP_RATIO times faster than on the step before src along the same line; with no such step,
        the step is halved: a branch moves about half as far in each half."""
        step = _distance(self.problem, r.params, self.cells[src].params)
        if step <= JUMP_FLOOR:
            return False
        back = (2 * src[0] - ij[0], 2 * src[1] - ij[1])
        b = self.cells.get(back)
        if b is not None and b.success:
            axis = 0 if back[1] == ij[1] else 1  # the line runs along x or along y
            h1, h0 = (abs(self.axes[axis].values[p[axis]] - self.axes[axis].values[src[axis]]) for p in (ij, back))
            before = _distance(self.problem, self.cells[src].params, b.params)
            return step / h1 > JUMP_RATIO * before / h0
        mid = self.warm(self.at(ij, towards=src), self.cells[src])
        if not mid.success:
            return True
        halves = (
            _distance(self.problem, mid.params, self.cells[src].params),
            _distance(self.problem, r.params, mid.params),
        )
        return max(halves) > 0.75 * step


def _distance(problem, a: dict, b: dict) -> float:
    """The largest change of a free parameter relative to the design's largest length."""
    size = max(abs(b[k]) for k in problem.mechanism.LENGTHS if k in b)
    return max(abs(a[k] - b[k]) for k in problem.free) / size


__all__ = ["solve_tile"]
