"""Dynamics: the mass model and loads (``model``; general forces and torques at crank angles: ``applied``), a
rigid body's motion from its joints' (``rigid``), exact
inverse dynamics (``inverse``; compiled once a call shape is hot: ``compiled``), cycle quantities and the
flywheel (``cycle``), and the crank's motion under a motor (``forward``)."""

from qropt.dynamics.forward import Motor, Simulation, TurnSpeeds, simulate, steady_mean_torque
from qropt.dynamics.inverse import Dynamics, body_masses, inverse_dynamics
from qropt.dynamics.model import BodyMass, Counterweight, Force, Loads, Masses, Torque, Window

__all__ = [
    "BodyMass",
    "Counterweight",
    "Loads",
    "Force",
    "Torque",
    "Window",
    "Masses",
    "Dynamics",
    "body_masses",
    "inverse_dynamics",
    "Motor",
    "Simulation",
    "TurnSpeeds",
    "simulate",
    "steady_mean_torque",
]
