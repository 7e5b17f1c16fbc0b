"""The mass model and the loads: data (numbers and tables) that problems, results and chart tiles carry.

SI throughout (kg, m, N, kg m^2); a mechanism's lengths are converted from its stated unit. A body's frame has its
origin at the body's first joint and x along the body towards its second joint (or ray); see
``docs/dynamics.md`` and the contract's "Dynamics" section.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from qropt.errors import InvalidParameter
from qropt.validate import LIMIT, number


def _real(what, v, *, positive=False, nonneg=False, nonzero=False, allow_inf=False) -> float:
    """A finite number (|value| <= LIMIT; +inf too if ``allow_inf``), or InvalidParameter naming ``what``."""
    if not (allow_inf and isinstance(v, (int, float, np.integer, np.floating)) and v == math.inf):
        v = number(what, v, limit=LIMIT)
    if positive and v <= 0:
        raise InvalidParameter(f"{what} must be positive, got {v:g}")
    if nonneg and v < 0:
        raise InvalidParameter(f"{what} must be zero or positive, got {v:g}")
    if nonzero and v == 0:
        raise InvalidParameter(f"{what} must be nonzero (its sign is the sense of rotation), got 0")
    return float(v)


@dataclass(frozen=True)
class BodyMass:
    """One body: mass (kg), centre of mass (m) in the body's frame, moment of inertia (kg m^2) about it."""

    mass: float
    com: tuple = (0.0, 0.0)
    inertia: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "mass", _real("a body's mass", self.mass, nonneg=True))
        c = self.com
        if not isinstance(c, (tuple, list)) or len(c) != 2:
            raise InvalidParameter(f"a body's centre of mass is a pair (x, y) in metres, got {c!r}")
        object.__setattr__(self, "com", (_real("com x", c[0]), _real("com y", c[1])))
        object.__setattr__(self, "inertia", _real("a body's moment of inertia", self.inertia, nonneg=True))

    def to_dict(self) -> dict:
        return {"mass": self.mass, "com": list(self.com), "inertia": self.inertia}

    @classmethod
    def from_dict(cls, d) -> BodyMass:
        if not isinstance(d, dict) or set(d) - {"mass", "com", "inertia"} or "mass" not in d:
            raise InvalidParameter(f"a body mass is {{mass, com, inertia}}, got {d!r}")
        return cls(d["mass"], tuple(d.get("com", (0.0, 0.0))), d.get("inertia", 0.0))


@dataclass(frozen=True)
class Counterweight:
    """A point mass (kg) on the crank at ``radius`` (m) from O2, ``angle`` (rad) counter-clockwise from the
    crank's direction O2->A (pi: opposite the pin). ``free``: a solve chooses its mass (up to ``mass``) and its
    angle (``Counterweight.balancing``); the chosen one is the Result's ``counterweight``."""

    mass: float
    radius: float
    angle: float = math.pi
    free: bool = False

    def __post_init__(self):
        object.__setattr__(self, "mass", _real("the counterweight's mass", self.mass, nonneg=True))
        object.__setattr__(self, "radius", _real("the counterweight's radius", self.radius, nonneg=True))
        object.__setattr__(self, "angle", _real("the counterweight's angle", self.angle))
        if not isinstance(self.free, bool):
            raise InvalidParameter(f"the counterweight's free is true or false, got {self.free!r}")
        if self.free and not (self.mass > 0 and self.radius > 0):
            raise InvalidParameter(
                "a free counterweight needs a positive largest mass and radius (Counterweight.balancing(radius, "
                f"max_mass)), got mass {self.mass:g} kg at radius {self.radius:g} m"
            )

    @classmethod
    def balancing(cls, radius: float, max_mass: float) -> Counterweight:
        """A counterweight a solve chooses: any mass up to ``max_mass`` (kg), at any angle, at ``radius`` (m)."""
        return cls(max_mass, radius, math.pi, True)

    def start(self) -> Counterweight:
        """Where a solve starts a free counterweight: half its largest mass, opposite the pin (a fixed one: itself)."""
        return Counterweight(self.mass / 2, self.radius, math.pi) if self.free else self

    def part(self) -> tuple:
        """The crank's part it is: (mass, its point (x, y) in the crank's frame, 0 inertia about itself)."""
        return (self.mass, (self.radius * math.cos(self.angle), self.radius * math.sin(self.angle)), 0.0)

    def with_moment(self, mx: float, my: float) -> Counterweight:
        """The fixed counterweight of first moment (mx, my) kg m in the crank's frame, at this radius."""
        return Counterweight(math.hypot(mx, my) / self.radius, self.radius, math.atan2(my, mx))

    def to_dict(self) -> dict:
        return {"mass": self.mass, "radius": self.radius, "angle": self.angle} | ({"free": True} if self.free else {})


