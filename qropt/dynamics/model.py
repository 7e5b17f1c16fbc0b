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
    ``bodies``: name -> BodyMass overriding the default of that body; ``points``: joint -> a point mass (kg) at
    that joint, added to the body that carries it (the ram for the ram's joint). ``Masses.bars(...)`` builds one."""

    density: float = 0.0
    ram: float = 0.0
    block: float = 0.0
    bodies: dict = field(default_factory=dict)
    counterweight: Counterweight | None = None
    points: dict = field(default_factory=dict)

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
        if not isinstance(self.points, dict):
            raise InvalidParameter(f"points is a dict of joint name -> mass (kg), got {self.points!r:.120}")
        points = {}
        for k, v in self.points.items():
            if not isinstance(k, str) or not k:
                raise InvalidParameter(f"a point mass is placed at a joint named by a string, got {k!r}")
            points[k] = _real(f"the point mass at {k} (kg)", v, nonneg=True)
        object.__setattr__(self, "points", points)

    @classmethod
    def bars(
        cls, density: float, ram: float = 0.0, *, block: float = 0.0, bodies=None, counterweight=None, points=None
    ) -> Masses:
        """Uniform slender bars of ``density`` kg/m, a ram of ``ram`` kg; overrides by body name; point masses
        (kg) by joint."""
        return cls(density, ram, block, dict(bodies or {}), counterweight, dict(points or {}))

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
            **({"points": dict(self.points)} if self.points else {}),
        }

    @classmethod
    def from_dict(cls, d) -> Masses:
        keys = {"density", "ram", "block", "bodies", "counterweight", "points"}
        if not isinstance(d, dict) or set(d) - keys:
            raise InvalidParameter(f"masses take {sorted(keys)}, got {d!r}")
        return cls(
            d.get("density", 0.0),
            d.get("ram", 0.0),
            d.get("block", 0.0),
            d.get("bodies") or {},
            d.get("counterweight"),
            d.get("points") or {},
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


TWO_PI = 2 * math.pi
STROKES = ("working", "return", "both")
NAMED = {"working": "working", "return": "return", "always": "both"}
WAYS = ("+x", "-x")
MAX_ROWS = 10_000


def _pair(what, v) -> tuple:
    if isinstance(v, (str, bytes)) or not isinstance(v, (tuple, list)) or len(v) != 2:
        raise InvalidParameter(f"{what} is a pair of numbers, got {v!r:.120}")
    return (_real(what, v[0]), _real(what, v[1]))


def _table(what, v, *, nonneg=False) -> float | tuple:
    """A constant or a table ((abscissa, value), ...) with the abscissa strictly increasing (1 to MAX_ROWS rows)."""
    if not isinstance(v, (tuple, list)):
        return _real(what, v, nonneg=nonneg)
    rows = []
    for row in v:
        if not isinstance(row, (tuple, list)) or len(row) != 2:
            raise InvalidParameter(f"{what}: a table is ((abscissa, value), ...), got row {row!r:.120}")
        rows.append((_real(f"{what}: a table's abscissa", row[0]), _real(what, row[1], nonneg=nonneg)))
    if not rows or len(rows) > MAX_ROWS:
        raise InvalidParameter(f"{what}: a table has 1 to {MAX_ROWS:,} rows, got {len(rows)}")
    for a, b in zip(rows, rows[1:], strict=False):
        if b[0] <= a[0]:
            raise InvalidParameter(f"{what}: a table's abscissa must increase strictly, got {a[0]:g} then {b[0]:g}")
    return tuple(rows)


def level(magnitude, at) -> np.ndarray:
    """A constant or a table's value at the abscissae ``at`` (linear between rows, constant beyond them)."""
    at = np.asarray(at, float)
    if isinstance(magnitude, tuple):
        xs, fs = np.array(magnitude).T
        return np.interp(at, xs, fs)
    return np.full(at.shape, magnitude)


def _rows_dict(v):
    return [list(r) for r in v] if isinstance(v, tuple) else v


def _keys(what, d, required, optional) -> dict:
    if not isinstance(d, dict) or set(d) - set(required) - set(optional) or set(required) - set(d):
        raise InvalidParameter(f"{what} takes {sorted(required)} and optionally {sorted(optional)}, got {d!r:.160}")
    return d


@dataclass(frozen=True)
class Window:
    """Where a load acts: on a ``stroke`` ("working", "return" or "both"), within the ram's positions ``x`` =
    (x0, x1) (the mechanism's length unit; x0 < x1) if given, or over the crank angles ``theta2`` = (a, b) (rad,
    counter-clockwise from a to b, 0 < b - a <= 2 pi) if given. The names "working", "return" and "always" are
    the strokes' windows (``Window.of``)."""

    x: tuple | None = None
    stroke: str = "both"
    theta2: tuple | None = None

    def __post_init__(self):
        if self.stroke not in STROKES:
            raise InvalidParameter(f"a window's stroke is one of {list(STROKES)}, got {self.stroke!r:.60}")
        if self.x is not None:
            x0, x1 = _pair("a window's x range", self.x)
            if not x0 < x1:
                raise InvalidParameter(f"a window's x range (x0, x1) needs x0 < x1, got ({x0:g}, {x1:g})")
            object.__setattr__(self, "x", (x0, x1))
        if self.theta2 is not None:
            if self.x is not None or self.stroke != "both":
                raise InvalidParameter("a window is a range of theta2 alone: no x range or stroke with it")
            a, b = _pair("a window's theta2 range (rad)", self.theta2)
            if not 0 < b - a <= TWO_PI:
                raise InvalidParameter(f"a window's theta2 range (a, b) needs 0 < b - a <= 2 pi, got ({a:g}, {b:g})")
            object.__setattr__(self, "theta2", (a, b))

    @classmethod
    def of(cls, v) -> Window:
        """A window from a Window, a name ("working", "return", "always") or its dict (``to_dict``)."""
        if isinstance(v, Window):
            return v
        if isinstance(v, str):
            if v not in NAMED:
                raise InvalidParameter(f"a window is named one of {list(NAMED)} or is a qropt.Window, got {v!r:.60}")
            return cls(stroke=NAMED[v])
        if isinstance(v, dict):
            d = _keys("a window", v, (), ("x", "stroke", "theta2"))
            return cls(d.get("x"), d.get("stroke", "both"), d.get("theta2"))
        raise InvalidParameter(f"a window is a qropt.Window, a name or a dict, got {v!r:.80}")

    @property
    def by_stroke(self) -> bool:
        """Whether it needs to know the working stroke."""
        return self.stroke != "both"

    def to_dict(self):
        if self.x is None and self.theta2 is None:
            return next(k for k, v in NAMED.items() if v == self.stroke)
        if self.theta2 is not None:
            return {"theta2": list(self.theta2)}
        return {"x": list(self.x), "stroke": self.stroke}

    def active(self, theta2, working, x) -> np.ndarray:
        """Where it acts at crank angles theta2 (rad), ``working`` (bool, on the working stroke) and ram positions
        x (the mechanism's unit; None without a ram)."""
        on = np.ones(np.shape(theta2), bool)
        if self.stroke != "both":
            on &= working if self.stroke == "working" else ~working
        if self.x is not None:
            on &= (x >= self.x[0]) & (x <= self.x[1])
        if self.theta2 is not None:
            a, b = self.theta2
            on &= np.mod(theta2 - a, TWO_PI) <= b - a
        return on


def _against(what, v) -> str:
    if v not in ("x", "theta2"):
        raise InvalidParameter(f"{what}: a table is against 'x' (the ram's position) or 'theta2', got {v!r:.60}")
    return v


@dataclass(frozen=True)
class Force:
    """A force (N) at a point: ``at`` a joint's name ("ram": the output's joint, C or D by type, in every type
    with a ram or yoke) or a body's point (body, x, y) in the body's frame (m).
    ``direction``: "against" (opposing the point's velocity; zero where it is at rest), "slide" (along the slide
    line's +x, signed by the magnitude) or a vector (fx, fy) in the frame (its direction; the magnitude's sign
    turns it). ``magnitude``: a constant or a table ((x or theta2, N), ...) against the ram's position x (the
    mechanism's unit) or theta2 (rad, in [0, 2 pi)), as ``against`` says, linear between rows and constant beyond.
    ``window``: where it acts (``Window``)."""

    at: str | tuple
    magnitude: float | tuple
    direction: str | tuple = "against"
    window: Window | str = "working"
    against: str = "x"

    def __post_init__(self):
        at = self.at
        if isinstance(at, str):
            if not at:
                raise InvalidParameter("a force is at a joint named by a non-empty string or at (body, x, y)")
        elif isinstance(at, (tuple, list)) and len(at) == 3 and isinstance(at[0], str) and at[0]:
            at = (at[0], _real("a force's point x (m)", at[1]), _real("a force's point y (m)", at[2]))
        else:
            raise InvalidParameter(f"a force is at a joint (its name) or a body's point (body, x, y), got {at!r:.120}")
        object.__setattr__(self, "at", at)
        object.__setattr__(self, "against", _against(f"the force at {self.where}", self.against))
        object.__setattr__(self, "magnitude", _table(f"the force at {self.where} (N)", self.magnitude))
        d = self.direction
        if isinstance(d, str):
            if d not in ("against", "slide"):
                raise InvalidParameter(
                    f"the force at {self.where}: its direction is 'against', 'slide' or (fx, fy), got {d!r:.60}"
                )
        else:
            d = _pair(f"the force at {self.where}: its direction vector", d)
            if d[0] == 0 and d[1] == 0:
                raise InvalidParameter(f"the force at {self.where}: its direction vector has zero length")
        object.__setattr__(self, "direction", d)
        object.__setattr__(self, "window", Window.of(self.window))

    @property
    def where(self) -> str:
        return self.at if isinstance(self.at, str) else f"({self.at[0]}, {self.at[1]:g}, {self.at[2]:g})"

    def __str__(self) -> str:
        return f"the force at {self.where}"

    def to_dict(self) -> dict:
        return {
            "at": self.at if isinstance(self.at, str) else list(self.at),
            "magnitude": _rows_dict(self.magnitude),
            "direction": self.direction if isinstance(self.direction, str) else list(self.direction),
            "window": self.window.to_dict(),
            "against": self.against,
        }

    @classmethod
    def from_dict(cls, d) -> Force:
        d = _keys("a force", d, ("at", "magnitude"), ("direction", "window", "against"))
        return cls(
            d["at"], d["magnitude"], d.get("direction", "against"), d.get("window", "working"), d.get("against", "x")
        )


@dataclass(frozen=True)
class Torque:
    """A torque (N m, counter-clockwise positive) on body ``on``: a constant or a table against the ram's position
    x or theta2 (``against``, as ``Force``), acting in ``window``."""

    on: str
    magnitude: float | tuple
    window: Window | str = "always"
    against: str = "x"

    def __post_init__(self):
        if not isinstance(self.on, str) or not self.on:
            raise InvalidParameter(f"a torque is on a body named by a string, got {self.on!r:.80}")
        object.__setattr__(self, "against", _against(f"the torque on {self.on}", self.against))
        object.__setattr__(self, "magnitude", _table(f"the torque on {self.on} (N m)", self.magnitude))
        object.__setattr__(self, "window", Window.of(self.window))

    def __str__(self) -> str:
        return f"the torque on {self.on}"

    def to_dict(self) -> dict:
        return {
            "on": self.on,
            "magnitude": _rows_dict(self.magnitude),
            "window": self.window.to_dict(),
            "against": self.against,
        }

    @classmethod
    def from_dict(cls, d) -> Torque:
        d = _keys("a torque", d, ("on", "magnitude"), ("window", "against"))
        return cls(d["on"], d["magnitude"], d.get("window", "always"), d.get("against", "x"))


def _many(what, kind, v) -> tuple:
    if isinstance(v, (str, bytes, dict)) or not isinstance(v, (tuple, list)):
        raise InvalidParameter(f"{what} is a list of qropt.{kind.__name__}, got {v!r:.120}")
    out = []
    for item in v:
        if isinstance(item, dict):
            item = kind.from_dict(item)
        if not isinstance(item, kind):
            raise InvalidParameter(f"{what} is a list of qropt.{kind.__name__}, got an item {item!r:.80}")
        out.append(item)
    return tuple(out)


def _friction_pair(what, v) -> tuple:
    """(mu, radius) of one pin: a radius (m) with the common mu, or a pair (mu, radius)."""
    if isinstance(v, dict):
        v = _keys(what, v, ("mu", "radius"), ())
        v = (v["mu"], v["radius"])
    if isinstance(v, (tuple, list)):
        if len(v) != 2:
            raise InvalidParameter(f"{what} is a radius (m) or a pair (mu, radius), got {v!r:.80}")
        return (_real(f"{what}: mu", v[0], nonneg=True), _real(f"{what}: its radius (m)", v[1], positive=True))
    return None, _real(f"{what}: its radius (m)", v, positive=True)


@dataclass(frozen=True)
class PinFriction:
    """Coulomb friction at the pins: at a pin of radius r (m) with coefficient mu, a friction moment
    ``mu * r * |F|`` (F the pin's force) opposing the relative rotation of the two bodies it joins, equal and
    opposite on them. ``mu`` and ``radius`` hold for every pin (every revolute joint between two bodies, the ground
    pivots and the crank-pin block's pin included); ``joints``: joint name -> its own radius (m) with the common mu,
    or a pair (mu, radius) (a joint's mu = 0 takes that pin out). ``radius=None``: only the joints named have
    friction. Slots (a block or pin sliding in a slot, the yoke's slot) are not pins: their friction is not
    modelled (the ram's guide has its own, ``Loads.friction``); a joint named here that is not a pin is an error."""

    mu: float = 0.0
    radius: float | None = None
    joints: dict = field(default_factory=dict)

    def __post_init__(self):
        object.__setattr__(self, "mu", _real("pin friction: mu (a coefficient)", self.mu, nonneg=True))
        if self.radius is not None:
            object.__setattr__(self, "radius", _real("pin friction: the pins' radius (m)", self.radius, positive=True))
        if not isinstance(self.joints, dict):
            raise InvalidParameter(
                f"pin friction: joints is a dict of joint name -> radius or (mu, radius), got {self.joints!r:.120}"
            )
        joints = {}
        for k, v in self.joints.items():
            if not isinstance(k, str) or not k:
                raise InvalidParameter(f"pin friction: a pin is named by its joint (a string), got {k!r:.60}")
            mu, r = _friction_pair(f"pin friction at {k}", v)
            joints[k] = (self.mu if mu is None else mu, r)
        object.__setattr__(self, "joints", joints)
        if self.radius is None and not joints:
            raise InvalidParameter("pin friction needs a radius for every pin or the joints it acts at, got neither")

    def at(self, joint: str) -> tuple:
        """(mu, radius) at a pin; (0, 0) where it has no friction."""
        if joint in self.joints:
            return self.joints[joint]
        return (self.mu, self.radius) if self.radius is not None else (0.0, 0.0)

    @property
    def active(self) -> bool:
        """Whether some pin has a friction moment (mu r > 0)."""
        return (self.radius is not None and self.mu > 0) or any(mu > 0 for mu, _ in self.joints.values())

    def to_dict(self) -> dict:
        return {
            "mu": self.mu,
            **({} if self.radius is None else {"radius": self.radius}),
            **({"joints": {k: list(v) for k, v in self.joints.items()}} if self.joints else {}),
        }

    @classmethod
    def from_dict(cls, d) -> PinFriction:
        if isinstance(d, PinFriction):
            return d
        d = _keys("pin friction", d, ("mu",), ("radius", "joints"))
        return cls(d["mu"], d.get("radius"), dict(d.get("joints") or {}))


@dataclass(frozen=True)
class Loads:
    """What the mechanism works against. ``cutting_force`` (N) resists the ram's motion on the working (slow)
    stroke only: a constant, or a table ((x, F), ...) of force against the ram's position x (the mechanism's
    length unit), linear between points and constant beyond them; ``friction``: the slide's coefficient (the
    guide's friction force mu |N| against the ram's velocity); ``gravity`` (m/s^2): a number g along -y or a
    vector (gx, gy); ``follower_torque`` (N m): for a four-bar whose output is its follower, a torque resisting its
    working swing. ``forces`` and ``torques``: further loads (``Force``, ``Torque``); ``working``: "+x" or "-x",
    the way the output moves on the working stroke where the strokes take equal time (TR = 1)."""

    cutting_force: float | tuple = 0.0
    friction: float = 0.0
    gravity: float | tuple = 0.0
    follower_torque: float = 0.0
    forces: tuple = ()
    torques: tuple = ()
    working: str | None = None
    pin_friction: PinFriction | None = None

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
        g = self.gravity
        if isinstance(g, (tuple, list)):
            gx, gy = _pair("gravity (gx, gy) (m/s^2)", g)
            g = -gy if gx == 0 and gy <= 0 else (gx, gy)  # (0, -g) is the number g
        object.__setattr__(self, "gravity", g if isinstance(g, tuple) else _real("gravity (m/s^2)", g, nonneg=True))
        object.__setattr__(self, "follower_torque", _real("follower_torque (N m)", self.follower_torque, nonneg=True))
        object.__setattr__(self, "forces", _many("forces", Force, self.forces))
        object.__setattr__(self, "torques", _many("torques", Torque, self.torques))
        if self.working is not None and self.working not in WAYS:
            raise InvalidParameter(f"working is the working stroke's direction, '+x' or '-x', got {self.working!r:.60}")
        pf = self.pin_friction
        if pf is not None and not isinstance(pf, PinFriction):
            if not isinstance(pf, dict):
                raise InvalidParameter(f"pin_friction is a qropt.PinFriction, its dict or None, got {pf!r:.80}")
            object.__setattr__(self, "pin_friction", PinFriction.from_dict(pf))

    @property
    def gravity_vector(self) -> tuple:
        """(gx, gy) m/s^2."""
        g = self.gravity
        return g if isinstance(g, tuple) else (0.0, -g)

    @property
    def general(self) -> list:
        """The loads beyond the shorthands, named: every force and torque, and a gravity that is not along -y."""
        out = [str(f) for f in self.forces] + [str(t) for t in self.torques]
        if isinstance(self.gravity, tuple):
            out.append(f"gravity {self.gravity}")
        return out

    def by_stroke(self) -> list:
        """The loads that act on one stroke (they need the working stroke decided), named."""
        out = ["the cutting force"] if self.cutting_force else []
        out += ["the follower's torque"] if self.follower_torque else []
        return out + [str(v) for v in (*self.forces, *self.torques) if v.window.by_stroke]

    def require_plain(self, what: str) -> None:
        """UnsupportedLoad naming the first load beyond the shorthands, which ``what`` cannot apply yet."""
        from qropt.errors import UnsupportedLoad

        named = self.general + ([f"the named working stroke ({self.working})"] if self.working else [])
        if not named and self.pin_friction is not None:
            raise UnsupportedLoad(
                f"{what} cannot apply pin friction (Loads.pin_friction) yet: its friction moments depend on the joint "
                "forces, which it does not solve for exactly; inverse_dynamics, the cycle's extremes, the flywheel "
                "and the efficiency apply it"
            )
        if named:
            raise UnsupportedLoad(
                f"{what} cannot apply {named[0]} yet (it takes the cutting force, friction, gravity along -y and the "
                "follower's torque); inverse_dynamics, the flywheel and simulate apply every load"
            )

    @property
    def switching(self) -> bool:
        """Whether a cutting force or a follower's load torque acts: they switch on and off at the dead centres."""
        f = self.cutting_force
        return bool(self.follower_torque or (any(r[1] > 0 for r in f) if isinstance(f, tuple) else f))

    @property
    def jumps(self) -> bool:
        """Whether the joint forces may jump at the dead centres: a cutting force switching on or off there, the
        slide's friction turning with the ram's velocity, or a force or torque (a window's edge, a force against
        a velocity that turns)."""
        return self.switching or bool(self.friction) or bool(self.forces or self.torques)

    def force_at(self, x) -> np.ndarray:
        """The cutting force's magnitude (N) at ram positions x (the mechanism's unit)."""
        return level(self.cutting_force, x)

    def to_dict(self) -> dict:
        f = self.cutting_force
        return {
            "cutting_force": [list(r) for r in f] if isinstance(f, tuple) else f,
            "friction": self.friction,
            "gravity": list(self.gravity) if isinstance(self.gravity, tuple) else self.gravity,
            "follower_torque": self.follower_torque,
            **({"forces": [v.to_dict() for v in self.forces]} if self.forces else {}),
            **({"torques": [v.to_dict() for v in self.torques]} if self.torques else {}),
            **({"working": self.working} if self.working is not None else {}),
            **({"pin_friction": self.pin_friction.to_dict()} if self.pin_friction is not None else {}),
        }

    @classmethod
    def from_dict(cls, d) -> Loads:
        keys = {
            "cutting_force",
            "friction",
            "gravity",
            "follower_torque",
            "forces",
            "torques",
            "working",
            "pin_friction",
        }
        if not isinstance(d, dict) or set(d) - keys:
            raise InvalidParameter(f"loads take {sorted(keys)}, got {d!r}")
        return cls(**d)


__all__ = [
    "BodyMass",
    "Counterweight",
    "Masses",
    "Loads",
    "PinFriction",
    "Force",
    "Torque",
    "Window",
    "STEEL",
    "slender_bar",
    "union",
    "level",
]
