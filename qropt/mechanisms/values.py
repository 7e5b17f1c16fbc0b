"""The values a mechanism's analysis answers with (typed, immutable): positions, motion, dead centres, peaks,
extremes, the bounding box, gamma_min, a type's rules and bodies, and a quantity's exact sensitivity. Lengths in
the mechanism's unit, angles in rad, theta2 counter-clockwise from +x."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np


class cached_property:  # noqa: N801 - functools.cached_property without its lock (Python 3.11 takes one per read)
    """A value computed on first read and kept in the instance's ``__dict__`` (later reads do not come here)."""

    def __init__(self, func):
        self.func, self.name, self.__doc__ = func, func.__name__, func.__doc__

    def __set_name__(self, owner, name):
        self.name = name

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        value = obj.__dict__[self.name] = self.func(obj)
        return value


class Rule(NamedTuple):
    """A feasibility rule of a type, written once over a math namespace: it holds where ``value >= 0``.

    Construction checks it on numbers, the NLP states it as a row, ``reachable`` reads the interval it leaves
    a parameter (the rules are linear in each length)."""

    name: str
    value: Any


@dataclass(frozen=True)
class Positions:
    """Joint coordinates (arrays of shape (n, 2)) and link angles (rad) at the crank angles theta2."""

    theta2: np.ndarray
    points: dict
    angles: dict
    x: np.ndarray


class Motion:
    """Output position x, velocity v, acceleration a and every link's angle, omega, alpha (dicts by angle name,
    computed on first use).

    Units: length, length/s, length/s^2, rad, rad/s, rad/s^2 (for FourBar x is theta4 in rad).
    """

    def __init__(self, theta2: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray, links):
        self.theta2, self.x, self.v, self.a = theta2, x, v, a
        self._links = links  # () -> (angles, omega, alpha)

    @cached_property
    def _rates(self) -> tuple[dict, dict, dict]:
        return self._links()

    @property
    def angles(self) -> dict:
        return self._rates[0]

    @property
    def omega(self) -> dict:
        return self._rates[1]

    @property
    def alpha(self) -> dict:
        return self._rates[2]

    def __reduce__(self):  # pickled with its link rates computed (the closure that makes them is not data)
        rates = self._rates
        return (_motion_of, (self.theta2, self.x, self.v, self.a, rates))

    def __repr__(self):
        return f"Motion({self.theta2.size} crank angles: x, v, a, and {', '.join(self.angles)})"


def _motion_of(theta2, x, v, a, rates) -> Motion:
    return Motion(theta2, x, v, a, lambda: rates)


class DeadCentres(NamedTuple):
    """Crank angles (rad, in [0, 2pi)) of the largest and smallest output, and those outputs.

    ``reversals`` counts the output's local maxima over a turn: 1 for a proper
    quick-return; more means the slider reverses inside a stroke and TR is ill-posed.
    """

    theta_max: float
    theta_min: float
    x_max: float
    x_min: float
    reversals: int = 1


class PeakAcceleration(NamedTuple):
    """Largest |slider acceleration| (length/s^2) at a constant omega2 and the crank angle (rad) where it occurs."""

    value: float
    theta2: float


class PeakVelocity(NamedTuple):
    """Largest |slider velocity| (length/s) over the working stroke at a constant omega2, the crank angle (rad)
    where it occurs, and the peak crank torque per newton of a constant cutting force (length: N m per N)."""

    value: float
    theta2: float
    torque_per_newton: float


class AccelerationExtremes(NamedTuple):
    """Local maxima and minima of d2x/dtheta2 over a turn: each (theta2 array in rad, value array)."""

    maxima: tuple
    minima: tuple


class BoundingBox(NamedTuple):
    """Extremes of every joint's path over a turn (length), the crank angles (rad) where they occur and the
    coordinates that reach them (index into the loop's points, two per joint: x then y), each in the order
    x_min, x_max, y_min, y_max."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    angles: tuple
    coords: tuple = ()


class GammaMin(NamedTuple):
    """Smallest transmission angle over a full turn and every joint: value (rad), theta2 (rad), joint."""

    value: float
    theta2: float
    joint: str


BODY_KINDS = ("bar", "plate", "slot-lever", "block", "ram", "yoke")


class Body(NamedTuple):
    """A moving body of a type, declared once on the type (``Mechanism.BODIES``) for its pictures and mass model.

    name: what it is ('crank', 'coupler', 'lever', 'rod', 'ram', ...); joints: the joints it carries, its frame's
    origin first (the body's x axis points from it towards the second joint, or along the ray through it);
    kind, one of BODY_KINDS:

    - 'bar': a rigid straight link, a binary link or a lever carrying collinear joints (the four-bar sliders'
      follower O4, B, C); drawn from its first joint to the farthest of the others;
    - 'plate': a rigid link over three or more joints that are not collinear (a coupler carrying a coupler
      point); drawn as a filled polygon over its joints in order;
    - 'slot-lever': a lever about its first joint (a ground pivot) along the ray through its second, which slides
      in the lever's slot; drawn from the pivot to the farthest its joints reach over a turn, with the slot;
    - 'block': a block on a pin sliding in a slot: (the pin, a second point on the slot's line);
    - 'ram': the slider on the slide line (along +x): (its pin,);
    - 'yoke': a ram driven by a pin sliding in a slot normal to the slide line: (the pin,).
    """

    name: str
    joints: tuple[str, ...]
    kind: str


SENSITIVE = ("time_ratio", "stroke", "gamma_min", "peak_acceleration")  # quantities with exact sensitivities


class Sensitivity(NamedTuple):
    """Exact derivatives of a cycle quantity Q with respect to the parameters ``names``.

    ``branches`` (J, len(names)): the gradients of the smooth pieces of which Q is, near these parameters, the
    largest (``combine`` 'max') or least ('min'); J = 1 and ``kink`` '' where Q is differentiable, else ``kink``
    says why it is not (the one-sided derivatives ``left`` and ``right`` then differ)."""

    quantity: str
    names: tuple
    branches: np.ndarray
    combine: str = "max"
    kink: str = ""

    @property
    def gradient(self) -> np.ndarray:
        """Per parameter the one-sided derivative of larger magnitude: the derivative where Q is smooth, and a
        slope whose magnitude bounds either side at a kink (a safe coefficient for a worst-case stack-up)."""
        g = self.branches
        return g[np.argmax(np.abs(g), axis=0), np.arange(g.shape[1])]

    @property
    def right(self) -> np.ndarray:
        """dQ/dp_i from above (p_i increased)."""
        return self.branches.max(axis=0) if self.combine == "max" else self.branches.min(axis=0)

    @property
    def left(self) -> np.ndarray:
        """dQ/dp_i from below (p_i decreased)."""
        return self.branches.min(axis=0) if self.combine == "max" else self.branches.max(axis=0)

    def change(self, delta) -> np.ndarray:
        """First-order change of Q for parameter changes delta (len(names),) or (len(names), K): the largest
        (or least) of the pieces' linear changes, exact to second order even at a kink."""
        lin = self.branches @ np.asarray(delta, float)
        return lin.max(axis=0) if self.combine == "max" else lin.min(axis=0)


__all__ = [
    "cached_property",
    "Rule",
    "Positions",
    "Motion",
    "DeadCentres",
    "PeakAcceleration",
    "PeakVelocity",
    "AccelerationExtremes",
    "BoundingBox",
    "GammaMin",
    "BODY_KINDS",
    "Body",
    "SENSITIVE",
    "Sensitivity",
]
