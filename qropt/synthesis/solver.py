"""The Solver: a synthesis problem -> a certified Result. ``qropt.solve`` is its documented default instance.

A solve walks down once: starts (closed forms first: a complete enumeration replaces the multi-start,
a closed-form family is scanned and only its best points refined; otherwise a Sobol multi-start), a
local solve per start (IPOPT on the problem's Formulation, with an exchange loop that adds the crank
angles where the exact analysis disagrees with the NLP's samples), a certificate by exact evaluation,
and a Result with every distinct local optimum, best first.
"""

from __future__ import annotations

import contextlib
import math
import time
from dataclasses import dataclass, field

import numpy as np

from qropt.errors import ProblemError, QroptError
from qropt.synthesis import starts as starts_
from qropt.synthesis.certificate import (
    Certificate,
    Designs,
    better,
    certify,
    objective_of,
    objective_value,
    quantities,
    residuals,
)
from qropt.synthesis.criteria import BOUNDS, UNITS, in_nlp_terms, maximises, measured, objective_for, violations
from qropt.synthesis.formulation import BASE_SAMPLES, EXTRA_SAMPLES, TWO_PI, Formulation
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import Result

TOLERANCES = {"feasibility": 1e-8, "gap": 1e-8}
ACCEPTABLE = "Solved_To_Acceptable_Level"
MIN_WAY = 3  # space-filling starts tried in each way of meeting the TR equality, at least
MANY_STARTS = 6  # more closed-form points than this are scored exactly and only the best few refined
RESTARTS = 2  # IPOPT runs continued from their last iterate when they hit the iteration limit


@dataclass
class Candidate:
    """One local solve's outcome (internal): the design, its certificate data and IPOPT's statistics."""

    ok: bool
    values: dict
    branch: dict
    orientation: int
    mechanism: object = None
    info: dict = field(default_factory=dict)
    residuals: dict = field(default_factory=dict)
    statuses: list = field(default_factory=list)
    iterations: int = 0
    t_ipopt: float = 0.0
    rounds: int = 0
    origin: str = ""
    q: dict | None = None
    pruned: bool = False


