"""The drive's criterion: the RMS torque at the motor over the turn at constant omega2 (N m), through the problem's
gearbox (``Problem(drive=qropt.Drive(ratio, efficiency))``). The motor's torque is ``Drive.motor_torque``: the crank
torque over i eta where the motor drives, times eta over i where it brakes, so the efficiency weighs the two parts
of the turn differently and the design that minimises it is not the crank's RMS optimum in general. At constant
speed the inertias of the gearbox and the rotor carry no torque. Objective ``min_rms_motor_torque``, bound
condition ``max_rms_motor_torque`` (the motor's rated torque).

Its value is the RMS crank torque's rule applied to the motor's torque (``drive.rms_motor_torque(..., split=False)``:
Gauss-Legendre on each stroke, the nodes moving with the dead centres), which the NLP states and the certificate
evaluates exactly. ``drive_check`` also splits the strokes where the crank torque changes sign (the motor's torque
has a kink there), which this rule does not.
"""

from __future__ import annotations

import math

from qropt.dynamics.drive import rms_motor_torque
from qropt.synthesis import dynamic
from qropt.synthesis.criteria import register

TWO_PI = 2 * math.pi


class RmsMotorTorque(dynamic.RmsTorque):
    """The root mean square of the motor's torque over the turn at constant omega2 (N m)."""

    name, unit, label = "rms_motor_torque", "N m", "RMS motor torque"
    reported = False  # only where the problem has a drive and uses it

    def check(self, problem) -> str | None:
        if problem.drive is None:
            return f"{self.objective} needs the drive: Problem(..., drive=qropt.Drive(ratio, efficiency))"
        return super().check(problem)

    def baked(self, problem) -> tuple:
        return (repr(problem.drive),)

    def value(self, problem, m):
        return rms_motor_torque(dynamic._cycle(problem, m), problem.drive, split=False)

    def measure(self, f, z):
        s = dynamic._symbolic(f)
        total = 0
        for out, w, arc in f.strokes(dynamic.quadrature_rule(f)):
            total += 0.5 * arc * w * f.drive.motor_torque(s.torque(out), f.omega2) ** 2
        return total / TWO_PI


register(RmsMotorTorque(), built_in=True)

__all__ = ["RmsMotorTorque"]