@dataclass(frozen=True)
class Masses:
    """The mass model of a mechanism: every link a uniform slender bar of ``density`` (kg per metre of link; a
    plate the rigid union of bars from its first joint to each other joint), the ram a point mass ``ram`` (kg),
    the crank-pin block ``block`` (kg, a point at the pin; 0: massless), a crank ``counterweight``, and
    ``bodies``: name -> BodyMass overriding the default of that body. ``Masses.bars(...)`` builds one."""

    density: float = 0.0
    ram: float = 0.0
    block: float = 0.0
    bodies: dict = field(default_factory=dict)
    counterweight: Counterweight | None = None

    def __post_init__(self):
        object.__setattr__(self, "density", _real("density (kg/m)", self.density, nonneg=True))
        object.__setattr__(self, "ram", _real("the ram's mass (kg)", self.ram, nonneg=True))
        object.__setattr__(self, "block", _real("the block's mass (kg)", self.block, nonneg=True))
        if not isinstance(self.bodies, dict):
            raise InvalidParameter(f"bodies is a dict of body name -> BodyMass, got {self.bodies!r}")
        bodies = {}
        for k, v in self.bodies.items():
            if not isinstance(k, str):
                raise InvalidParameter(f"a body is named by a string, got {k!r}")
            bodies[k] = v if isinstance(v, BodyMass) else BodyMass.from_dict(v)
        object.__setattr__(self, "bodies", bodies)
        cw = self.counterweight
        if cw is not None and not isinstance(cw, Counterweight):
            if (
                not isinstance(cw, dict)
                or set(cw) - {"mass", "radius", "angle", "free"}
                or {"mass", "radius"} - set(cw)
            ):
                raise InvalidParameter(
                    f"counterweight is a Counterweight or {{mass, radius, angle?, free?}} (kg, m, rad), got {cw!r:.120}"
                )
            object.__setattr__(self, "counterweight", Counterweight(**cw))

    @classmethod
    def bars(cls, density: float, ram: float = 0.0, *, block: float = 0.0, bodies=None, counterweight=None) -> Masses:
        """Uniform slender bars of ``density`` kg/m, a ram of ``ram`` kg; overrides by body name."""
        return cls(density, ram, block, dict(bodies or {}), counterweight)

    @classmethod
    def steel(cls, area: float, ram: float = 0.0, **kw) -> Masses:
        """Steel links (7850 kg/m^3) of cross-section ``area`` (m^2): density = 7850 * area kg/m."""
        return cls.bars(STEEL * _real("the cross-section (m^2)", area, positive=True), ram, **kw)

    def replace(self, **kw) -> Masses:
        return Masses(**{**self.__dict__, **kw})

    @property
    def balancing(self) -> bool:
        """Whether a solve chooses the counterweight (``Counterweight.balancing``)."""
        return self.counterweight is not None and self.counterweight.free

    def started(self) -> Masses:
        """These masses with a free counterweight at its start (the masses themselves otherwise)."""
        return self.replace(counterweight=self.counterweight.start()) if self.balancing else self

    def to_dict(self) -> dict:
        return {
            "density": self.density,
            "ram": self.ram,
            "block": self.block,
            "bodies": {k: v.to_dict() for k, v in self.bodies.items()},
            **({} if self.counterweight is None else {"counterweight": self.counterweight.to_dict()}),
        }

    @classmethod
    def from_dict(cls, d) -> Masses:
        keys = {"density", "ram", "block", "bodies", "counterweight"}
        if not isinstance(d, dict) or set(d) - keys:
            raise InvalidParameter(f"masses take {sorted(keys)}, got {d!r}")
        return cls(
            d.get("density", 0.0), d.get("ram", 0.0), d.get("block", 0.0), d.get("bodies") or {}, d.get("counterweight")
        )


STEEL = 7850.0  # kg/m^3


def slender_bar(density, length, ux=1.0, uy=0.0) -> tuple:
    """A uniform slender bar from its body frame's origin along the unit vector (ux, uy): (mass, (cx, cy),
    inertia about its centre) = (rho L, L/2 (ux, uy), m L^2 / 12). Numbers or CasADi expressions alike."""
    mass = density * length
    return (mass, (length / 2 * ux, length / 2 * uy), mass * length * length / 12)


