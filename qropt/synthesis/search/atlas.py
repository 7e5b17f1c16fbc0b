"""The atlas's designs of the problem's shape (``qropt.synthesis.atlas``), solved first: where one certifies and
none falls short of its nodes' designs, the rest of the starts phase does not run. Designs the atlas holds for the
problem without its bound conditions are compared with their nodes' values without the bounds: a design that
comes as close as they do and meets the bounds with room (none binds) is the unbounded problem's best, so it is the
bounded one's; where a bound binds, the multi-start runs as well."""

from __future__ import annotations

from qropt.synthesis import atlas as atlas_
from qropt.synthesis import criteria, multistart
from qropt.synthesis.search.base import STOP, Stage


class AtlasStarts(Stage):
    name = "atlas"

    def accepts(self, problem, plan):
        return plan is not None and bool(plan.atlas.designs) and plan.searching and plan.spread

    def run(self, problem, pool, context):
        ms, plan, tol = context.solver.multistart, pool.plan, context.settings.atlas_short
        first = [("atlas", v, b) for v, b in plan.atlas.designs]
        cands = ms.run(
            problem, first, context.targets, context.max_rounds, pool.designs, False, deadline=context.deadline
        )
        unbounded = atlas_.unbounded(problem, plan.atlas.unbounded)  # the problem whose optima they are
        between, floor = multistart.expected(unbounded, plan.atlas, pool.designs)
        how = plan.atlas.how
        done = {c.start for c in cands if c.ok}
        if multistart.short(problem, cands, between, tol) and len(done) < len(first):  # again, a larger limit
            again = [r for i, r in enumerate(first) if i not in done]
            cands += ms.run(
                problem,
                again,
                context.targets,
                context.max_rounds,
                pool.designs,
                False,
                True,
                deadline=context.deadline,
            )
            how += ", those without a design run again with a larger iteration limit"
        pool.candidates += cands
        if (
            any(c.ok for c in cands)
            and not multistart.short(problem, cands, floor, tol)
            and not held(problem, cands, plan.atlas.unbounded)
        ):
            pool.claim = f"best of {how}"
            return STOP
        return None  # none certified, or still short: the multi-start as well (these candidates kept, counted)


def held(problem, cands, names) -> bool:
    """Whether a bound among ``names`` (those the atlas's designs were found without) binds at the best certified
    candidate: it may then hold back a better design than the atlas's, which the multi-start looks for."""
    good = [c for c in cands if c.ok]
    if not names or not good:
        return False
    sign = criteria.sense(problem.objective)
    best = max(good, key=lambda c: sign * criteria.objective_of(problem, c.mechanism))
    return bool(criteria.binding(problem, best.mechanism, names))
