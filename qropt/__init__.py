"""qropt: optimisation-based dimensional synthesis of quick-return mechanisms."""

from qropt.certify import Certificate
from qropt.design import Comparison, design
from qropt.errors import (
    AssemblyError,
    DegenerateMechanism,
    GrashofError,
    InvalidParameter,
    NoDeadCentres,
    ProblemError,
    QroptError,
)
from qropt.family import Family, family
from qropt.mechanisms import (
    CrankRockerSlider,
    CrankShaper,
    DragLinkSlider,
    FourBar,
    SliderCrank,
    Whitworth,
    grashof,
    mechanism_type,
)
from qropt.pareto import Front, pareto
from qropt.problem import Problem
from qropt.reachable import Reachable, reachable
from qropt.result import STATUSES, Result
from qropt.solve import Solver, solve, target_range

__version__ = "0.1.0"

__all__ = [
    "SliderCrank",
    "CrankShaper",
    "Whitworth",
    "CrankRockerSlider",
    "DragLinkSlider",
    "FourBar",
    "grashof",
    "Problem",
    "Result",
    "STATUSES",
    "Certificate",
    "Solver",
    "solve",
    "family",
    "Family",
    "reachable",
    "Reachable",
    "target_range",
    "design",
    "Comparison",
    "pareto",
    "Front",
    "mechanism_type",
    "QroptError",
    "InvalidParameter",
    "GrashofError",
    "AssemblyError",
    "NoDeadCentres",
    "DegenerateMechanism",
    "ProblemError",
]
