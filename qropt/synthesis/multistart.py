"""Local solves from many starts: a list of starts -> local solves (each in its TR orientation, the incumbent
pruning starts that cannot beat it), a guarded design continued back to its problem, a closed-form family's best
points and its walk; and the helpers the search's strategies share (``score``, ``distinct``, ``expected``). Which
starts run, in which order, is the search pipeline's (``qropt.synthesis.search``)."""

from __future__ import annotations

import time

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import criteria
from qropt.synthesis import starts as starts_
from qropt.synthesis.local import Candidate, LocalSolve, nlp_value

NEAR = ("atlas", "given", "evolution")  # starts at or near optima: run from a small barrier (``Ipopt.near``)
AGAIN = ("atlas", "evolution")  # such starts that give no design there run from the default barrier too (``run``)


class MultiStart:
    """Runs starts through a LocalSolve, with the search's ``Settings``."""

    def __init__(self, local: LocalSolve, settings):
        self.local, self.settings = local, settings

    def continued(
        self, problem, start: Candidate, guard: float, targets, max_rounds, designs, deadline=None
    ) -> Candidate | None:
        """A design certified under a transmission guard, solved again under guards ``guard_step`` times smaller in
        turn (down to ``guard_least``, or the problem's own bound) and then on the problem itself, each from the last
        design certified, from the backend's small barrier; once the guard does not bind, the problem itself next.
        The problem's candidate, or None where its last solve certifies nothing."""
        own = problem.conditions.get(criteria.GUARDED, 0.0)
        step, least = self.settings.guard_step, self.settings.guard_least
        steps, g = [], guard * step
        while g > max(least, own):
            steps.append(g)
            g *= step
        values, way, gamma = start.values, start.orientation, start.mechanism.gamma_min().value
        t_ipopt, iterations = 0.0, 0

        def run(sub):  # a local solve of sub from the last design, its time and iterations counted
            nonlocal t_ipopt, iterations
            x = self.local.run(
                sub,
                values,
                start.branch,
                targets,
                orientation=way,
                max_rounds=max_rounds,
                designs=designs,
                near=True,
                deadline=deadline,
            )
            t_ipopt, iterations = t_ipopt + x.t_ipopt, iterations + x.iterations
            return x

        for g in [*steps, None]:
            if g is not None and g >= gamma:
                continue
            x = run(problem if g is None else under(problem, g))
            if x.ok and g is not None:
                values, way, gamma = x.values, x.orientation, x.mechanism.gamma_min().value
                if gamma > g * (1 + 1e-6):  # the guard does not bind: the problem itself from here
                    x, g = run(problem), None
            if x.ok and g is None:
                x.t_ipopt, x.iterations = t_ipopt, iterations
                return x
        return None

    def run(self, problem, runs, targets, max_rounds, designs, both_ways, patient=False, hint=None, deadline=None):
        """A local solve from every start; the incumbent's NLP value prunes starts that cannot beat it; patient:
        each run with the backend's larger iteration limit (``LocalSolve.run``). A start of a NEAR origin runs
        from the backend's small barrier; one from the atlas or a descent (AGAIN) that gives no design there runs
        from its default barrier too (not in a patient rerun, where the default barrier can spend the larger
        iteration limit for nothing): from such a start the small barrier can reach its iteration limit where the
        default one certifies a design. deadline: no start runs after it (perf_counter s)."""
        plans, count = [], {1: 0, -1: 0}
        for i, (origin, v, *br) in enumerate(runs):
            for b in br or starts_.branches(problem):
                known = hint.orientation(v, b) if hint is not None and origin == "given" else None
                if known and self.local.formulations.get(problem, b, known) is not hint.form:
                    known = None  # a hint of another problem's NLP
                own = known or starts_.orientation(problem, v, b, designs)  # a continued optimum's: its NLP's
                ways = [own] if own and not both_ways else [1, -1]
                plans.append((i, origin, v, b, ways))
                if origin == "multistart":
                    for way in ways:
                        count[way] += 1
        for _, origin, _, _, ways in plans:
            if origin == "multistart" and len(ways) == 1 and count[-ways[0]] < self.settings.min_way:
                ways.append(-ways[0])
                count[-ways[0]] += 1
        out, bound = [], None
        for i, origin, v, b, ways in plans:
            if deadline is not None and time.perf_counter() >= deadline:
                break
            for way in ways:
                kw = {"orientation": way, "max_rounds": max_rounds, "designs": designs, "bound": bound}
                kw["deadline"] = deadline
                given = hint if origin == "given" else None
                c = self.local.run(problem, v, b, targets, patient=patient, near=origin in NEAR, hint=given, **kw)
                if origin in AGAIN and not patient and not c.ok and not c.pruned:
                    first, c = c, self.local.run(problem, v, b, targets, patient=patient, **kw)
                    c.t_ipopt, c.iterations = c.t_ipopt + first.t_ipopt, c.iterations + first.iterations
                c.origin, c.start = origin, i
                out.append(c)
                if c.ok and problem.objective:
                    f = nlp_value(problem, c.info)
                    bound = f if bound is None else min(bound, f)
        return out

    @staticmethod
    def family_starts(problem, plan, designs):
        """The best local optima of the objective along the closed-form family (exact evaluation), per branch."""
        out = []
        bounded = any(k in problem.conditions for k in criteria.bounds())
        for br in starts_.branches(problem):
            scored = [score(problem, v, br, designs) for v in plan.analytic]
            best = starts_.local_best([s for s, _ in scored], criteria.maximises(problem.objective))
            if bounded:  # and the point nearest to meeting the bounds, where the best may lie on a bound
                near = starts_.local_best([v if v else None for _, v in scored], False, keep=1)
                best += [i for i in near if i not in best]
            out += [("family", plan.analytic[i], br) for i in best]
        return out

    def walked(self, problem, plan, run, failed, targets, designs) -> Candidate | None:
        """A family point's design by a bounded 1-D search (Brent) of the exact objective along the closed-form
        family (``plan.walk``) between the scan's points on either side of it, where IPOPT from it (``failed``)
        ended without a design (near a toggle the NLP can be too ill-conditioned to converge from any start). Every
        design of the family meets the targets, so the search's best is the best design between those points; it
        is certified by exact evaluation like any design. None where the search finds no design."""
        from scipy.optimize import minimize_scalar  # imported here: only this fallback needs it

        _, values, branch = run
        walk = plan.walk
        i = next(k for k, v in enumerate(plan.analytic) if v is values)
        x = walk.positions[i]
        variant = [k for k, at in enumerate(walk.positions) if at == x].index(i)  # which design at x (mirrors)
        xs = sorted(set(walk.positions))
        j = xs.index(x)
        lo, hi = xs[max(j - 1, 0)], xs[min(j + 1, len(xs) - 1)]
        # an end point: as far beyond as its neighbour is on the other side (no design there costs inf)
        lo, hi = (lo if j > 0 else x - (hi - x)), (hi if j < len(xs) - 1 else x + (x - lo))
        sign = criteria.sense(problem.objective)

        def design(t):
            vs = walk.at(float(t))
            v = vs[variant] if variant < len(vs) else None
            inside = v is not None and all(a <= v[k] <= b for k, (a, b) in problem.free.items())
            return v if inside else None

        def cost(t):
            v = design(t)
            f = score(problem, v, branch, designs)[0] if v is not None else None
            return np.inf if f is None else -sign * f

        # the objective between the scan's points can have several minima, and a narrow valley beyond the first
        # (between the end of the family and its first scan point, say): the search runs between the best of a
        # finer grid's neighbours
        grid, xtol = self.settings.walk_grid, self.settings.walk_xtol
        ts = np.linspace(lo, hi, grid)
        k = int(np.argmin([cost(t) for t in ts]))
        lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, grid - 1)]
        found = minimize_scalar(
            cost, bounds=(lo, hi), method="bounded", options={"xatol": xtol * max(abs(lo), abs(hi))}
        )
        v = design(found.x) if np.isfinite(found.fun) else None
        if v is None:
            return None
        c = self.local.evaluate(problem, v, branch, targets, designs)
        c.origin, c.start = "walk", failed.start
        c.statuses = [f"bounded 1-D search along the family ({found.nfev} evaluations)"]
        return c