class Solver:
    """Owns the NLP formulations (built once per problem structure) and the options of every solve.

    tolerances: {'feasibility': largest accepted violation, 'gap': certified minus NLP epigraph value that
    ends the exchange loop}; ipopt_options: merged into IPOPT's (names as CasADi takes them, 'ipopt.tol');
    samples: uniform epigraph sample angles per formulation (the exchange loop adds up to ``extra`` more);
    starts_n, seed: the Sobol multi-start used where no closed form enumerates the solutions.
    Results do not depend on what the Solver solved before: formulations take every value as a parameter.
    """

    def __init__(self, *, tolerances: dict | None = None, ipopt_options: dict | None = None,
                 samples: int = BASE_SAMPLES, extra: int = EXTRA_SAMPLES, starts_n: int = 8, seed: int = 0,
                 max_rounds: int = 30):  # fmt: skip
        tol = {**TOLERANCES, **(tolerances or {})}
        if set(tol) != set(TOLERANCES) or not all(_positive(v) for v in tol.values()):
            raise ProblemError(f"tolerances are positive numbers for {sorted(TOLERANCES)}, got {tolerances!r}")
        for name, v, lo in (("samples", samples, 2), ("extra", extra, 1), ("starts_n", starts_n, 0),
                            ("max_rounds", max_rounds, 1)):  # fmt: skip
            if isinstance(v, bool) or not isinstance(v, int) or v < lo:
                raise ProblemError(f"Solver: {name} must be an integer >= {lo}, got {v!r}")
        if ipopt_options is not None and not isinstance(ipopt_options, dict):
            raise ProblemError(f"Solver: ipopt_options must be a dict, got {ipopt_options!r}")
        self.tolerances, self.ipopt_options = tol, dict(ipopt_options or {})
        self.samples, self.extra, self.starts_n, self.seed, self.max_rounds = samples, extra, starts_n, seed, max_rounds
        self._formulations: dict = {}

    def __repr__(self):
        return (f"Solver(tolerances={self.tolerances}, samples={self.samples}, extra={self.extra}, "
                f"starts_n={self.starts_n}, formulations built={len(self._formulations)})")  # fmt: skip

    # ---- formulations ----------------------------------------------------------------------------
    def formulation(self, problem: Problem, branch: dict, orientation: int, range_target=None, sense=1) -> Formulation:
        """The NLP of this problem structure, built once: fixed values, targets and samples are CasADi
        parameters, and the free bounds are read from the problem at solve time."""
        c = problem.conditions
        cond = (c.get("grashof"), tuple(k for k in BOUNDS if k in c), repr(c.get("linear")), repr(c.get("ratio")))
        key = (problem.mechanism, tuple(problem.free), tuple(problem.fixed), tuple(problem.targets), cond,
               problem.objective, problem.size, problem.accel_over, tuple(sorted(branch.items())), orientation,
               range_target, sense)  # fmt: skip
        f = self._formulations.get(key)
        if f is None:
            f = self._formulations[key] = Formulation(problem, branch, orientation, range_target, sense,
                                                      self.samples, self.extra, self.ipopt_options)  # fmt: skip
        f.problem = problem
        return f

    @property
    def formulations(self) -> int:
        """How many NLPs this Solver has built."""
        return len(self._formulations)

    # ---- one local solve -------------------------------------------------------------------------
    def local(self, problem, values0, branch, targets, *, orientation=None, max_rounds=None, range_target=None,
              sense=1, designs=None, bound=None) -> Candidate:  # fmt: skip
        """IPOPT from values0 with the exchange loop; orientation: which way the TR equality is met (+1, -1),
        None for the start's own; designs: the solve's memo of built mechanisms; bound: the incumbent's NLP
        objective value, above which the exchange loop stops (the start is pruned)."""
        max_rounds = self.max_rounds if max_rounds is None else max_rounds
        designs = designs or Designs()
        th0, orientation = starts_.dead_centre_start(
            problem, values0, branch, targets, orientation, range_target, designs
        )
        form = self.formulation(problem, branch, orientation, range_target, sense)
        samples, fractions = form.base_samples()
        used = used_f = form.n_base
        phi, box = form.lifted_start(values0, designs)
        p = form.param_vector(targets, samples, fractions, box=box)
        w = form.epigraph_start(form.pack(values0, th0, phi=phi, box=box), p)
        c = Candidate(False, dict(values0), branch, orientation)
        gap_tol, feas_tol = self.tolerances["gap"], self.tolerances["feasibility"]
        st, g, info, m, restarts = {}, None, {}, None, 0
        while c.rounds < max_rounds:
            c.rounds += 1
            w, f, g, st = form.solve(w, p, warm=c.rounds > 1)
            c.t_ipopt += st.get("t_wall_total", 0.0)
            c.iterations += st.get("iter_count", 0)
            c.statuses.append(st.get("return_status", "?"))
            c.values = dict(zip(form.free, w[: form.nx].tolist(), strict=True))
            th, z = w[form.nx : form.nx + 2], w[form.nx + 2 : form.nx + 2 + form.nz]
            m, info, add, frac = certify(problem, range_target, c.values, branch, th, z, f, gap_tol, feas_tol, designs)
            if st.get("return_status") == "Maximum_Iterations_Exceeded" and restarts < RESTARTS and not range_target:
                restarts += 1  # IPOPT's iteration budget ran out on the way: go on from where it stopped
                continue
            if not _converged(st) and not range_target:
                break
            if not add and not frac:
                break
            if bound is not None and info.get("ok") and f > bound + 1e-9 * max(1.0, abs(bound)):
                c.pruned = True  # more samples only raise this basin's NLP value: it cannot beat the incumbent
                break
            used = _place(samples, used, add, TWO_PI, 0.05, form.n_base)
            used_f = _place(fractions, used_f, frac, 1.0, 0.01, form.n_base)
            if form.n_box and m is not None:  # each box side lifted at the coordinate that reaches it now
                box = m.bounding_box()
                at = form.nx + 2 + form.nz + form.n_lift
                w[at : at + form.n_box] = form.box_angles(box)
            p = form.param_vector(targets, samples, fractions, box=box)
            w = form.epigraph_start(w, p) if info.get("gap", 0) > 0 or not info.get("ok") else w
        c.mechanism, c.info = m, info
        c.residuals = residuals(problem, form.violations(g), m, {k: targets[k] for k in form.targets})
        c.ok = bool(info.get("ok")) and _converged(st) and _within(c, self.tolerances) and not c.pruned
        return c

    def polish(self, problem, values0, branch, targets, designs=None) -> Candidate:
        """Newton on the target and dead-centre equations from a closed-form point of a square problem (as many
        free parameters as targets): the point of the finite solution set that the closed form names."""
        designs = designs or Designs()
        th0, orientation = starts_.dead_centre_start(problem, values0, branch, targets, None, None, designs)
        form = self.formulation(problem, branch, orientation)
        rows = form.square_rows
        if rows is None:
            return self.local(problem, values0, branch, targets, orientation=orientation, designs=designs)
        p = form.param_vector(targets, *form.base_samples())
        w = form.pack(values0, th0)
        n = form.nx + 2
        c = Candidate(False, dict(values0), branch, orientation, origin="enumeration")
        for _ in range(30):
            out = form.square_system(np.concatenate([w, p])[None, :])[0]
            try:
                step = np.linalg.solve(out[n:].reshape(n, n, order="F"), out[:n])
            except np.linalg.LinAlgError:
                break
            w[:n] -= step
            c.iterations += 1
            if np.max(np.abs(step)) <= 1e-14 * max(1.0, np.max(np.abs(w[:n]))):
                break
        inside = all(lo - 1e-12 <= x <= hi + 1e-12 for x, (lo, hi) in zip(w[: form.nx], problem.free.values(),
                                                                          strict=True))  # fmt: skip
        if not np.all(np.isfinite(w[:n])) or not inside:
            c.info = {"ok": False, "reason": "Newton on the target equations leaves the bounds from the closed form's "
                      "point (it meets the targets only approximately: no design there)"}  # fmt: skip
            c.statuses = ["enumerated point (Newton)"]
            return c
        # the closed form's own values where Newton only moved them by rounding (one design built, not two)
        free = [
            values0[k] if abs(w[i] - values0[k]) <= 4e-16 * abs(values0[k]) else w[i] for i, k in enumerate(form.free)
        ]
        c.values = dict(zip(form.free, free, strict=True))
        w[: form.nx] = free
        w = form.epigraph_start(w, p)
        g = form.constraint_values(np.concatenate([w, p])[None, :])[0]
        tol = self.tolerances
        m, info, _, _ = certify(problem, None, c.values, branch, w[form.nx : n], None, None, tol["gap"],
                                tol["feasibility"], designs)  # fmt: skip
        c.mechanism, c.info, c.statuses = m, info, ["enumerated point (Newton)"]
        c.residuals = residuals(problem, form.violations(g), m, {k: targets[k] for k in form.targets})
        inside = all(lo - 1e-12 <= c.values[k] <= hi + 1e-12 for k, (lo, hi) in problem.free.items())
        c.ok = bool(info.get("ok")) and inside and _within(c, tol)
        return c

    # ---- the solve ---------------------------------------------------------------------------------
    def solve(self, problem: Problem, *, starts_n: int | None = None, use_analytic: bool = True,
              seed: int | None = None, targets: dict | None = None, max_rounds: int | None = None,
              extra_starts=(), diagnose: bool = True) -> Result:  # fmt: skip
        """Solve a synthesis problem; returns a Result whatever happens (only invalid input raises).

        starts_n: Sobol points where no closed form enumerates the solutions (default the Solver's);
        use_analytic: use the closed forms; targets: new values for some targets (the NLP is not rebuilt);
        extra_starts: more starting points (free-parameter dicts), tried first; diagnose: on failure, find why
        (the reachable range of each target or bound, more solves); without it a failure is 'failed' with
        IPOPT's reasons, or 'infeasible' where a closed form that gives every design gives none that is valid.
        """
        t0 = time.perf_counter()
        problem, targets, extra, starts_n, seed, max_rounds = self._check(
            problem, targets, extra_starts, starts_n, seed, max_rounds
        )
        plan = starts_.plan(problem, use_analytic)
        designs = Designs()  # every mechanism this solve builds, built once
        runs = [("given", v) for v in extra]
        cands: list[Candidate] = []
        claim = ""
        if plan.kind == "enumeration" and not extra:
            for v in plan.analytic:
                for br in starts_.branches(problem):
                    cands.append(self.polish(problem, v, br, targets, designs))
            claim = f"by enumeration: {plan.how}"
        elif plan.kind == "family" and not extra:
            runs += self._family_starts(problem, plan, designs)
            claim = (
                f"best along a closed-form family that holds every solution ({plan.how}; {len(plan.analytic)} points)"
            )
        else:
            if len(plan.analytic) > MANY_STARTS and not extra:  # a sweep of closed-form points: the best few
                best = self._family_starts(problem, plan, designs)
                runs += [("analytic", v, *b) for _, v, *b in best]
            else:
                runs += [("analytic", v) for v in plan.analytic]
            runs += [("multistart", v) for v in starts_.sobol(problem, starts_n, seed, designs)]
        cands += self._run(problem, runs, targets, max_rounds, designs, both_ways=False)
        good = [c for c in cands if c.ok]
        if not good and any(o == "multistart" for o, *_ in runs):  # the other way of meeting the TR equality
            cands += self._run(problem, [r for r in runs if r[0] == "multistart"], targets, max_rounds, designs, True)
            good = [c for c in cands if c.ok]
        if plan.kind == "enumeration" and not extra and not good and not diagnose:  # every design, none valid
            why = sorted({c.info.get("reason", "") or "it breaks a condition" for c in cands})
            msg = f"no design: the closed form that gives every design ({plan.how}) gives "
            msg += f"{plan.outside + len(cands)}" if plan.outside or cands else "none for these targets"
            msg += f", {plan.outside} outside the bounds" if plan.outside else ""
            msg += f"; {len(cands)} fail ({'; '.join(why[:3])})" if cands else ""
            return Result("infeasible", msg, stats={"plan": plan.kind, "starts": len(cands),
                                                    "t_total": time.perf_counter() - t0})  # fmt: skip
        if plan.kind in ("family", "enumeration") and not extra and not good:
            # no closed-form point refines (or the closed form missed): search instead
            kw = {"starts_n": starts_n, "seed": seed, "targets": targets, "max_rounds": max_rounds}
            return self.solve(problem, use_analytic=False, diagnose=diagnose, **kw)
        stats = {"starts": len(cands), "plan": plan.kind, "omega2": problem.omega2, "formulations": self.formulations,
                 "ipopt_runs": sum(len(c.statuses) for c in cands if c.origin != "enumeration"),
                 "iterations_total": sum(c.iterations for c in cands),
                 "t_ipopt": sum(c.t_ipopt for c in cands)}  # fmt: skip
        if good:
            for c in good:
                c.q = quantities(problem, c.mechanism)
            best_first = sorted(_distinct(good), key=lambda c: objective_value(problem, c.q) or 0.0,
                                reverse=maximises(problem.objective))  # fmt: skip
            k = len(best_first)
            claim = claim or f"best of {k} distinct local optima from {len(cands)} starts"
            stats.update(t_total=time.perf_counter() - t0, local_optima=k)
            local = [self._result(problem, c, "local_optimum" if i else None, claim, stats)
                     for i, c in enumerate(best_first)]  # fmt: skip
            return self._result(problem, best_first[0], None, claim, stats, local)
        if not diagnose:
            stats["t_total"] = time.perf_counter() - t0
            why = sorted({c.info.get("reason", "") or ", ".join(c.statuses[-1:]) for c in cands})
            return Result("failed", f"no start gave a certified design ({'; '.join(w for w in why[:3] if w)}); "
                          "not diagnosed", stats=stats)  # fmt: skip
        return self._diagnose(problem, cands, targets, starts_n, seed, stats, t0)

    def _run(self, problem, runs, targets, max_rounds, designs, both_ways):
        """A local solve from every start in its own TR orientation (both where it has none, or if asked); the
        space-filling starts also try the other orientation until each has at least MIN_WAY of them."""
        plans, count = [], {1: 0, -1: 0}
        for origin, v, *br in runs:
            for b in br or starts_.branches(problem):
                own = starts_.orientation(problem, v, b, designs)
                ways = [own] if own and not both_ways else [1, -1]
                plans.append((origin, v, b, ways))
                if origin == "multistart":
                    for way in ways:
                        count[way] += 1
        for origin, _, _, ways in plans:
            if origin == "multistart" and len(ways) == 1 and count[-ways[0]] < MIN_WAY:
                ways.append(-ways[0])
                count[-ways[0]] += 1
        out, bound = [], None
        for origin, v, b, ways in plans:
            for way in ways:
                c = self.local(problem, v, b, targets, orientation=way, max_rounds=max_rounds, designs=designs,
                               bound=bound)  # fmt: skip
                c.origin = origin
                out.append(c)
                if c.ok and problem.objective:
                    f = _nlp_value(problem, c.info)
                    bound = f if bound is None else min(bound, f)
        return out

    def _family_starts(self, problem, plan, designs):
        """The best local optima of the objective along the closed-form family (exact evaluation), per branch."""
        out = []
        bounded = any(k in problem.conditions for k in BOUNDS)
        for br in starts_.branches(problem):
            scored = [_score(problem, v, br, designs) for v in plan.analytic]
            best = starts_.local_best([s for s, _ in scored], maximises(problem.objective))
            if bounded:  # and the point nearest to meeting the bounds, where the best may lie on a bound
                near = starts_.local_best([v if v else None for _, v in scored], False, keep=1)
                best += [i for i in near if i not in best]
            out += [("family", plan.analytic[i], br) for i in best]
        return out

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
            status = "acceptable" if converged_to == ACCEPTABLE else "optimal" if problem.objective else "feasible"
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
        msg = {"optimal": "certified optimum", "feasible": "certified design (no objective)",
               "acceptable": "certified design; IPOPT stopped at its acceptable tolerance",
               "local_optimum": "another certified local optimum"}[status]  # fmt: skip
        return Result(
            status=status,
            message=f"{msg}; global: {claim}",
            params=dict(c.mechanism.params),
            mechanism=c.mechanism,
            objective=objective_value(problem, c.q),
            quantities=c.q,
            residuals=c.residuals,
            certificate=cert,
            stats={
                **stats,
                "statuses": list(c.statuses),
                "iterations": c.iterations,
                "t_ipopt_design": c.t_ipopt,
                "branch": dict(c.branch),
                "orientation": c.orientation,
                "origin": c.origin,
            },  # fmt: skip
            local_optima=tuple(local),
        )

    def _diagnose(self, problem, cands, targets, starts_n, seed, stats, t0):
        """No certified design: say why (a target out of its reachable range, or nothing meets all together)."""
        reasons = sorted({c.info.get("reason", "") or ", ".join(c.statuses[-1:]) for c in cands})
        beyond, found = self._bound_out_of_reach(problem, targets, starts_n, seed)
        if beyond:
            stats["t_total"] = time.perf_counter() - t0
            return Result("infeasible", beyond[0], stats=stats, reachable=beyond[1])
        if found:  # a design optimising a bounded criterion meets every bound: refine from it
            r = self.solve(problem, targets=targets, starts_n=0, seed=seed, extra_starts=found, diagnose=False)
            if r.success:
                return r
        if problem.objective and not found:  # is there any design at all? (then the objective's solves failed)
            r = self.solve(problem.replace(objective=None), targets=targets, starts_n=starts_n, seed=seed,
                           diagnose=False)  # fmt: skip
            found = [{k: r.params[k] for k in problem.free}] if r.success else []
        reach, msgs = {}, []
        for k, v in targets.items():
            lo, hi = self.target_range(problem, k, targets, starts_n=starts_n, seed=seed)
            reach[k] = (lo, hi)
            msgs.append(_range_message(problem, k, v, lo, hi))
        stats["t_total"] = time.perf_counter() - t0
        outside = [m for (k, (lo, hi)), m in zip(reach.items(), msgs, strict=True) if not _inside(targets[k], lo, hi)]
        if outside:
            return Result("infeasible", "; ".join(outside), stats=stats, reachable=reach)
        if all(max(c.residuals.values(), default=0.0) > self.tolerances["feasibility"] or c.mechanism is None
               for c in cands):  # fmt: skip
            ends: dict = {}
            for c in cands:
                k = c.statuses[-1] if c.statuses else "no run"
                ends[k] = ends.get(k, 0) + 1
            how = ", ".join(f"{n} {k}" for k, n in sorted(ends.items(), key=lambda kv: -kv[1]))
            msg = f"none of {len(cands)} starts reaches a design meeting the targets and conditions together "
            msg += f"(IPOPT: {how}), though each target alone can be met (" + "; ".join(msgs) + ")"
            # IPOPT's own failures (invalid numbers, iteration limits) prove nothing: only converged or
            # infeasible-detected runs make the problem infeasible
            if found:  # a design meeting every target and condition exists: the objective's solves failed
                shown = ", ".join(f"{k}={v:.6g}" for k, v in found[0].items())
                msg += (f"; designs meeting every target and condition exist (one: {shown}), so the {problem.objective}"
                        " optimum was not reached (it may lie at a singular limit: a dead point, a link of zero "
                        "length or a bound)")  # fmt: skip
                return Result("failed", msg, stats=stats, reachable=reach)
            proved = any(k in ("Infeasible_Problem_Detected", "Solve_Succeeded", ACCEPTABLE) for k in ends)
            return Result("infeasible" if proved else "failed", msg, stats=stats, reachable=reach)
        why = "; ".join(r for r in reasons[:3] if r)
        return Result("failed", f"no start converged to a certified design ({why}); " + "; ".join(msgs),
                      stats=stats, reachable=reach)  # fmt: skip

    def _bound_out_of_reach(self, problem, targets, starts_n, seed):
        """((message, {quantity: (low, high)}) if a bound condition is beyond what any design meeting the targets
        and the other conditions reaches (its best value, from a solve optimising it), else None; and the designs
        of those solves that meet every bound, as starts)."""
        found = []
        for key, (quantity, sense) in BOUNDS.items():
            bound = problem.conditions.get(key)
            if bound is None:
                continue
            objective, size = objective_for(quantity)
            sub = problem.replace(objective=objective, size=size or problem.size,
                                  conditions={k: v for k, v in problem.conditions.items() if k != key})  # fmt: skip
            r = self.solve(sub, targets=targets, starts_n=starts_n, seed=seed)
            if r.status not in ("optimal", "acceptable"):
                continue
            tol = self.tolerances["feasibility"]
            found += [{k: o.params[k] for k in problem.free} for o in r.local_optima or (r,)
                      if max(violations(problem, o.mechanism).values(), default=0.0) <= tol]  # fmt: skip
            best = r.objective
            if (best < bound) if sense == "lower" else (best > bound):
                span = (0.0, best) if sense == "lower" else (best, math.inf)
                word = "largest" if sense == "lower" else "smallest"

                def show(v, quantity=quantity):
                    deg = f" ({math.degrees(v):.2f} deg)" if quantity == "gamma_min" else ""
                    return f"{v:.6g} {UNITS[quantity]}{deg}"

                msg = (f"{key} {show(bound)} is beyond reach: the {word} {quantity} of a design meeting the "
                       f"targets and the other conditions is {show(best)} ({r.certificate.global_claim})")  # fmt: skip
                return (msg, {quantity: span}), []
        return None, found

    # ---- reachable range of one target ---------------------------------------------------------------
    def target_range(self, problem, target, targets=None, *, starts_n=None, seed=None):
        """(low, high) of one target over the free bounds and conditions (other targets dropped).

        Every value is that of a certified design: the optimised extremes and the start designs themselves.
        (nan, nan) if no design turns fully.
        """
        starts_n = self.starts_n if starts_n is None else starts_n
        seed = self.seed if seed is None else seed
        targets = dict(problem.targets if targets is None else targets)
        if target not in targets:
            raise ProblemError(f"{target!r} is not a target of this problem ({sorted(targets)})")
        sub = problem.replace(targets={target: targets[target]})
        seen = []

        def value(m):
            return m.time_ratio() if target == "time_ratio" else m.stroke()

        pts = list(starts_.plan(problem).analytic) + starts_.sobol(problem, starts_n, seed)
        for v in pts:
            for br in starts_.branches(problem):
                with contextlib.suppress(QroptError):
                    seen.append(value(problem.build(v, br)))
        for sense in (1, -1):
            for v in pts:
                for br in starts_.branches(problem):
                    for way in (1, -1):
                        c = self.local(sub, v, br, {target: targets[target]}, orientation=way, max_rounds=3,
                                       range_target=target, sense=sense)  # fmt: skip
                        m = c.mechanism
                        internal = ("dead centre", "time_ratio orientation")
                        conditions = [x for k, x in c.residuals.items() if not k.startswith(internal)]
                        if m is not None and m.dead_centres().reversals == 1 and max(conditions, default=0.0) <= 1e-9:
                            seen.append(value(m))  # the exact value of a design that meets every condition
        if not seen:
            return float("nan"), float("nan")
        return float(min(seen)), float(max(seen))


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


