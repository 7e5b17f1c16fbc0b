"""The Solver: a synthesis problem -> a certified Result. ``qropt.solve`` is its documented default instance.

A solve runs the Solver's pipeline of strategies once (``qropt.synthesis.search``; ``search.DEFAULT`` unless one is
given): the plan of starts, the multi-start of local solves (``local``: a backend run and the exchange loop), the
global strategies the criterion's capabilities call for, a certificate by exact evaluation, and a Result with every
distinct local optimum, best first; where no start gives a certified design, the diagnosis says why within its
budget.
"""

from __future__ import annotations

import contextlib
import json
import math
import time

import numpy as np

from qropt.errors import ProblemError, QroptError
from qropt.synthesis import evolution, search
from qropt.synthesis import starts as starts_
from qropt.synthesis.backends import Ipopt
from qropt.synthesis.formulation import BASE_SAMPLES, EXTRA_SAMPLES, Formulation, RowKind
from qropt.synthesis.local import Candidate, Formulations, LocalSolve
from qropt.synthesis.multistart import MultiStart
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result
from qropt.synthesis.settings import Settings

TOLERANCES = {"feasibility": 1e-8, "gap": 1e-8}
RANGE_FREE = (RowKind.DEAD_CENTRE, RowKind.ORIENTATION, RowKind.TARGET)  # rows a range's designs need not meet