def under(problem, guard: float):
    """The problem with every transmission angle at least ``guard`` (rad) instead of its own gamma_min bound."""
    return problem.replace(conditions={**problem.conditions, criteria.GUARDED: guard})


def expected(problem, found, designs) -> tuple[float | None, float | None]:
    """The values a solve between two atlas nodes is expected to reach, in the problem's objective, signed so that
    larger is better, from the two nodes' best designs, each valued at its own node: (the value interpolated
    linearly in TR between the nodes', the worse of the two). A branch of optima can end between two nodes, so
    only the worse node's value bounds the optimum's from below. (None, None) where only one node has designs (the
    other beyond the type's reach) or without an objective."""
    if not problem.objective:
        return None, None
    sign = criteria.sense(problem.objective)
    at_nodes = {}
    for (v, b), n in zip(found.designs, found.nodes, strict=True):
        f = score(problem, v, b, designs)[0]
        if f is not None:
            at_nodes[n] = max(at_nodes.get(n, -np.inf), sign * f)
    if len(at_nodes) != 2:
        return None, None
    u = (problem.targets["time_ratio"] - found.trs[0]) / (found.trs[1] - found.trs[0])
    return at_nodes[0] + u * (at_nodes[1] - at_nodes[0]), min(at_nodes.values())


def short(problem, cands, floor: float | None, tol: float) -> bool:
    """Whether the best certified candidate (or none) falls ``tol`` (relative) below ``expected``'s value."""
    if floor is None:
        return False
    sign = criteria.sense(problem.objective)
    best = max((sign * criteria.objective_of(problem, c.mechanism) for c in cands if c.ok), default=-np.inf)
    return bool(best < floor - tol * abs(floor))


def score(problem, values, branch, build):
    """(objective, 0.0) of a design that builds and meets every bound condition, (None, total violation) of one
    that builds and does not, (None, None) of one that does not build or turn once."""
    try:
        m = build(problem, values, branch)
        if m.dead_centres().reversals != 1:
            return None, None
        excess = sum(criteria.violations(problem, m).values())
        if excess > 0:
            return None, excess
        return (criteria.objective_of(problem, m) if problem.objective else 0.0), 0.0
    except QroptError:
        return None, None


def distinct(cands):
    """Candidates that differ from every earlier one (another branch, or values apart by more than 1e-6 of the
    largest value: the test is the same at every scale)."""
    out = []
    for c in cands:
        v = np.array([c.values[k] for k in sorted(c.values)])
        scale = max(float(np.max(np.abs(v))), np.finfo(float).tiny)
        if all(
            c.branch != o.branch or np.max(np.abs(v - np.array([o.values[k] for k in sorted(o.values)]))) > 1e-6 * scale
            for o in out
        ):
            out.append(c)
    return out


__all__ = ["MultiStart", "score", "distinct", "expected", "short", "under", "NEAR", "AGAIN"]