def _nlp_value(problem, info) -> float:
    """A certified objective in the NLP's terms (what IPOPT minimises)."""
    return in_nlp_terms(measured(problem.objective, problem.size), info["certified"], problem.omega2)


def _within(c: Candidate, tol) -> bool:
    return max(c.residuals.values(), default=0.0) <= tol["feasibility"] and c.info.get("gap", 0.0) <= tol["gap"]


def _converged(stats) -> bool:
    """IPOPT solved the NLP (to its tolerance, or to its acceptable level)."""
    return bool(stats.get("success")) or stats.get("return_status") == ACCEPTABLE


def _score(problem, values, branch, build):
    """(objective, 0.0) of a design that builds and meets every bound condition, (None, total violation) of one
    that builds and does not, (None, None) of one that does not build or turn once."""
    try:
        m = build(problem, values, branch)
        if m.dead_centres().reversals != 1:
            return None, None
        excess = sum(violations(problem, m).values())
        if excess > 0:
            return None, excess
        return (objective_of(problem, m) if problem.objective else 0.0), 0.0
    except QroptError:
        return None, None


def _place(slots, used, new, period, near, base):
    """Put new sample angles into the extra slots: an angle close to an extra sample moves it there (the
    worst angle drifts as the design changes), others take free slots; with every slot taken, the nearest
    extra sample moves (an angle the exact evaluation names is never dropped). Returns the slots in use."""
    for t in new:
        extra = np.arange(base, used)
        if extra.size:
            d = np.abs((slots[extra] - t + period / 2) % period - period / 2)
            k = int(np.argmin(d))
            if d[k] < near or used == slots.size:
                slots[extra[k]] = t
                continue
        if used < slots.size:
            slots[used] = t
            used += 1
    return used