class Solver:
    """Owns the NLP formulations (built once per problem structure; a dynamic one kept while its masses, loads and
    omega2 are those of one of the last two dynamic tasks, ``Formulations``), the backend and the options of every
    solve.

    tolerances: {'feasibility': largest accepted violation, 'gap': certified minus NLP epigraph value that
    ends the exchange loop}; ipopt_options: merged into IPOPT's (names as CasADi takes them, 'ipopt.tol'; runs
    that start at or near an optimum use a monotone barrier from mu_init 1e-6, unless these name their own);
    samples: uniform epigraph sample angles per formulation (the exchange loop adds up to ``extra`` more);
    starts_n, seed: the Sobol multi-start used where no closed form enumerates the solutions (where none
    enumerates or walks them, starts_n per two free parameters unless a solve names its own); backend: an NLP
    backend (``qropt.synthesis.backends``; default IPOPT); atlas: start a problem whose shape is in the atlas
    (``qropt.synthesis.atlas``) from its designs first, and run the multi-start only where none certifies;
    evolution: where the criterion declares a transmission guard (the peak torque), descents on the exact objective
    from a differential evolution too (the ``Evolution`` and ``Descended`` strategies: the costliest part of a
    four-bar-driven solve, for better designs where the multi-start's basins miss them; False leaves them out);
    evolutions: how many independent evolutions (seeds seed, seed + 1, ...; each with its SQP): the basins they
    reach differ from seed to seed; None: four where the problem has seven free parameters or more, else one
    (``evolution.count``); sqp: where the objective is a peak over the
    turn, each design of the evolution and each Nelder-Mead end descended again by the SQP on the exact peak
    (``minimax.polish``: its ends are first-order stationary but not always better than the ends it starts
    from, so it is off unless asked). Whatever ``sqp`` says, the SQP descends the best
    certified designs and every descent's end once more at the end of a solve (the ``PeakSQP`` strategy);
    settings: the search's tuning numbers (``search.Settings``); pipeline: the strategies a solve runs, in order
    (default ``search.DEFAULT``; a Solver rebuilt from ``options()`` has the default).
    Results do not depend on what the Solver solved before: formulations take every value as a parameter.
    """

    def __init__(
        self,
        *,
        tolerances: dict | None = None,
        ipopt_options: dict | None = None,
        samples: int = BASE_SAMPLES,
        extra: int = EXTRA_SAMPLES,
        starts_n: int = 8,
        seed: int = 0,
        max_rounds: int = 30,
        backend=None,
        atlas: bool = True,
        evolution: bool = True,
        evolutions: int | None = None,
        sqp: bool = False,
        settings: Settings | None = None,
        pipeline=None,
    ):
        tol = {**TOLERANCES, **(tolerances or {})}
        if set(tol) != set(TOLERANCES) or not all(_positive(v) for v in tol.values()):
            raise ProblemError(f"tolerances are positive numbers for {sorted(TOLERANCES)}, got {tolerances!r}")
        for name, v, lo in (
            ("samples", samples, 2),
            ("extra", extra, 1),
            ("starts_n", starts_n, 0),
            ("max_rounds", max_rounds, 1),
        ):
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise ProblemError(f"Solver: {name} must be an integer >= {lo}, got {v!r}")
        if evolutions is not None and (
            isinstance(evolutions, bool) or not isinstance(evolutions, int) or evolutions < 1
        ):
            raise ProblemError(f"Solver: evolutions is None (by the problem) or an integer >= 1, got {evolutions!r}")
        if ipopt_options is not None and not isinstance(ipopt_options, dict):
            raise ProblemError(f"Solver: ipopt_options must be a dict, got {ipopt_options!r}")
        if backend is not None and not callable(getattr(backend, "run", None)):
            raise ProblemError(f"Solver: backend must have a run(form, w0, p, lbx, ubx, warm) method, got {backend!r}")
        self.tolerances, self.ipopt_options = tol, dict(ipopt_options or {})
        self.samples, self.extra, self.starts_n, self.seed, self.max_rounds = samples, extra, starts_n, seed, max_rounds
        for name, v in (("atlas", atlas), ("evolution", evolution), ("sqp", sqp)):
            if not isinstance(v, bool):
                raise ProblemError(f"Solver: {name} is True or False, got {v!r}")
        self.atlas, self.evolution, self.evolutions, self.sqp = atlas, evolution, evolutions, sqp
        if isinstance(settings, dict):
            settings = Settings.from_dict(settings)
        if settings is not None and not isinstance(settings, Settings):
            raise ProblemError(f"Solver: settings is a qropt.synthesis.search.Settings, got {settings!r}")
        self.settings = settings or Settings()
        self.pipeline = search.DEFAULT if pipeline is None else _pipeline(pipeline)
        self.starts = search.starts_of(self.pipeline)
        self.backend = backend or Ipopt(self.ipopt_options)
        self._formulations = Formulations(samples, extra)
        self.local_solve = LocalSolve(self._formulations, self.backend, tol, max_rounds, self.settings)
        self.multistart = MultiStart(self.local_solve, self.settings)

    def __repr__(self):
        return (
            f"Solver(tolerances={self.tolerances}, samples={self.samples}, extra={self.extra}, "
            f"starts_n={self.starts_n}, backend={self.backend.name}, formulations held={self.formulations})"
        )

    def options(self) -> dict:
        """The constructor's options (plain data: a Dask worker rebuilds an equal Solver from them)."""
        return {
            "tolerances": dict(self.tolerances),
            "ipopt_options": dict(self.ipopt_options),
            "samples": self.samples,
            "extra": self.extra,
            "starts_n": self.starts_n,
            "seed": self.seed,
            "max_rounds": self.max_rounds,
            "atlas": self.atlas,
            "evolution": self.evolution,
            "evolutions": self.evolutions,
            "sqp": self.sqp,
            "settings": self.settings.to_dict(),
        }

    def evolutions_of(self, problem: Problem) -> int:
        """The evolutions a solve of ``problem`` runs where they apply: the Solver's, else ``evolution.count``."""
        return self.evolutions if self.evolutions is not None else evolution.count(problem, self.settings)

    # ---- formulations ----------------------------------------------------------------------------
    def formulation(self, problem: Problem, branch: dict, orientation: int, range_target=None, sense=1) -> Formulation:
        """The NLP of this problem structure, built once (immutable: a problem's numbers are passed per solve)."""
        return self._formulations.get(problem, branch, orientation, range_target, sense)

    @property
    def formulations(self) -> int:
        """How many NLPs this Solver holds (``Formulations``: every kinematic one, the last dynamic tasks')."""
        return len(self._formulations)

    def local(self, problem, values0, branch, targets, **kw) -> Candidate:
        """One local solve (see ``LocalSolve.run``)."""
        return self.local_solve.run(problem, values0, branch, targets, **kw)

    # ---- the solve ---------------------------------------------------------------------------------
    def solve(
        self,
        problem: Problem,
        *,
        starts_n: int | None = None,
        use_analytic: bool = True,
        seed: int | None = None,
        targets: dict | None = None,
        max_rounds: int | None = None,
        extra_starts=(),
        diagnose: bool = True,
        continue_from: Result | None = None,
        time_limit: float | None = None,
    ) -> Result:
        """Solve a synthesis problem by one pass of the Solver's pipeline; returns a Result whatever happens (only
        invalid input raises).

        starts_n: Sobol points where no closed form enumerates the solutions (default the Solver's);
        use_analytic: use the closed forms; targets: new values for some targets (the NLP is not rebuilt);
        extra_starts: more starting points (free-parameter dicts), tried first; diagnose: on failure, find why
        (within the diagnosis budget); without it a failure is 'failed' with the backend's reasons, or
        'infeasible' where a closed form that gives every design gives none that is valid; continue_from: a
        Result of a nearby problem (a chart's neighbour) whose design is one of ``extra_starts``: that start is
        continued by Newton on the optimum's active set, verified, before the backend runs (``newton``);
        time_limit: seconds of wall time, after which no strategy starts but those that make the Result of what
        was found (a local solve, an evolution or an SQP under way ends first); the claim names the strategies it
        left out, and a solve without a certified design is 'failed' and not diagnosed.
        """
        t0 = time.perf_counter()
        asked = starts_n is not None
        if continue_from is not None and not isinstance(continue_from, Result):
            raise ProblemError(f"continue_from is a qropt Result, got {type(continue_from).__name__}")
        problem, targets, extra, starts_n, seed, max_rounds = self._check(
            problem, targets, extra_starts, starts_n, seed, max_rounds
        )
        hint = continue_from.continuation if continue_from is not None and extra else None
        time_limit = check_time_limit(time_limit)
        deadline = None if time_limit is None else t0 + time_limit
        context = search.Context(
            self, targets, starts_n, seed, max_rounds, extra, use_analytic, diagnose, asked, hint, t0, deadline
        )
        return search.solve(self.pipeline, problem, context)

    def _check(self, problem, targets, extra_starts, starts_n, seed, max_rounds):
        if not isinstance(problem, Problem):
            raise ProblemError(f"solve takes a qropt.Problem, got {type(problem).__name__}")
        if targets is not None:
            if not isinstance(targets, dict):
                raise ProblemError(f"targets must be a dict of target values, got {targets!r}")
            unknown = sorted(set(targets) - set(problem.targets))
            if unknown:
                raise ProblemError(f"targets {unknown} are not targets of this problem ({sorted(problem.targets)})")
            problem = problem.replace(targets={**problem.targets, **targets})
        extra = []
        if isinstance(extra_starts, (dict, str, bytes)) or not hasattr(extra_starts, "__iter__"):
            raise ProblemError(f"extra_starts is a list of free-parameter dicts, got {extra_starts!r}")
        for v in extra_starts:
            if not isinstance(v, dict) or set(problem.free) - set(v):
                raise ProblemError(f"each extra start gives every free parameter {sorted(problem.free)}, got {v!r}")
            extra.append({k: _real(f"extra start {k}", v[k]) for k in problem.free})
        starts_n = self.starts_n if starts_n is None else starts_n
        max_rounds = self.max_rounds if max_rounds is None else max_rounds
        seed = self.seed if seed is None else seed
        for name, v, lo in (("starts_n", starts_n, 0), ("max_rounds", max_rounds, 1), ("seed", seed, 0)):
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise ProblemError(f"{name} must be an integer >= {lo}, got {v!r}")
        return problem, dict(problem.targets), extra, int(starts_n), int(seed), int(max_rounds)

    # ---- reachable range of one target ---------------------------------------------------------------
    def target_range(self, problem, target, targets=None, *, starts_n=None, seed=None, solves: int | None = None):
        """(low, high) of one target over the free bounds and conditions (other targets dropped); see
        ``target_ranges``. (nan, nan) if no design turns fully."""
        targets = dict(problem.targets if targets is None else targets)
        if target not in targets:
            raise ProblemError(f"{target!r} is not a target of this problem ({sorted(targets)})")
        return self.target_ranges(problem, targets, [target], starts_n=starts_n, seed=seed, solves=solves)[target]

    def target_ranges(
        self, problem, targets, names, *, starts_n=None, seed=None, solves: int | None = None, toward: bool = False
    ):
        """{target: (low, high)} over the free bounds and conditions, each target alone: the exact values of
        ``settings.range_samples`` designs spread over the bounds (with the corners of the bounds and the closed forms'
        points), built once for every target (or the closed form's range where the plan has one), then at most
        ``solves`` local solves per target that push it down and up from the samples nearest each end (``toward``: only
        for a target outside the samples' range). Every value is that of a design found, not a proof of an end; (nan,
        nan) where no design turns."""
        starts_n = self.starts_n if starts_n is None else starts_n
        seed = self.seed if seed is None else seed
        s = self.settings
        solves = s.range_solves if solves is None else solves
        plan = starts_.plan(problem)
        exact = {k: plan.ranges[k] for k in names if k in plan.ranges}  # the closed form's own, where it has one
        names = [k for k in names if k not in exact]
        pts = (
            list(plan.analytic)
            + starts_.corners(problem, s)
            + starts_.rule_points(problem, max(s.range_samples, starts_n), seed, settings=s)
        )
        pts = pts if names else []
        seen = []  # (mechanism, start values, branch)
        for v in pts:
            for br in starts_.branches(problem):
                with contextlib.suppress(QroptError):
                    m = problem.build(v, br)
                    if m.dead_centres().reversals == 1:
                        seen.append((m, v, br))
        if pts and not seen:  # none of the samples turns: a grid screen of many more finds some that do
            for v in starts_.turning_points(problem, max(s.range_samples, starts_n), seed, s):
                for br in starts_.branches(problem):
                    with contextlib.suppress(QroptError):
                        m = problem.build(v, br)
                        if m.dead_centres().reversals == 1:
                            seen.append((m, v, br))
        out = dict(exact)
        for target in names:
            if not seen:
                out[target] = (math.nan, math.nan)
                continue

            def value(m, target=target):
                return m.time_ratio() if target == "time_ratio" else m.stroke()

            values = [value(m) for m, _, _ in seen]
            sub = problem.replace(targets={target: targets[target]})
            per_end = solves // 2
            if toward and min(values) <= targets[target] <= max(values):
                out[target] = (float(min(values)), float(max(values)))  # inside the samples: nothing to push
                continue
            for sense in (1, -1):  # minimise, then maximise, from the samples nearest that end
                for _, v, br in sorted(seen, key=lambda s, sense=sense: sense * value(s[0]))[:per_end]:
                    c = self.local(
                        sub, v, br, {target: targets[target]}, max_rounds=3, range_target=target, sense=sense
                    )
                    form = self.formulation(sub, br, c.orientation, target, sense)
                    m = c.mechanism
                    conditions = [x for k, x in c.residuals.items() if form.row_kind(k) not in RANGE_FREE]
                    if m is not None and m.dead_centres().reversals == 1 and max(conditions, default=0.0) <= 1e-9:
                        values.append(value(m))  # the exact value of a design that meets every condition
            out[target] = (float(min(values)), float(max(values)))
        return out


