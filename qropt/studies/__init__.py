"""Studies built on single solves: type synthesis (``design``; ``type_problem`` is one row's Problem), trade-off
fronts (``pareto``), one-parameter families (``family``), reachable ranges (``reachable``) and design charts
(``chart``)."""

from qropt.studies._chart import Chart
from qropt.studies._chart_run import chart
from qropt.studies._design import Comparison, design, type_problem
from qropt.studies._family import Family, family
from qropt.studies._pareto import Front, pareto
from qropt.studies._reachable import Reachable, reachable

__all__ = [
    "Chart",
    "chart",
    "Comparison",
    "design",
    "type_problem",
    "Family",
    "family",
    "Front",
    "pareto",
    "Reachable",
    "reachable",
]