def _distinct(cands):
    out = []
    for c in cands:
        v = np.array([c.values[k] for k in sorted(c.values)])
        if all(
            c.branch != o.branch
            or np.max(np.abs(v - np.array([o.values[k] for k in sorted(o.values)])) / np.maximum(1, np.abs(v))) > 1e-6
            for o in out
        ):
            out.append(c)
    return out


def _inside(v, lo, hi) -> bool:
    """v within a found range, to 1e-6 relative: the range's ends are designs found, not proofs of an end."""
    tol = 1e-6 * max(1.0, abs(v))
    return lo - tol <= v <= hi + tol


def _range_message(problem, k, v, lo, hi):
    bounds = ", ".join(f"{n} in [{a:g}, {b:g}]" for n, (a, b) in problem.free.items())
    if not math.isfinite(lo):
        return f"no design turns fully and meets the conditions for {bounds}"
    where = "inside" if _inside(v, lo, hi) else "below" if v < lo else "above"
    return f"{k} {v:g} is {where} the reachable {lo:.6g}..{hi:.6g} for {bounds}"


DEFAULT = Solver()


def solve(problem: Problem, **options) -> Result:
    """Solve with the default Solver (``qropt.solve.DEFAULT``); options as ``Solver.solve``."""
    return DEFAULT.solve(problem, **options)


def target_range(problem, target, targets=None, **options):
    """(low, high) of one target with the default Solver; see ``Solver.target_range``."""
    return DEFAULT.target_range(problem, target, targets, **options)


__all__ = ["Solver", "DEFAULT", "solve", "target_range", "better"]