def _pipeline(stages) -> tuple:
    """A pipeline as given: strategies (``search.Strategy``), at least one."""
    if isinstance(stages, (str, bytes, dict)) or not hasattr(stages, "__iter__"):
        raise ProblemError(f"Solver: pipeline is a list of strategies, got {stages!r}")
    stages = tuple(stages)
    bad = [s for s in stages if not isinstance(s, search.Strategy)]
    if not stages or bad:
        raise ProblemError(
            f"Solver: each stage of a pipeline has a name, accepts(problem, plan) and run(problem, pool, context), "
            f"got {bad[0] if bad else 'none'!r}"
        )
    return stages


def check_time_limit(v) -> float | None:
    """A time limit as given: None, or a positive finite number of seconds (ProblemError otherwise)."""
    if v is None:
        return None
    if not _positive(v) or v > 1e12:
        raise ProblemError(f"time_limit is a positive number of seconds (or None), got {v!r}")
    return float(v)


def _positive(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0


def _real(name, v) -> float:
    try:
        ok = (
            isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool) and math.isfinite(float(v))
        )
    except OverflowError:
        ok = False
    if not ok:
        raise ProblemError(f"{name} must be a finite number, got {v!r}")
    return float(v)


DEFAULT = Solver()
_SHARED: dict = {}  # per process: the Solver of each option set


