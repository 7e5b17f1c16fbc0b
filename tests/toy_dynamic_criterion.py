"""A dynamic criterion defined in one file, as a user would: the peak drive torque of a crank, written anew on the
public base of peaks over the turn (``dynamic.PeakOverTurn``) with the capabilities the search reads: the quantity
whose peak it is (the SQP on the exact peak) and a transmission guard (the guarded multi-start and the evolution).
Being the same quantity as the shipped ``peak_torque``, a solve by it must give the same design to the last bit."""

from __future__ import annotations

import math

import numpy as np

from qropt.synthesis import criteria, dynamic


class PeakDriveTorque(dynamic.PeakOverTurn):
    """The largest |crank torque| over the turn at constant omega2 (N m)."""

    name, unit, label = "peak_drive_torque", "N m", "peak drive torque"
    what, epigraph_name = "torque", "peak |crank torque|"
    guard = math.radians(10.0)

    @staticmethod
    def quantity(d):
        return np.abs(d.torque)

    def lifted(self, s, out):
        t = s.torque(out)
        return t, [t, -t]


DRIVE = criteria.CRITERIA.get("peak_drive_torque") or criteria.register(PeakDriveTorque())
