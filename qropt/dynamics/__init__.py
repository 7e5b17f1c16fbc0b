"""Dynamics: the mass model and loads (``model``; general forces and torques at crank angles: ``applied``), a
rigid body's motion from its joints' (``rigid``), exact
inverse dynamics (``inverse``; compiled once a call shape is hot: ``compiled``), cycle quantities, the
flywheel and the efficiency (``cycle``), the crank's motion under a motor (``forward``) and the drive (``drive``)."""

from qropt.dynamics.cycle import Efficiency, StrokeWork
from qropt.dynamics.drive import Drive, DriveCheck, drive_check
from qropt.dynamics.forward import Motor, Simulation, TurnSpeeds, simulate, steady_mean_torque
from qropt.dynamics.inverse import Dynamics, body_masses, inverse_dynamics
from qropt.dynamics.model import BodyMass, Counterweight, Force, Loads, Masses, PinFriction, Torque, Window

__all__ = [
    "BodyMass",
    "Counterweight",
    "Loads",
    "Force",
    "Torque",
    "Window",
    "PinFriction",
    "Masses",
    "Dynamics",
    "body_masses",
    "inverse_dynamics",
    "Motor",
    "Simulation",
    "TurnSpeeds",
    "simulate",
    "steady_mean_torque",
    "Drive",
    "DriveCheck",
    "drive_check",
    "Efficiency",
    "StrokeWork",
]