def union(a: tuple, b: tuple) -> tuple:
    """Two rigid parts (mass, (cx, cy), inertia) in one body frame as one body (parallel axes); numbers or CasADi
    expressions alike (two massless numbers give a massless part at the origin)."""
    (ma, ca, ia), (mb, cb, ib) = a, b
    mass = ma + mb
    if isinstance(mass, (int, float)) and mass == 0:
        return (0.0, (0.0, 0.0), 0.0)
    cx, cy = (ma * ca[0] + mb * cb[0]) / mass, (ma * ca[1] + mb * cb[1]) / mass
    inertia = ia + ib + ma * ((ca[0] - cx) ** 2 + (ca[1] - cy) ** 2) + mb * ((cb[0] - cx) ** 2 + (cb[1] - cy) ** 2)
    return (mass, (cx, cy), inertia)


@dataclass(frozen=True)
class Loads:
    """What the mechanism works against. ``cutting_force`` (N) resists the ram's motion on the working (slow)
    stroke only: a constant, or a table ((x, F), ...) of force against the ram's position x (the mechanism's
    length unit), linear between points and constant beyond them; ``friction``: the slide's coefficient (the
    guide's friction force mu |N| against the ram's velocity); ``gravity`` (m/s^2) along -y; ``follower_torque``
    (N m): for a four-bar whose output is its follower, a torque resisting its working swing."""

    cutting_force: float | tuple = 0.0
    friction: float = 0.0
    gravity: float = 0.0
    follower_torque: float = 0.0

    def __post_init__(self):
        f = self.cutting_force
        if isinstance(f, (tuple, list)):
            pts = []
            for row in f:
                if not isinstance(row, (tuple, list)) or len(row) != 2:
                    raise InvalidParameter(f"a cutting-force table is ((x, F), ...), got row {row!r}")
                pts.append((_real("a table's x", row[0]), _real("a table's force (N)", row[1], nonneg=True)))
            if not pts or len(pts) > 10_000 or any(b[0] <= a[0] for a, b in zip(pts, pts[1:], strict=False)):
                raise InvalidParameter("a cutting-force table has 1 to 10,000 rows with x strictly increasing")
            object.__setattr__(self, "cutting_force", tuple(pts))
        else:
            object.__setattr__(self, "cutting_force", _real("cutting_force (N)", f, nonneg=True))
        object.__setattr__(self, "friction", _real("friction (a coefficient)", self.friction, nonneg=True))
        object.__setattr__(self, "gravity", _real("gravity (m/s^2)", self.gravity, nonneg=True))
        object.__setattr__(self, "follower_torque", _real("follower_torque (N m)", self.follower_torque, nonneg=True))

    @property
    def switching(self) -> bool:
        """Whether a cutting force or a follower's load torque acts: they switch on and off at the dead centres."""
        f = self.cutting_force
        return bool(self.follower_torque or (any(r[1] > 0 for r in f) if isinstance(f, tuple) else f))

    @property
    def jumps(self) -> bool:
        """Whether the joint forces jump at the dead centres: a cutting force switching on or off there, or the
        slide's friction turning with the ram's velocity."""
        return self.switching or bool(self.friction)

    def force_at(self, x) -> np.ndarray:
        """The cutting force's magnitude (N) at ram positions x (the mechanism's unit)."""
        f = self.cutting_force
        x = np.asarray(x, float)
        if isinstance(f, tuple):
            xs, fs = np.array(f).T
            return np.interp(x, xs, fs)
        return np.full(x.shape, f)

    def to_dict(self) -> dict:
        f = self.cutting_force
        return {
            "cutting_force": [list(r) for r in f] if isinstance(f, tuple) else f,
            "friction": self.friction,
            "gravity": self.gravity,
            "follower_torque": self.follower_torque,
        }

    @classmethod
    def from_dict(cls, d) -> Loads:
        keys = {"cutting_force", "friction", "gravity", "follower_torque"}
        if not isinstance(d, dict) or set(d) - keys:
            raise InvalidParameter(f"loads take {sorted(keys)}, got {d!r}")
        return cls(**d)


__all__ = ["BodyMass", "Counterweight", "Masses", "Loads", "STEEL", "slender_bar", "union"]
