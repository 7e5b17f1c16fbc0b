"""qropt: optimisation-based dimensional synthesis of quick-return mechanisms.

The public names only; the layers, from the bottom: kinematics -> dynamics -> mechanisms -> synthesis ->
studies | convex -> io (see docs/architecture.md). Importing it attaches every object's pictures and notebook
view (``qropt.io.views``).
"""

from qropt.convex.servo import SpeedProfile, speed_profile
from qropt.convex.tolerance import Allocation, MonteCarlo, allocate, sensitivities
from qropt.dynamics import (
    BodyMass,
    Counterweight,
    Drive,
    Dynamics,
    Force,
    Loads,
    Masses,
    Motor,
    PinFriction,
    Simulation,
    Torque,
    Window,
    simulate,
)
from qropt.errors import (
    AssemblyError,
    ChartError,
    DegenerateMechanism,
    GrashofError,
    InvalidParameter,
    NoDeadCentres,
    PinLocked,
    ProblemError,
    QroptError,
    UnsupportedLoad,
)
from qropt.io import views  # noqa: F401 - attaches every object's plot() and notebook view
from qropt.mechanisms import (
    CouplerSlider,
    CrankRockerSlider,
    CrankShaper,
    DragLinkSlider,
    FourBar,
    Mechanism,
    SliderCrank,
    SlotRamShaper,
    Whitworth,
    grashof,
    mechanism_type,
)
from qropt.schema import VERSION as __version__  # noqa: F401 - the installed package's (pyproject.toml)
from qropt.studies import Chart, Comparison, Family, Front, Reachable, chart, design, family, pareto, reachable
from qropt.synthesis.certificate import Certificate
from qropt.synthesis.problem import Problem
from qropt.synthesis.result import STATUSES, Result
from qropt.synthesis.solver import Solver, solve, target_range

__all__ = [
    # mechanism types
    "SliderCrank",
    "CrankShaper",
    "Whitworth",
    "CrankRockerSlider",
    "DragLinkSlider",
    "FourBar",
    "CouplerSlider",
    "SlotRamShaper",
    "Mechanism",
    "grashof",
    "mechanism_type",
    # synthesis
    "Problem",
    "Result",
    "STATUSES",
    "Certificate",
    "Solver",
    "solve",
    "target_range",
    # studies
    "design",
    "Comparison",
    "pareto",
    "Front",
    "family",
    "Family",
    "reachable",
    "Reachable",
    "chart",
    "Chart",
    # dynamics
    "Masses",
    "BodyMass",
    "Counterweight",
    "Loads",
    "Force",
    "Torque",
    "Window",
    "Dynamics",
    "Motor",
    "Drive",
    "PinFriction",
    "Simulation",
    "simulate",
    # convex layer
    "speed_profile",
    "SpeedProfile",
    "sensitivities",
    "allocate",
    "Allocation",
    "MonteCarlo",
    # errors
    "QroptError",
    "InvalidParameter",
    "GrashofError",
    "AssemblyError",
    "NoDeadCentres",
    "DegenerateMechanism",
    "ProblemError",
    "ChartError",
    "UnsupportedLoad",
    "PinLocked",
]
