"""Analysis and dynamics as plain JSON-ready records: what ``qropt analyze --json`` prints and the web API
answers (angles in degrees under names ending in ``_deg``, lengths in the mechanism's unit, forces in N, SI
otherwise)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from qropt.mechanisms import Mechanism, type_reference


def analysis(m: Mechanism, theta2: float, omega2: float, alpha2: float) -> dict:
    """Every analysed quantity of m over the turn and its state at crank angle theta2 (rad), omega2 (rad/s),
    alpha2 (rad/s^2)."""
    d, g = m.dead_centres(), m.gamma_min()
    a, b = m.stroke_angles()
    mo = m.motion(np.array([theta2]), omega2, alpha2)
    out = {
        "type": type_reference(type(m)),
        "output": m.OUTPUT,
        "params": dict(m.params),
        "units": m.units,
        "time_ratio": m.time_ratio(),
        "stroke": m.stroke(),
        "dead_centres": {
            "theta_max_deg": math.degrees(d.theta_max),
            "theta_min_deg": math.degrees(d.theta_min),
            "x_max": d.x_max,
            "x_min": d.x_min,
            "reversals": d.reversals,
        },
        "stroke_angles_deg": [math.degrees(max(a, b)), math.degrees(min(a, b))],
        "working_direction": m.working_direction(omega2),
        "gamma_min": {"value_deg": math.degrees(g.value), "theta2_deg": math.degrees(g.theta2), "joint": g.joint},
        "state": {
            "theta2_deg": math.degrees(theta2),
            "omega2": omega2,
            "alpha2": alpha2,
            "x": float(mo.x[0]),
            "v": float(mo.v[0]),
            "a": float(mo.a[0]),
            "links": {
                k: {
                    "angle_deg": math.degrees(float(mo.angles[k][0])),
                    "omega": float(mo.omega[k][0]),
                    "alpha": float(mo.alpha[k][0]),
                }
                for k in mo.angles
            },
        },
    }
    if hasattr(m, "grashof"):
        out["grashof"] = m.grashof()._asdict()
    return out


def dynamics(cd, masses, ex, fw=None) -> dict:
    """The dynamic extremes ``ex`` of a ``CycleDynamics`` cd with its ``masses`` (peak and RMS torque, N m; peak
    joint forces and shaking, N, N m) and its flywheel ``fw`` if any (every field but the speed: omega2)."""
    out = {
        "type": type(cd.m).__name__,
        "omega2": cd.omega2,
        "alpha2": cd.alpha2,
        "masses": masses.to_dict(),
        "loads": cd.loads.to_dict(),
        "peak_torque": {"value": ex.peak_torque.value, "theta2_deg": math.degrees(ex.peak_torque.theta2)},
        "rms_torque": ex.rms_torque,
        "mean_torque": ex.mean_torque,
        "peak_forces": {k: {"value": p.value, "theta2_deg": math.degrees(p.theta2)} for k, p in ex.peak_forces.items()},
        "peak_shaking_force": ex.peak_shaking_force.value,
        "peak_shaking_moment": ex.peak_shaking_moment.value,
    }
    if fw is not None:
        out["flywheel"] = {k: v for k, v in dataclasses.asdict(fw).items() if k != "omega2"}
    return out
