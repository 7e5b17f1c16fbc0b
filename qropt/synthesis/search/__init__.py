"""The search of a solve as a declared pipeline of strategies (``pipeline.DEFAULT``): the Strategy protocol, the
Pool they share and the Context of one solve (``base``), one module per strategy, the settings of the search."""

from qropt.synthesis.search.base import STOP, Context, Phase, Pool, Stage, Strategy, run, solve
from qropt.synthesis.search.pipeline import DEFAULT, STARTS, starts_of
from qropt.synthesis.settings import Settings

__all__ = [
    "Strategy",
    "Stage",
    "Pool",
    "Context",
    "Phase",
    "run",
    "solve",
    "STOP",
    "DEFAULT",
    "STARTS",
    "starts_of",
    "Settings",
]
