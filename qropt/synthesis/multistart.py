"""The multi-start: a plan of starts -> local solves -> the distinct certified designs, best first.

Closed forms first: a complete enumeration is polished point by point (no multi-start), a closed-form family is
scanned by exact evaluation and only its best points refined; otherwise the atlas's designs of the problem's
shape (``atlas``), and only where none of them certifies, the closed-form points and a scrambled Sobol design.
Each start is solved in its own TR orientation (both where it has none); the space-filling starts also try the
other orientation until each has at least MIN_WAY of them. A criterion with a transmission guard (the peak
torque's) has its starts run again under it, each design they certify continued back to the problem (``guarded``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from qropt.errors import QroptError
from qropt.synthesis import atlas as atlas_
from qropt.synthesis import criteria, descents, evolution
from qropt.synthesis import starts as starts_
from qropt.synthesis.certificate import Designs
from qropt.synthesis.local import Candidate, LocalSolve, nlp_value

NEAR = ("atlas", "given", "evolution")  # starts at or near optima: run from a small barrier (``Ipopt.near``)
AGAIN = ("atlas", "evolution")  # such starts that give no design there run from the default barrier too (``run``)
MIN_WAY = 3  # space-filling starts tried in each way of meeting the TR equality, at least
WALK_GRID = 33  # points of a family walk's finer grid between two scan points, before its bounded search
WALK_XTOL = 1e-12  # a family walk's search tolerance relative to its parameter (SciPy's bounded Brent stops
# within sqrt(machine epsilon) of it, relative, at the least: about 1e-16 of a smooth objective's optimum)
MANY_STARTS = 6  # more closed-form points than this are scored exactly and only the best few refined
WIDER = 4  # a wider multi-start runs this many times the starts (some optima lie in basins the default starts miss)
FULL_TURN = 2 * math.pi * (1 - 1e-9)  # an angle's box this wide holds every angle: its edges are one (``wrapped``)
WRAP_EDGE = 1e-6  # rad: a design's angle this near such an edge is at it
EVOLUTION_GENERATIONS = 100  # an evolution's generations where the guard applies (``evolved``)
THIN = 3  # a multi-start whose second pass (both TR orientations) certifies fewer designs than this is thin
# evidence: the diagnosis's wider multi-start runs too (``Diagnosis.run``)
GUARD_STEP = 0.7  # a guarded design is continued through transmission guards this much smaller each step: a jump
# from a binding guard straight to none can end at no design where gradual steps keep one
GUARD_LEAST = math.radians(1.0)  # the smallest guard before none
ATLAS_SHORT = 0.02  # where the atlas's starts end this much (relative) worse than their nodes' designs interpolated
# to the TR, those without a design run again with a larger iteration limit (a jump in TR from an optimum can need
# more IPOPT iterations than the default limit), and where they end this much worse than both nodes' designs, the
# multi-start runs as well


class MultiStart:
    """Runs a plan of starts through a LocalSolve; ``claim`` says what the best of them rests on."""

    def __init__(self, local: LocalSolve):
        self.local = local

    def candidates(self, problem, plan, extra, targets, starts_n, seed, max_rounds, designs, retry=True, hint=None):
        """(candidates, claim, the retry): where no space-filling start gives a certified design, the retry runs
        each of them in both TR orientations; with ``retry`` it is run here (and None is returned), otherwise it
        is returned as a callable (None where there is nothing to retry). ``hint``: a nearby problem's optimum
        (``newton.Hint``) that a given start continues where it is that optimum's design."""
        runs = [("given", v) for v in extra]
        cands: list[Candidate] = []
        claim = ""
        if plan.kind == "enumeration" and not extra:
            for v in plan.analytic:
                for br in starts_.branches(problem):
                    cands.append(self.local.polish(problem, v, br, targets, designs))
            claim = f"by enumeration: {plan.how}"
        elif plan.kind == "family" and not extra:
            runs += self.family_starts(problem, plan, designs)
            claim = (
                f"best along a closed-form family that holds every solution ({plan.how}; {len(plan.analytic)} points)"
            )
        else:
            if plan.atlas.designs and not extra:  # the atlas's designs first: the multi-start only where none certifies
                first = [("atlas", v, b) for v, b in plan.atlas.designs]
                cands += self.run(problem, first, targets, max_rounds, designs, both_ways=False)
                between, floor = expected(problem, plan.atlas, designs)
                how = plan.atlas.how
                done = {c.start for c in cands if c.ok}
                if short(problem, cands, between) and len(done) < len(first):
                    # again, each start without a design, with a larger iteration limit
                    again = [r for i, r in enumerate(first) if i not in done]
                    cands += self.run(problem, again, targets, max_rounds, designs, both_ways=False, patient=True)
                    how += ", those without a design run again with a larger iteration limit"
                falls_short = short(problem, cands, floor)
                if any(c.ok for c in cands) and not falls_short:
                    return cands, f"best of {how}", None
                # none certified, or still short: the multi-start as well (the atlas's candidates kept, counted)
            if len(plan.analytic) > MANY_STARTS and not extra:  # a sweep of closed-form points: the best few
                runs += [("analytic", v, *b) for _, v, *b in self.family_starts(problem, plan, designs)]
            else:
                runs += [("analytic", v) for v in plan.analytic]
            if not extra:  # shapes best by the objective among many, on a grid
                runs += [("shape", v) for v in starts_.shapes(problem, starts_.SHAPES_KEEP, seed)]
                # and, for a dynamic objective, the atlas's optima of the same shape by the kinematic ones, from the
                # default barrier (from the small one they can give no design where the default one finds optima
                # that the other starts miss)
                runs += [("related", v, b) for v, b in plan.related.designs]
            runs += [("multistart", v) for v in starts_.sobol(problem, starts_n, seed, designs)]
        cands += self.run(problem, runs, targets, max_rounds, designs, both_ways=False, hint=hint)
        if plan.kind == "family" and plan.walk is not None and not extra and problem.objective:
            failed = [(runs[c.start], c) for c in cands if c.origin == "family" and not c.ok and not c.pruned]
            walked = [w for run, c in failed if (w := self.walked(problem, plan, run, c, targets, designs))]
            if any(c.ok for c in walked):
                claim += (
                    f"; from {sum(c.ok for c in walked)} point(s) where IPOPT ended without a design, a bounded 1-D "
                    f"search of the exact objective along the family's {plan.walk.name} instead"
                )
            cands += walked
        spread = [r for r in runs if r[0] == "multistart"]
        if not spread or any(c.ok for c in cands):
            return cands, claim, None

        def again():  # the other way of meeting the TR equality
            return self.run(problem, spread, targets, max_rounds, designs, both_ways=True)

        if retry:
            return cands + again(), claim, None
        return cands, claim, again

    def guarded(self, problem, plan, targets, starts_n, seed, max_rounds, designs) -> tuple[list, str, list]:
        """Where the objective's criterion names a transmission guard (``Criterion.guard``) above the problem's own
        gamma_min bound and no closed form enumerates or walks the designs: the same starts on the problem with
        gamma_min >= guard, and each distinct design they certify continued to this problem (``continued``).
        (candidates of this problem, the claim's words for them, the guarded problem's candidates; [], '' and []
        where no guard applies)."""
        c = criteria.of_problem(problem)
        own = problem.conditions.get("gamma_min", 0.0)
        if c is None or c.guard is None or own >= c.guard or plan.kind not in ("none", "partial"):
            return [], "", []
        found, _, _ = self.candidates(_under(problem, c.guard), plan, [], targets, starts_n, seed, max_rounds, designs)
        good = distinct([x for x in found if x.ok])
        out = [x for x in (self.continued(problem, x, c.guard, targets, max_rounds, designs) for x in good) if x]
        for x in out:
            x.origin = "guard"
        to = "the problem's bound" if own > 0 else "none"
        kept = f"{len(good)} distinct design{'s' * (len(good) != 1)}"
        how = (
            f"{kept} of {len(found)} starts under a transmission guard (gamma_min >= {math.degrees(c.guard):g} "
            f"deg) continued to {to}, {len(out)} certified"
        )
        return out, how, found

    def evolved(
        self, problem, plan, targets, seed, max_rounds, designs, sqp=False, count: int = 1
    ) -> tuple[list, str, list]:
        """Where the guard applies (``guarded``): local solves from the ends of descents on the exact objective
        from ``count`` evolutions' designs (``evolution.descended``: EVOLUTION_GENERATIONS generations each, from
        seeds ``seed``, ``seed + 1``, ...; sqp: the SQP on the exact peak too).
        (candidates, the claim's words, the descents' distinct ends, ``evolution.End``s best first, which the
        solver compares with the certified designs, ``Solver.descended``; [], '' and [] where it does not apply;
        the local solves start from the KEEP best of each evolution.) Run
        whether or not the passes certify a design: the descents reach basins the passes miss, and can give a
        problem its only design."""
        c = criteria.of_problem(problem)
        own = problem.conditions.get("gamma_min", 0.0)
        if c is None or c.guard is None or own >= c.guard or plan.kind not in ("none", "partial"):
            return [], "", []
        if not evolution.applies(problem):
            return [], "", []
        each = [descents.descended(problem, EVOLUTION_GENERATIONS, seed + i, sqp=sqp) for i in range(count)]
        runs = [("evolution", e.design) for ends in each for e in ends[: evolution.KEEP]]  # the best distinct ends
        out = self.run(problem, runs, targets, max_rounds, designs, both_ways=False)
        which = (
            "a differential evolution"
            if count == 1
            else f"{count} differential evolutions (seeds {seed}-{seed + count - 1})"
        )
        how = (
            f"{len(runs)} starts from descents on the exact objective after {which} of "
            f"{EVOLUTION_GENERATIONS} generations, {sum(x.ok for x in out)} certified"
        )
        return out, how, sorted((e for ends in each for e in ends), key=lambda e: e.value)

    def wrapped(self, problem, cands, targets, max_rounds, designs) -> tuple[list, str]:
        """Each distinct certified design with an angle at an edge of a full-turn box (its width 2 pi), solved again
        from that angle taken across the edge (2 pi less or more: the same mechanism), where the box cut its descent.
        (candidates, the claim's words; '' where no design is at such an edge)."""
        kinds, runs = problem.mechanism.kinds(), []
        turns = [k for k, (lo, hi) in problem.free.items() if kinds[k] == "angle" and hi - lo >= FULL_TURN]
        for c in distinct([c for c in cands if c.ok]) if turns else []:
            for k in turns:
                lo, hi = problem.free[k]
                x = c.values[k]
                if min(x - lo, hi - x) <= WRAP_EDGE:
                    across = x - 2 * math.pi if hi - x <= WRAP_EDGE else x + 2 * math.pi
                    runs.append(("wrapped", {**c.values, k: min(max(across, lo), hi)}, c.branch))
        if not runs:
            return [], ""
        out = self.run(problem, runs, targets, max_rounds, designs, both_ways=False)
        n = len(runs)
        how = f"{n} design{'s' * (n != 1)} at an edge of a full-turn angle's box solved again from across it, "
        return out, how + f"{sum(c.ok for c in out)} certified"

    def continued(self, problem, start: Candidate, guard: float, targets, max_rounds, designs) -> Candidate | None:
        """A design certified under a transmission guard, solved again under guards GUARD_STEP times smaller in turn
        (down to GUARD_LEAST, or the problem's own bound) and then on the problem itself, each from the last design
        certified, from the backend's small barrier; once the guard does not bind, the problem itself next. The
        problem's candidate, or None where its last solve certifies nothing."""
        own = problem.conditions.get("gamma_min", 0.0)
        steps, g = [], guard * GUARD_STEP
        while g > max(GUARD_LEAST, own):
            steps.append(g)
            g *= GUARD_STEP
        values, way, gamma = start.values, start.orientation, start.mechanism.gamma_min().value
        t_ipopt, iterations = 0.0, 0

        def run(sub):  # a local solve of sub from the last design, its time and iterations counted
            nonlocal t_ipopt, iterations
            x = self.local.run(
                sub, values, start.branch, targets, orientation=way, max_rounds=max_rounds, designs=designs, near=True
            )
            t_ipopt, iterations = t_ipopt + x.t_ipopt, iterations + x.iterations
            return x

        for g in [*steps, None]:
            if g is not None and g >= gamma:
                continue
            x = run(problem if g is None else _under(problem, g))
            if x.ok and g is not None:
                values, way, gamma = x.values, x.orientation, x.mechanism.gamma_min().value
                if gamma > g * (1 + 1e-6):  # the guard does not bind: the problem itself from here
                    x, g = run(problem), None
            if x.ok and g is None:
                x.t_ipopt, x.iterations = t_ipopt, iterations
                return x
        return None

    def wider(self, problem, plan, targets, starts_n, seed, max_rounds):
        """(candidates, claim, plan) of one more multi-start of WIDER times ``starts_n`` space-filling starts
        (already grown with the free parameters), from seed + 1, without the closed-form points and the atlas."""
        wide = dataclasses.replace(plan, atlas=atlas_.Starts()) if plan.kind == "none" else starts_.plan(problem, False)
        more, how, _ = self.candidates(
            problem, wide, [], targets, WIDER * starts_n, seed + 1, max_rounds, Designs(), retry=False
        )
        return more, how, wide

    def run(self, problem, runs, targets, max_rounds, designs, both_ways, patient=False, hint=None):
        """A local solve from every start; the incumbent's NLP value prunes starts that cannot beat it; patient:
        each run with the backend's larger iteration limit (``LocalSolve.run``). A start of a NEAR origin runs
        from the backend's small barrier; one from the atlas or a descent (AGAIN) that gives no design there runs
        from its default barrier too (not in a patient rerun, where the default barrier can spend the larger
        iteration limit for nothing): from such a start the small barrier can reach its iteration limit where the
        default one certifies a design."""
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
            if origin == "multistart" and len(ways) == 1 and count[-ways[0]] < MIN_WAY:
                ways.append(-ways[0])
                count[-ways[0]] += 1
        out, bound = [], None
        for i, origin, v, b, ways in plans:
            for way in ways:
                kw = {"orientation": way, "max_rounds": max_rounds, "designs": designs, "bound": bound}
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
        ts = np.linspace(lo, hi, WALK_GRID)
        k = int(np.argmin([cost(t) for t in ts]))
        lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, WALK_GRID - 1)]
        found = minimize_scalar(
            cost, bounds=(lo, hi), method="bounded", options={"xatol": WALK_XTOL * max(abs(lo), abs(hi))}
        )
        v = design(found.x) if np.isfinite(found.fun) else None
        if v is None:
            return None
        c = self.local.evaluate(problem, v, branch, targets, designs)
        c.origin, c.start = "walk", failed.start
        c.statuses = [f"bounded 1-D search along the family ({found.nfev} evaluations)"]
        return c


def _under(problem, guard: float):
    """The problem with every transmission angle at least ``guard`` (rad) instead of its own gamma_min bound."""
    return problem.replace(conditions={**problem.conditions, "gamma_min": guard})


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


def short(problem, cands, floor: float | None) -> bool:
    """Whether the best certified candidate (or none) falls ATLAS_SHORT (relative) below ``expected``'s value."""
    if floor is None:
        return False
    sign = criteria.sense(problem.objective)
    best = max((sign * criteria.objective_of(problem, c.mechanism) for c in cands if c.ok), default=-np.inf)
    return bool(best < floor - ATLAS_SHORT * abs(floor))


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


__all__ = [
    "MultiStart",
    "score",
    "distinct",
    "MIN_WAY",
    "MANY_STARTS",
    "WIDER",
    "THIN",
    "GUARD_STEP",
    "GUARD_LEAST",
    "EVOLUTION_GENERATIONS",
    "AGAIN",
]