def not_rebuilt(solver: Solver) -> str | None:
    """Why a Solver built elsewhere (a worker process) from ``solver.options()`` would not solve as ``solver`` does:
    a backend given to it, which the options do not carry; None where it would."""
    if solver.pipeline is not search.DEFAULT:
        return "a Solver rebuilt from Solver.options() runs the default pipeline, not the one given to this one"
    if type(solver.backend) is Ipopt and solver.backend.given == solver.ipopt_options:
        return None
    return (
        f"a Solver rebuilt from Solver.options() does not carry the backend given to this one "
        f"({solver.backend.name!r}; IPOPT options go in Solver(ipopt_options=...))"
    )


def shared(options: dict, solver: Solver | None = None) -> Solver:
    """This process's Solver for ``options`` (``Solver.options()``): the first given, else one built once (a
    worker process's, whose formulations stay built from one task to the next; a process forked after a Solver
    was given here starts with its formulations)."""
    key = json.dumps(options, sort_keys=True, default=str)
    if key not in _SHARED:
        _SHARED[key] = solver or Solver(**options)
    return _SHARED[key]


def solve(problem: Problem, **options) -> Result:
    """Solve with the default Solver (``qropt.synthesis.solver.DEFAULT``); options as ``Solver.solve``."""
    return DEFAULT.solve(problem, **options)


def target_range(problem, target, targets=None, **options):
    """(low, high) of one target with the default Solver; see ``Solver.target_range``."""
    return DEFAULT.target_range(problem, target, targets, **options)


__all__ = ["Solver", "DEFAULT", "solve", "target_range", "TOLERANCES"]
