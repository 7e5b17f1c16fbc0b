"""The Solver: a synthesis problem -> a certified Result. ``qropt.solve`` is its documented default instance.

A solve walks down once through three parts: a plan of starts (``qropt.synthesis.starts``), the multi-start
(``multistart``: closed forms first, then space-filling) of local solves (``local``: a backend run and the
exchange loop), a certificate by exact evaluation, and a Result with every distinct local optimum, best first.
Where no start gives a certified design, the diagnosis (``diagnosis``) says why within a bounded budget.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import math
import time

import numpy as np

from qropt.errors import ProblemError, QroptError
from qropt.synthesis import criteria, evolution, minimax, scaling
from qropt.synthesis import starts as starts_
from qropt.synthesis.backends import Ipopt, Status
from qropt.synthesis.certificate import Certificate, Designs, objective_value, quantities, residuals
from qropt.synthesis.diagnosis import Diagnosis
from qropt.synthesis.formulation import BASE_SAMPLES, EXTRA_SAMPLES, Formulation, RowKind
from qropt.synthesis.local import Candidate, Formulations, LocalSolve
from qropt.synthesis.multistart import MultiStart, distinct, score
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result

TOLERANCES = {"feasibility": 1e-8, "gap": 1e-8}
TIE_TOL = 1e-9  # relative: designs this close to an optimum tie with it (see Solver.least_size)
STANDS = 1e-6  # relative: a descent's end this much better than every certified design is the result (descended)
POLISHED = 3  # the best certified designs the SQP on the exact peak descends again (with every descent's end)
REFRESHES = 3  # a dynamic objective's best design solved again from itself at most this often (Solver.refreshed)
RANGE_SAMPLES = 64  # designs spread over the bounds whose exact target values start a reachable range
RANGE_SOLVES = 4  # local solves that push a reachable range's ends out from the samples
RANGE_FREE = (RowKind.DEAD_CENTRE, RowKind.ORIENTATION, RowKind.TARGET)  # rows a range's designs need not meet
TIE_SCAN = 24  # common scales of a continuum's tied lengths evaluated exactly, log-spaced over what the bounds allow
TIE_BISECT = 24  # bisections of the least scale whose size is the least (to 2^-24 of a scan step)


def _relabelled(r: Result) -> Result:
    """A certified design as another local optimum (a better design stands before it)."""
    claim = r.message.split("; global: ", 1)[-1]
    return dataclasses.replace(r, status="local_optimum", message=f"another certified local optimum; global: {claim}")


class Solver:
    """Owns the NLP formulations (built once per problem structure), the backend and the options of every solve.

    tolerances: {'feasibility': largest accepted violation, 'gap': certified minus NLP epigraph value that
    ends the exchange loop}; ipopt_options: merged into IPOPT's (names as CasADi takes them, 'ipopt.tol'; runs
    that start at or near an optimum use a monotone barrier from mu_init 1e-6, unless these name their own);
    samples: uniform epigraph sample angles per formulation (the exchange loop adds up to ``extra`` more);
    starts_n, seed: the Sobol multi-start used where no closed form enumerates the solutions (where none
    enumerates or walks them, starts_n per two free parameters unless a solve names its own); backend: an NLP
    backend (``qropt.synthesis.backends``; default IPOPT); atlas: start a problem whose shape is in the atlas
    (``qropt.synthesis.atlas``) from its designs first, and run the multi-start only where none certifies;
    evolution: where the objective names a transmission guard (the peak torque), descents on the exact objective
    from a differential evolution too (``MultiStart.evolved``, ``Solver.descended``: the costliest part of a
    four-bar-driven solve, for better designs where the multi-start's basins miss them; False leaves them out);
    evolutions: how many independent evolutions (seeds seed, seed + 1, ...; each with its SQP): the basins they
    reach differ from seed to seed; None: four where the problem has seven free parameters or more, else one
    (``evolution.count``); sqp: where the objective is a peak over the
    turn, each design of the evolution and each Nelder-Mead end descended again by the SQP on the exact peak
    (``minimax.polish``: its ends are first-order stationary but not always better than the ends it starts
    from, so it is off unless asked). Whatever ``sqp`` says, the SQP descends the best
    certified designs and every descent's end once more at the end of a solve (``polished``).
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
        self.backend = backend or Ipopt(self.ipopt_options)
        self._formulations = Formulations(samples, extra)
        self.local_solve = LocalSolve(self._formulations, self.backend, tol, max_rounds)
        self.multistart = MultiStart(self.local_solve)
        self.diagnosis = Diagnosis(self)

    def __repr__(self):
        return (
            f"Solver(tolerances={self.tolerances}, samples={self.samples}, extra={self.extra}, "
            f"starts_n={self.starts_n}, backend={self.backend.name}, formulations built={self.formulations})"
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
        }

    def evolutions_of(self, problem: Problem) -> int:
        """The evolutions a solve of ``problem`` runs where they apply: the Solver's, else ``evolution.count``."""
        return self.evolutions if self.evolutions is not None else evolution.count(problem)

    # ---- formulations ----------------------------------------------------------------------------
    def formulation(self, problem: Problem, branch: dict, orientation: int, range_target=None, sense=1) -> Formulation:
        """The NLP of this problem structure, built once (immutable: a problem's numbers are passed per solve)."""
        return self._formulations.get(problem, branch, orientation, range_target, sense)

    @property
    def formulations(self) -> int:
        """How many NLPs this Solver has built."""
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
    ) -> Result:
        """Solve a synthesis problem; returns a Result whatever happens (only invalid input raises).

        starts_n: Sobol points where no closed form enumerates the solutions (default the Solver's);
        use_analytic: use the closed forms; targets: new values for some targets (the NLP is not rebuilt);
        extra_starts: more starting points (free-parameter dicts), tried first; diagnose: on failure, find why
        (within the diagnosis budget); without it a failure is 'failed' with the backend's reasons, or
        'infeasible' where a closed form that gives every design gives none that is valid; continue_from: a
        Result of a nearby problem (a chart's neighbour) whose design is one of ``extra_starts``: that start is
        continued by Newton on the optimum's active set, verified, before the backend runs (``newton``).
        """
        t0 = time.perf_counter()
        asked = starts_n
        if continue_from is not None and not isinstance(continue_from, Result):
            raise ProblemError(f"continue_from is a qropt Result, got {type(continue_from).__name__}")
        problem, targets, extra, starts_n, seed, max_rounds = self._check(
            problem, targets, extra_starts, starts_n, seed, max_rounds
        )
        k = scaling.factor(problem)
        if k != 1.0:  # far from unit scale: solved at unit scale (the tolerances are absolute), scaled back
            r = self.solve(
                scaling.scaled(problem, k),
                starts_n=starts_n,
                use_analytic=use_analytic,
                seed=seed,
                max_rounds=max_rounds,
                extra_starts=[{n: v * k for n, v in e.items()} for e in extra],
                diagnose=diagnose,
            )
            r = scaling.unscaled(r, problem, k)
            if not r.success:
                r = dataclasses.replace(
                    r, message=f"{r.message} (lengths in this message are {k:g} times the problem's)"
                )
            return r
        plan = starts_.plan(problem, use_analytic, self.atlas)
        if asked is None:
            starts_n = starts_.grown(starts_n, problem, plan)
        designs = Designs()  # every mechanism this solve builds, built once
        hint = continue_from.continuation if continue_from is not None and extra else None
        cands, claim, retry = self.multistart.candidates(
            problem, plan, extra, targets, starts_n, seed, max_rounds, designs, retry=not diagnose, hint=hint
        )
        guard, spent, ends = "", {}, []
        if not extra:  # a criterion the NLP sees badly near a toggle: the same starts under its transmission guard too
            more, guard, found = self.multistart.guarded(problem, plan, targets, starts_n, seed, max_rounds, designs)
            if found:
                spent = {
                    "guarded_starts": len(found),
                    "guarded_ipopt_runs": sum(len(c.statuses) for c in found),
                    "t_ipopt_guarded": sum(c.t_ipopt for c in found),
                }
            t_evolved = time.perf_counter()
            evolved, how, ends = [], "", []
            if self.evolution:
                evolved, how, ends = self.multistart.evolved(
                    problem, plan, targets, seed, max_rounds, designs, self.sqp, self.evolutions_of(problem)
                )
            if how:  # starts from descents on the exact objective too
                more += evolved
                guard = f"{guard}; {how}" if guard else how
                spent["t_evolution"] = time.perf_counter() - t_evolved
            if retry is not None and (any(c.ok for c in more) or ends) and not any(c.ok for c in cands):
                # the guarded and evolved designs do not stand in for the searches the diagnosis runs after a first
                # pass without one: they run here, and the best of all is taken
                cands, claim, plan = self.diagnosis.searched(
                    problem, plan, cands, claim, retry, targets, starts_n, seed
                )
            cands += more
        wrapped, how = self.multistart.wrapped(problem, cands, targets, max_rounds, designs)
        if how:  # a box that cut a full-turn angle's descent: on from across its edge
            cands += wrapped
            guard = f"{guard}; {how}" if guard else how
        good = [c for c in cands if c.ok]
        if plan.kind == "enumeration" and not extra and not good and not diagnose:  # every design, none valid
            why = sorted({c.info.get("reason", "") or "it breaks a condition" for c in cands})
            msg = f"no design: the closed form that gives every design ({plan.how}) gives "
            msg += f"{plan.outside + len(cands)}" if plan.outside or cands else "none for these targets"
            msg += f", {plan.outside} outside the bounds" if plan.outside else ""
            msg += f"; {len(cands)} fail ({'; '.join(why[:3])})" if cands else ""
            stats = {"plan": plan.kind, "starts": len(cands), "t_total": time.perf_counter() - t0}
            return Result("infeasible", msg, stats=stats, units=problem.units)
        if plan.kind in ("family", "enumeration") and not extra and not good and not diagnose:
            # no closed-form point refines (or the closed form missed): search instead (the diagnosis does this last)
            kw = {"starts_n": starts_n, "seed": seed, "targets": targets, "max_rounds": max_rounds}
            return self.solve(problem, use_analytic=False, diagnose=False, **kw)
        if good:
            r = self.best(problem, cands, claim, plan, t0, guard)
            r = self.refreshed(problem, r, targets, seed, max_rounds) if not extra else r
            r = self.least_size(problem, r, targets, seed, max_rounds)
            if not extra:
                ends, sqp = self.polished(problem, r, ends)
                spent.update(sqp)
            r = self.descended(problem, r, ends, guard, polished=spent.get("sqp_ends", 0))
            return dataclasses.replace(r, stats={**r.stats, **spent, "t_total": time.perf_counter() - t0})
        if ends:  # no certified design, but a descent's end meets every target and condition
            ends, sqp = self.polished(problem, None, ends)
            spent.update(sqp)
            stats = {**self._stats(problem, cands, plan), **spent}
            r = self.descended(problem, None, ends, guard, stats, polished=spent["sqp_ends"])
            if r is not None:
                return dataclasses.replace(r, stats={**r.stats, "t_total": time.perf_counter() - t0})
        if not diagnose:
            stats = {**self._stats(problem, cands, plan), **spent}
            stats["t_total"] = time.perf_counter() - t0
            why = sorted({c.info.get("reason", "") or ", ".join(c.statuses[-1:]) for c in cands})
            return Result(
                "failed",
                f"no start gave a certified design ({'; '.join(w for w in why[:3] if w)}); not diagnosed",
                stats=stats,
                units=problem.units,
            )
        return self.diagnosis.run(problem, plan, cands, claim, retry, targets, starts_n, seed, t0)

    def _stats(self, problem, cands, plan) -> dict:
        return {
            "starts": len(cands),
            "plan": plan.kind,
            "omega2": problem.omega2,
            "formulations": self.formulations,
            "atlas_starts": len(plan.atlas.designs),
            "ipopt_runs": sum(len(c.statuses) for c in cands if c.origin not in ("enumeration", "walk")),
            "iterations_total": sum(c.iterations for c in cands),
            "t_ipopt": sum(c.t_ipopt for c in cands),
        }

    def best(self, problem, cands, claim, plan, t0, guard: str = "") -> Result:
        """The Result of the certified candidates among ``cands``, best first (with every distinct local optimum);
        guard: the claim's words for the candidates continued from a guarded multi-start (``MultiStart.guarded``)."""
        stats = self._stats(problem, cands, plan)
        good = [c for c in cands if c.ok]
        if good:
            for c in good:
                c.q = quantities(c.problem or problem, c.mechanism)
            best_first = sorted(
                distinct(good),
                key=lambda c: objective_value(problem, c.q) or 0.0,
                reverse=criteria.maximises(problem.objective),
            )
            k = len(best_first)
            if not claim:
                shaped = sum(c.origin == "shape" for c in cands)
                related = sum(c.origin == "related" for c in cands)
                how = [f"{shaped} chosen by the objective among {starts_.SHAPES} grid shapes"] if shaped else []
                how += [f"{related} the atlas's optima of this shape by kinematic objectives"] if related else []
                how = f" ({'; '.join(how)})" if how else ""
                started = sum(c.origin not in ("guard", "wrapped") for c in cands)
                claim = f"best of {k} distinct local optima from {started} starts{how}"
            if guard:
                claim += f"; with {guard}"
            stats.update(t_total=time.perf_counter() - t0, local_optima=k)
            local = [
                self._result(problem, c, "local_optimum" if i else None, claim, stats) for i, c in enumerate(best_first)
            ]
            return self._result(problem, best_first[0], None, claim, stats, local)
        raise AssertionError("best() of candidates without a certified one")

    def polished(self, problem, r: Result | None, ends: list) -> tuple[list, dict]:
        """Where the objective is a peak over the turn (``minimax.applies``): ``ends`` (``evolution.End``s, best
        first) with the ends of the SQP on the exact peak (``minimax.polish``) from the POLISHED best certified
        designs (``r`` and its local optima) and from each of ``ends``, where it moves them; best first, and
        {'sqp_ends': how many were added, 't_sqp': the time taken, s}. A Nelder-Mead descent stalls where peaks
        are equal, and a certified design can be a point the SQP leaves for a lower peak. Only ends: a
        design is not moved, so what the solve found stands (``descended`` takes the best)."""
        t0 = time.perf_counter()
        if not minimax.applies(problem):
            return ends, {"sqp_ends": 0, "t_sqp": time.perf_counter() - t0}
        certified = [r, *(r.local_optima or ())[1:]][:POLISHED] if r is not None else []
        seeds = [{k: x.params[k] for k in problem.free} for x in certified] + [e.design for e in ends]
        added = []
        for d in seeds:
            p = minimax.polish(problem, d)
            if p is not None and p.steps:
                added.append(evolution.End(p.value, p.design, p.local))
        spent = {"sqp_ends": len(added), "t_sqp": time.perf_counter() - t0}
        return sorted([*ends, *added], key=lambda e: e.value), spent

    def descended(
        self, problem, r: Result | None, ends: list, how: str, stats: dict | None = None, polished: int = 0
    ) -> Result | None:
        """The best end of the evolution's descents (``MultiStart.evolved``: ``evolution.End``s, best first; of
        them ``polished`` the SQP's, ``polished``) that meets every target, condition, rule and
        bound exactly, as a ``feasible`` Result where it beats ``r`` (the best certified design, or None) by more
        than STANDS (relative): the design is exact, not certified by the NLP (its certificate's ``local`` says
        what holds at the end: first-order stationarity of the peak where the SQP on the exact peak ends at a
        stationary point, else nothing); the certified designs stay as its local optima. ``r`` otherwise; not for
        a free counterweight (the descents keep it at its start)."""
        if not ends or (problem.masses is not None and problem.masses.balancing):
            return r
        n = len(ends) - polished
        best_of = f"the best of {n} descents' ends" if n else "the best of "
        if polished:
            best_of += f"{' and ' if n else ''}{polished} ends of the SQP on the exact peak from the best designs"
        branch, feasible = starts_.branches(problem)[0], self.tolerances["feasibility"]
        for end in ends:
            d = end.design
            try:
                m = problem.build(d, branch)
                q = quantities(problem, m)
                res = residuals(problem, {}, m, problem.targets)
            except QroptError:
                continue
            kept = starts_.rules_kept(problem, {k: np.array([v]) for k, v in d.items()})[0]
            if not kept or evolution.outside(problem, d) > 0 or max(res.values(), default=0.0) > feasible:
                continue
            value = objective_value(problem, q)
            if value is None or not math.isfinite(value):
                continue
            if r is not None:
                margin = STANDS * max(1.0, abs(r.objective))
                if not (criteria.better(problem, value, r.objective) and abs(value - r.objective) > margin):
                    return r
                claim = f"{best_of}; certified: {r.certificate.global_claim}"
                head = f"better than the best certified design, {r.objective:.6g}, by exact evaluation"
                local = tuple(_relabelled(x) for x in r.local_optima or (r,))
                stats = r.stats
            else:
                claim = f"{best_of} ({how})"
                head, local = "no start gave a certified design", ()
            cert = Certificate(True, None, value, 0.0, 0, end.local, claim)
            return Result(
                status="feasible",
                message=f"a design meeting every target and condition exactly, not certified ({head}); global: {claim}",
                params=dict(m.params),
                mechanism=m,
                objective=value,
                quantities=q,
                residuals=res,
                certificate=cert,
                stats={**(stats or {}), "branch": dict(branch), "origin": "descent"},
                local_optima=local,
            )
        return r

    def refreshed(self, problem, r: Result, targets, seed, max_rounds) -> Result:
        """For a dynamic objective, the best design solved again from itself with a fresh NLP (its samples and
        lifted extremes placed anew), up to REFRESHES times while that improves it by more than TIE_TOL: the
        exchange loop's samples can hold a design that a fresh start at it leaves for a better one nearby."""
        c = criteria.of_problem(problem)
        if c is None or c.kinematic or r.status != "optimal":
            return r
        kw = {"targets": targets, "seed": seed, "max_rounds": max_rounds, "diagnose": False, "use_analytic": False}
        best, times = r, 0
        for _ in range(REFRESHES):
            s = self.solve(problem, starts_n=0, extra_starts=[{k: best.params[k] for k in problem.free}], **kw)
            if s.status != "optimal" or not c.better(s.objective, best.objective):
                break
            if abs(s.objective - best.objective) <= TIE_TOL * max(1.0, abs(best.objective)):
                break
            best, times = s, times + 1
        if best is r:
            return r
        again = "once" if times == 1 else f"{times} times"
        claim = f"{r.certificate.global_claim}; its best design solved again from itself, better {again}"
        cert = dataclasses.replace(best.certificate, global_claim=claim)
        message = best.message.replace(best.certificate.global_claim, claim)
        best = dataclasses.replace(best, certificate=cert, message=message, local_optima=(), stats=r.stats)
        return dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))

    def least_size(self, problem, r: Result, targets, seed, max_rounds) -> Result:
        """Where the type's optima form a continuum (``Mechanism.TIES`` free) and the objective is kinematic, the
        design of least size (the problem's size measure) among those within TIE_TOL of the optimum: along the
        continuum by exact evaluation (``_least_along``), else min_size under a bound at the optimum, and alone
        (where the targets fix the criterion, the bound is redundant and degenerate, and the design stays within
        TIE_TOL anyway), local solves from the optimum first, then along the closed forms' family; a design
        accepted within 2 TIE_TOL of the optimum. ``r`` where none is optimal and that close."""
        c = criteria.of_problem(problem)
        ties = list(problem.mechanism.TIES)
        if not ties or not set(ties) <= set(problem.free) or c is None or c.size or not c.kinematic:
            return r
        if r.status != "optimal":  # a tie of what the certificate does not prove optimal is not broken
            return r
        tol = TIE_TOL * max(1.0, abs(r.objective))
        old = problem.conditions.get(c.bound)

        def within(k):  # k tol worse than the optimum, or the problem's own bound where that is stricter
            v = r.objective - k * tol if c.maximise else r.objective + k * tol
            return old if old is not None and c.better(old, v) else v

        # the bound holds at the sub-solve's design to rounding only: accepted within 2 tol
        # of the optimum, so that a bit either way (a kernel compiled or not) does not decide
        accept = within(2)
        along = self._least_along(problem, r, ties, targets, c, accept, tol)
        if along is not None:
            return along
        start = [{k: r.params[k] for k in problem.free}]
        kw = {"targets": targets, "seed": seed, "max_rounds": max_rounds, "diagnose": False}
        bounded = problem.replace(objective="min_size", conditions={**problem.conditions, c.bound: within(1)})
        alone = problem.replace(objective="min_size")
        local = {"use_analytic": False, "extra_starts": start}
        tries = [(bounded, local), (alone, local)]  # from the optimum first, then along a closed-form family
        if starts_.plan(bounded).kind in ("family", "enumeration"):
            tries += [(bounded, {}), (alone, {})]
        for sub, how in tries:
            s = self.solve(sub, starts_n=0, **how, **kw)
            if s.status == "optimal" and not c.better(accept, s.quantities[c.name]):
                size = s.quantities["size"]
                best = dataclasses.replace(
                    s,
                    objective=objective_value(problem, s.quantities),
                    message=f"{r.message}; optima form a continuum along {', '.join(ties)}: the least "
                    f"{problem.size} ({size:.6g}) within {2 * tol:.1e} of it ({s.certificate.global_claim})",
                    local_optima=(),
                )
                return dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))
        return r

    def _least_along(self, problem, r: Result, ties, targets, c, accept, tol) -> Result | None:
        """The least-size design of the continuum through the optimum ``r``: its tied lengths scaled together by
        one factor leave the motion, and so every kinematic criterion, the same (``Mechanism.TIES``); the size at
        TIE_SCAN factors log-spaced over what the bounds allow (each design built, its rules, one reversal and the
        bound conditions checked), the least refined by a bounded 1-D search between its neighbours, and of
        designs that small (within TIE_TOL) the one of the largest tied lengths, then certified by exact
        evaluation like any design. None where it is not certified within ``accept`` of the
        optimum (the NLP's way is tried then)."""
        from scipy.optimize import minimize_scalar  # imported here: only a continuum's tie needs it

        v0 = {k: r.params[k] for k in problem.free}
        branch = {k: r.params[k] for k in problem.branches}
        if any(v0[k] <= 0 for k in ties):
            return None
        lo = max(math.log(problem.free[k][0] / v0[k]) for k in ties)
        hi = min(math.log(problem.free[k][1] / v0[k]) for k in ties)
        if not lo < hi:
            return None
        designs, sized = Designs(), problem.replace(objective="min_size")

        def at(u):
            v = dict(v0)
            for k in ties:
                v[k] = min(max(v0[k] * math.exp(u), problem.free[k][0]), problem.free[k][1])
            return v

        def size(u):
            f, _ = score(sized, at(float(u)), branch, designs)
            return math.inf if f is None else f

        us = np.linspace(lo, hi, TIE_SCAN)
        sizes = np.array([size(u) for u in us])
        i = int(np.argmin(sizes))
        if not np.isfinite(sizes[i]):
            return None
        a, b = us[max(i - 1, 0)], us[min(i + 1, TIE_SCAN - 1)]
        found = minimize_scalar(size, bounds=(a, b), method="bounded", options={"xatol": 1e-9 * max(1.0, hi - lo)})
        u, least = (float(found.x), float(found.fun)) if found.fun <= sizes[i] else (float(us[i]), float(sizes[i]))
        # the size can be flat along the continuum (the lever's sweep spans the box): of the least, the largest
        # tied lengths (the same motion and torque with the least crank-pin force), their edge found by bisection
        # from the last scale within TIE_TOL of the least size
        level = least * (1.0 + TIE_TOL)
        small = np.flatnonzero(sizes <= level)
        if small.size and us[small[-1]] > u:
            j = int(small[-1])
            u = float(us[j])
            if j < TIE_SCAN - 1:
                inside, out = u, float(us[j + 1])
                for _ in range(TIE_BISECT):
                    mid = 0.5 * (out + inside)
                    inside, out = (mid, out) if size(mid) <= level else (inside, mid)
                u = inside
        cand = self.local_solve.evaluate(problem, at(u), branch, targets, designs)
        if not cand.ok:
            return None
        cand.q = quantities(problem, cand.mechanism)
        if c.better(accept, cand.q[c.name]):
            return None
        claim = (
            f"{r.certificate.global_claim}; optima form a continuum along {' and '.join(ties)} scaled together: "
            f"the least {problem.size} ({cand.q['size']:.6g}) by exact evaluation at {TIE_SCAN} scales and a "
            f"bounded 1-D search, within {2 * tol:.1e} of the optimum"
        )
        best = self._result(problem, cand, None, claim, r.stats)
        return dataclasses.replace(best, local_optima=(best, *r.local_optima[1:]))

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

    def _result(self, problem, c, status, claim, stats, local=()):
        converged_to = c.statuses[-1] if c.statuses else ""
        if status is None:
            acceptable = bool(c.ends) and c.ends[-1] is Status.ACCEPTABLE
            status = "acceptable" if acceptable else "optimal" if problem.objective else "feasible"
        info = c.info
        cert = Certificate(
            exact=info.get("gap", 0.0) <= self.tolerances["gap"],
            nlp=info.get("nlp"),
            certified=info.get("certified"),
            gap=float(info.get("gap", 0.0)),
            rounds=c.rounds,
            local=converged_to,
            global_claim=claim,
        )
        msg = {
            "optimal": "certified optimum",
            "feasible": "certified design (no objective)",
            "acceptable": "certified design; IPOPT stopped at its acceptable tolerance",
            "local_optimum": "another certified local optimum",
        }[status]
        return Result(
            status=status,
            message=f"{msg}; global: {claim}",
            params=dict(c.mechanism.params),
            mechanism=c.mechanism,
            objective=objective_value(problem, c.q),
            quantities=c.q,
            residuals=c.residuals,
            certificate=cert,
            continuation=c.hint,
            stats={
                **stats,
                "statuses": list(c.statuses),
                "iterations": c.iterations,
                "t_ipopt_design": c.t_ipopt,
                "branch": dict(c.branch),
                "orientation": c.orientation,
                "origin": c.origin,
            },
            local_optima=tuple(local),
            counterweight=c.problem.masses.counterweight if problem.masses and problem.masses.balancing else None,
        )

    # ---- reachable range of one target ---------------------------------------------------------------
    def target_range(self, problem, target, targets=None, *, starts_n=None, seed=None, solves: int = RANGE_SOLVES):
        """(low, high) of one target over the free bounds and conditions (other targets dropped); see
        ``target_ranges``. (nan, nan) if no design turns fully."""
        targets = dict(problem.targets if targets is None else targets)
        if target not in targets:
            raise ProblemError(f"{target!r} is not a target of this problem ({sorted(targets)})")
        return self.target_ranges(problem, targets, [target], starts_n=starts_n, seed=seed, solves=solves)[target]

    def target_ranges(
        self, problem, targets, names, *, starts_n=None, seed=None, solves: int = RANGE_SOLVES, toward: bool = False
    ):
        """{target: (low, high)} over the free bounds and conditions, each target alone: the exact values of
        RANGE_SAMPLES designs spread over the bounds (with the corners of the bounds and the closed forms' points),
        built once for every target
        (or the closed form's range where the plan has one),
        then at most ``solves`` local solves per target that push it down and up from the samples nearest each
        end (``toward``: only for a target outside the samples' range). Every value is that
        of a design found, not a proof of an end; (nan, nan) where no design turns."""
        starts_n = self.starts_n if starts_n is None else starts_n
        seed = self.seed if seed is None else seed
        plan = starts_.plan(problem)
        exact = {k: plan.ranges[k] for k in names if k in plan.ranges}  # the closed form's own, where it has one
        names = [k for k in names if k not in exact]
        pts = (
            list(plan.analytic)
            + starts_.corners(problem)
            + starts_.rule_points(problem, max(RANGE_SAMPLES, starts_n), seed)
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
            for v in starts_.turning_points(problem, max(RANGE_SAMPLES, starts_n), seed):
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
