"""A criterion defined in one file, as a user would: the crank length r2 (length), minimised (a small crank).

Registering it is all it takes for solve, design, pareto, family.best, the CLI and Result to know it.
"""

from qropt.synthesis import criteria


class Crank(criteria.Criterion):
    """The crank length r2 (length): a criterion of the parameters alone, so its NLP term is its expression."""

    name, unit, label = "crank", "length", "crank length"

    def value(self, problem, m):
        return m.params["r2"]

    def expression(self, f):
        return f.params["r2"]


CRANK = criteria.register(Crank()) if "crank" not in criteria.CRITERIA else criteria.CRITERIA["crank"]
