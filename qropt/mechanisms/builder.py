"""Planar one-degree-of-freedom linkages declared from Assur groups: a type in a few lines instead of a loop.

A ``Linkage`` is built from a frame, a crank and dyads, each named after the joint it places (the geometry contract,
``shared/CONVENTIONS.md``: x to the right, y up, theta2 counter-clockwise from +x; a link angle is the direction
from its first-named joint to its second, e.g. theta3 = A->B). Its ``loop(xp, theta2, p)`` is the same closed-form
loop a type would write by hand, built from the closures of ``qropt.kinematics.closures`` only, so it runs on numpy
arrays, Taylor jets and CasADi symbols alike (no branching on values). It is generated once, on first use, as
one straight-line Python function (every expression spelled out, nothing interpreted per evaluation), so it costs
what the hand-written loop did. A type then says::

    L = Linkage()
    L.ground("O2", (0, 0))
    L.crank("A", about="O2", length="r2")                       # A = r2 (cos theta2, sin theta2)
    L.rrr("B", ("A", "r3"), ("O4", "r4"), sign="sigma", around=math.pi)
    L.ground("O4", ("r1", 0))                                   # declared after B: the points keep this order
    L.on_ray("C", "O4", "B", "r5")                              # C on the follower, along O4->B
    L.rrp("D", ("C", "r6"), line_y="h", sign="sigma_slider")    # the rod CD and the ram D on y = h
    L.output("D")

    class MySlider(Mechanism):
        PARAMS = {...}
        loop = staticmethod(L.loop)
        BODIES, GROUND, OUTPUT_JOINT = L.bodies(), L.ground_joints(), L.output_joint()

Numbers and parameters. A coordinate, length or slide-line height is a number, a parameter name, or a short linear
expression of them (``"-r1 + h"``, ``"2*r1 - e"``), evaluated left to right exactly as written (``-r1 + h`` is
``-p["r1"] + p["h"]``); or a callable ``f(xp, p)``. A branch sign is a parameter name (``"sigma"``) or +1 / -1.
Each declaration is checked as it is made (LinkageError): numbers finite, a literal link length (a crank's, a
dyad's) positive, a dyad's two centres distinct, its bodies a pair; and when a type takes the loop, every name
the linkage reads is one of its PARAMS and every sign one of its BRANCHES.

Points are emitted in declaration order and may refer to points declared later (the loop is evaluated in dependency
order), so a type reproduces a hand-written loop's point order. Angles, transmission joints and margins are
emitted in the order the elements that define them were declared.

The elements (each: the closure it is, its branch sign, its assembly margin, its transmission rule, the angles it
defines and the bodies it makes):

- ``ground(name, (x, y))``: a frame pivot. No sign, margin or transmission.
- ``crank(name, about, length)``: the input link, the pin at ``length`` from the ground pivot along theta2;
  angle ``theta2`` (the crank angle itself); body ``crank`` (pivot, pin), a bar.
- ``rrr(name, (P, a), (Q, b), sign)``: RRR, a joint X on two circles (``circle_circle``). Two solutions: the branch
  sign by the contract, ``sigma = sign((P - Q) x (X - Q))``. Margin ``1 - c^2`` (c the cosine of the angle at Q),
  >= 0 where the circles meet; named ``"four-bar closure at X"`` when P is a crank's pin and Q a ground pivot (the
  four-bar of the contract), else ``"closure at X"``. Transmission at X by the contract's four-bar rule:
  ``joint_lines(P, Q, X)``, the coupler X->P (P's side drives: name it first) against the follower X->Q (exact for a
  ground Q, whose X moves normal to QX; with a moving Q it is the classical angle between the dyad's links).
  Angles: P->X and Q->X, named theta<k> after lengths named r<k> (theta3 = A->B, theta4 = O4->B); Q->X is the
  closure's continuous angle (``around`` as in ``circle_circle``: ``math.pi`` keeps a follower that rocks about
  -x continuous, as the four-bar does). Bodies: ``coupler`` (P, X) and ``follower`` (Q, X), bars.
- ``rrp(name, (P, r), line_y, sign)``: RRP, a rod of length r from pin P to the slider X on the slide line
  y = line_y, sliding along +x (``rod_to_line``). Two solutions: ``sign = +1`` puts X on the +x side of P (the
  contract's ``sigma_slider``). Margin ``(r^2 - (line_y - y_P)^2) / r^2``, named ``"rod PX reaching the slide
  line"``. Transmission at X: ``rod_lines(P, X)``, the rod against the slide line's normal. Angle P->X (theta6 for
  a rod r6). Bodies: ``rod`` (P, X), a bar, and ``ram`` (X,).
- ``rpr(pin, pivot, angle)``: RPR, a crank-pin block in a slotted link that turns about a ground pivot and passes
  through the pin (``pin_in_slot``): it defines the link's angle pivot->pin (``theta4``). One solution, no margin
  (it assembles wherever the pin is off the pivot). Transmission at the pin: ``RIGHT_ANGLE`` (a block in a slot
  carries force normal to the slot, along the pin's velocity: 90 degrees). Bodies: ``block`` (pin, pivot) and
  ``lever`` (pivot, pin), a slot-lever.
- ``rpp(pin)``: RPP, a yoke: the pin slides in a slot normal to the slide line, so the ram follows the pin's x
  (``output(pin)``). No new point, sign or margin; transmission at the pin: ``RIGHT_ANGLE``; body ``yoke`` (pin,).
- ``slot_line(name, (pivot, through), line_y)``: a pin on two lines (``slot_to_line``): the ram's pin rides in the
  slotted lever pivot->through and on the slide line y = line_y, where the lever's line crosses it. One solution;
  no margin by default (the lines cross unless parallel; ``margin="..."`` records t >= 0, the pin on the ray's side
  of the pivot). Transmission at the pin: ``slot_line_lines(pivot, through)``, the lever against the slide line.
  The pin joins the lever's body; body ``ram`` (name,).
- ``on_ray(name, origin, through, length)``: a point fixed on the body that carries origin and through, at
  ``length`` along the ray origin->through (``on_ray``; the ray's angle is the one the dyad that made it defined,
  e.g. the follower's theta4). ``coupler_point(name, origin, through, length, angle)``: at ``length`` and
  ``angle`` (counter-clockwise) from that ray, ``P = A + r5 (cos(theta3 + beta), sin(theta3 + beta))``; it makes
  the body a plate. Neither has a sign, margin or transmission.
- ``output(name)``: the output: a point's x (the ram on its +x slide line) or an angle (a follower's theta4).

``bodies()`` gives every moving body in declaration order (``Body``; a point fixed on a body joins it),
``ground_joints()`` the frame pivots, ``output_joint()`` the output point (None for an angle) and ``parameters()``
the parameter names the linkage reads, in first-use order.

Limits of this first step: one crank and one output per linkage; no optional dyads (a type whose structure depends
on which parameters are given, as the crank-shaper's yoke or rod, declares one linkage per variant and picks by the
keys of p); the RRR's transmission rule assumes its second centre is a ground pivot (see above).
"""

from __future__ import annotations

import re
from typing import NamedTuple

from qropt.errors import InvalidParameter
from qropt.kinematics import closures as cl
from qropt.kinematics.closures import Loop
from qropt.mechanisms.values import Body
from qropt.validate import branch_sign, number

__all__ = ["Linkage", "LinkageError", "Connection"]


class Connection(NamedTuple):
    """One joint between two bodies (see ``Linkage.connections``)."""

    joint: str
    giver: str
    receiver: str
    kind: str  # 'pin', 'slot' or 'guide'
    line: tuple | None = None  # a slot's line (two joints); None: the yoke's slot, normal to the slide line


class LinkageError(InvalidParameter):
    """A linkage declaration that cannot be built: a name used twice, a point never placed, a cycle of references,
    an expression that does not parse, or a point fixed on a body that no element made."""


# ---- numbers, parameters and linear expressions ------------------------------------------------------------------
_TERM = re.compile(
    r"\s*([+-])?\s*(?:((?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*(?:\*\s*([A-Za-z_]\w*))?|([A-Za-z_]\w*))\s*"
)


_NOT_NAMES = ("nan", "inf", "infinity")  # read as numbers by float(), never parameter names here


class _Scalar:
    """A number, a parameter, a linear expression of parameters (left to right) or a callable f(xp, p).
    ``positive``: a literal (or an expression of literals only) must be > 0 (a link's length)."""

    def __init__(self, spec, what: str, positive: bool = False):
        self.spec, self.names, self.zero, self.constant = spec, (), False, None
        if callable(spec):
            self.f = lambda xp, p: spec(xp, p)
            self.code = None  # the compiled loop calls it: f(xp, p)
            return
        if isinstance(spec, bool) or not isinstance(spec, (int, float, str)):
            raise LinkageError(f"{what}: a number, a parameter name, a linear expression or f(xp, p); got {spec!r:.80}")
        if not isinstance(spec, str):
            v = self.constant = number(what, spec, error=LinkageError)
            if positive and v <= 0:
                raise LinkageError(f"{what} must be positive, got {v:g}")
            self.zero = v == 0.0
            self.f = lambda xp, p: v
            self.code = repr(v)
            return
        terms, pos = [], 0
        while pos < len(spec):
            m = _TERM.match(spec, pos)
            if not m or m.end() == pos or (terms and not m.group(1)):
                raise LinkageError(f"{what}: cannot read {spec!r:.80} (terms like 'r1', '-r1 + h', '2*e')")
            sign, num, name = m.group(1) or "+", m.group(2), m.group(3) or m.group(4)
            if name is not None and name.lower() in _NOT_NAMES:
                raise LinkageError(f"{what}: {name!r} in {spec!r:.80} is not a parameter name (numbers are finite)")
            coef = None if num is None else number(f"{what}: the number {num}", float(num), error=LinkageError)
            terms.append((sign, coef, name))
            pos = m.end()
        if not terms:
            raise LinkageError(f"{what}: empty expression")
        self.names = tuple(dict.fromkeys(n for _, _, n in terms if n is not None))
        self.zero = all(n is None and c == 0.0 for _, c, n in terms)

        def f(xp, p):
            out = None
            for k, (sign, coef, name) in enumerate(terms):
                if name is None:
                    v = -coef if sign == "-" and k == 0 else coef
                elif coef is None:
                    v = -p[name] if sign == "-" and k == 0 else p[name]
                else:
                    v = (-coef if sign == "-" and k == 0 else coef) * p[name]
                out = v if k == 0 else (out - v if sign == "-" else out + v)
            return out

        if not self.names:
            self.constant = number(f"{what} ({spec!r:.80})", f(None, {}), error=LinkageError)
            if positive and self.constant <= 0:
                raise LinkageError(f"{what} must be positive, got {spec!r:.80} = {self.constant:g}")
        self.f = f
        code = ""
        for k, (sign, coef, name) in enumerate(terms):  # the same operations, in the same order, as f
            neg = sign == "-" and k == 0
            if name is None:
                v = repr(-coef if neg else coef)
            elif coef is None:
                v = f"(-p[{name!r}])" if neg else f"p[{name!r}]"
            else:
                v = f"({(-coef if neg else coef)!r} * p[{name!r}])"
            code = v if k == 0 else f"({code} {'-' if sign == '-' else '+'} {v})"
        self.code = code

    def __call__(self, xp, p):
        return self.f(xp, p)


def _sign(spec, what: str) -> _Scalar:
    """A branch sign: a parameter name (the type lists it in BRANCHES) or the literal +1 or -1."""
    if isinstance(spec, str) and re.fullmatch(r"[A-Za-z_]\w*", spec) and spec.lower() not in _NOT_NAMES:
        return _Scalar(spec, what)
    if isinstance(spec, bool) or not isinstance(spec, (int, float)):
        raise LinkageError(f"{what}: a branch sign is a parameter name (e.g. 'sigma') or +1 or -1, got {spec!r:.80}")
    return _Scalar(branch_sign(f"{what}: a branch sign", spec, error=LinkageError), what)


def _names(v, n: int, what: str) -> tuple:
    """n distinct non-empty names (a dyad's bodies or angles: None skips an angle)."""
    if not isinstance(v, (tuple, list)) or len(v) != n:
        raise LinkageError(f"{what}: {n} names, got {v!r:.80}")
    return tuple(v)


def _theta(length) -> str | None:
    """theta<k> for a length named r<k> (the hand-written loops' names), else None."""
    return f"theta{length[1:]}" if isinstance(length, str) and re.fullmatch(r"r\d+", length) else None


# ---- elements -----------------------------------------------------------------------------------------------------
class _Element:
    kind = ""
    point: str | None = None  # the point it places (None: rpr, rpp, output)
    needs: tuple = ()  # points it reads

    def angle_names(self) -> tuple:
        return ()

    def joints(self) -> tuple:
        """Transmission joints (in order)."""
        return ()

    def margin_names(self) -> tuple:
        return ()


class _Ground(_Element):
    kind = "ground"

    def __init__(self, name, xy):
        if not isinstance(xy, (tuple, list)) or len(xy) != 2:
            raise LinkageError(f"ground {name!r}: coordinates are a pair (x, y), got {xy!r}")
        self.point, self.xy = name, (_Scalar(xy[0], f"ground {name} x"), _Scalar(xy[1], f"ground {name} y"))


class _Crank(_Element):
    kind = "crank"

    def __init__(self, name, about, length, angle, body):
        self.point, self.about, self.needs = name, about, (about,)
        self.length, self.angle, self.body = _Scalar(length, f"crank {name} length", positive=True), angle, body
        self.pivot_zero = (False, False)  # set by the plan (a ground pivot at a literal 0 adds nothing)

    def angle_names(self):
        return (self.angle,) if self.angle else ()


class _RRR(_Element):
    kind = "rrr"

    def __init__(self, name, first, second, sign, around, angles, margin, bodies):
        (self.p_, a), (self.q_, b) = _pair(first, f"rrr {name}"), _pair(second, f"rrr {name}")
        if self.p_ == self.q_:
            raise LinkageError(f"rrr {name!r}: both circles are about {self.p_!r}; an RRR needs two centres")
        self.point, self.needs = name, (self.p_, self.q_)
        self.a = _Scalar(a, f"rrr {name} first length", positive=True)
        self.b = _Scalar(b, f"rrr {name} second length", positive=True)
        self.sign = _sign(sign, f"rrr {name} sign")
        self.around = number(f"rrr {name} around (rad)", around, error=LinkageError)
        self.angles = (_theta(a), _theta(b)) if angles == "default" else _names(angles, 2, f"rrr {name!r} angles")
        self.margin = self.margin_given = margin  # the default name is set by the plan
        self.bodies = _names(bodies, 2, f"rrr {name!r} bodies (coupler, follower)")

    def angle_names(self):
        return tuple(a for a in self.angles if a)

    def joints(self):
        return (self.point,)

    def margin_names(self):
        return (self.margin,)


class _RRP(_Element):
    kind = "rrp"

    def __init__(self, name, rod, line_y, sign, angle, margin, bodies):
        self.pin, r = _pair(rod, f"rrp {name}")
        self.point, self.needs = name, (self.pin,)
        self.r = _Scalar(r, f"rrp {name} rod length", positive=True)
        self.h = _Scalar(line_y, f"rrp {name} line_y")
        self.sign = _sign(sign, f"rrp {name} sign")
        self.angle = _theta(r) if angle == "default" else angle
        self.margin = margin or f"rod {self.pin}{name} reaching the slide line"
        self.bodies = _names(bodies, 2, f"rrp {name!r} bodies (rod, ram)")

    def angle_names(self):
        return (self.angle,) if self.angle else ()

    def joints(self):
        return (self.point,)

    def margin_names(self):
        return (self.margin,)


class _RPR(_Element):
    kind = "rpr"

    def __init__(self, pin, pivot, angle, bodies):
        if pin == pivot:
            raise LinkageError(f"rpr {pin!r}: the slot turns about its own pin; the pivot is another joint")
        self.pin, self.pivot, self.needs = pin, pivot, (pin, pivot)
        self.angle, self.bodies = angle, _names(bodies, 2, f"rpr {pin!r} bodies (block, lever)")

    def angle_names(self):
        return (self.angle,) if self.angle else ()

    def joints(self):
        return (self.pin,)


class _RPP(_Element):
    kind = "rpp"

    def __init__(self, pin, body):
        self.pin, self.needs, self.body = pin, (pin,), body

    def joints(self):
        return (self.pin,)


class _SlotLine(_Element):
    kind = "slot_line"

    def __init__(self, name, lever, line_y, margin, body):
        if not isinstance(lever, (tuple, list)) or len(lever) != 2 or not all(isinstance(j, str) for j in lever):
            raise LinkageError(f"slot_line {name!r}: the lever is (pivot, through), got {lever!r}")
        self.pivot, self.through = lever
        if self.pivot == self.through:
            raise LinkageError(f"slot_line {name!r}: the lever's line runs through two joints, got {lever!r}")
        self.point, self.needs = name, (self.pivot, self.through)
        self.h, self.margin, self.body = _Scalar(line_y, f"slot_line {name} line_y"), margin, body

    def joints(self):
        return (self.point,)

    def margin_names(self):
        return (self.margin,) if self.margin else ()


class _OnBody(_Element):
    kind = "on_ray"

    def __init__(self, name, origin, through, length, angle):
        if origin == through:
            raise LinkageError(f"{name!r}: a ray runs from one joint through another, got {origin!r} twice")
        self.point, self.origin, self.through, self.needs = name, origin, through, (origin, through)
        self.length = _Scalar(length, f"{name} length")
        self.offset = None if angle is None else _Scalar(angle, f"{name} angle")
        if self.offset is not None:
            self.kind = "coupler_point"


def _same_place(a: tuple, b: tuple) -> bool:
    """Two ground pivots declared at one point: the same numbers or the same expressions."""

    def key(c):
        return c.spec if c.constant is None else c.constant

    return not any(callable(c.spec) for c in (*a, *b)) and [key(c) for c in a] == [key(c) for c in b]


def _pair(v, what):
    if not isinstance(v, (tuple, list)) or len(v) != 2 or not isinstance(v[0], str):
        raise LinkageError(f"{what}: a (joint, length) pair, got {v!r}")
    return v[0], v[1]


# ---- the linkage --------------------------------------------------------------------------------------------------
class Linkage:
    """A planar one-degree-of-freedom linkage declared element by element (see the module docstring)."""

    def __init__(self):
        self._elements: list[_Element] = []
        self._output: str | None = None
        self._plan: tuple | None = None

    # -- declarations
    def _add(self, e: _Element) -> Linkage:
        taken = {x.point for x in self._elements if x.point}
        if e.point is not None:
            if not isinstance(e.point, str) or not e.point:
                raise LinkageError(f"a joint is named by a non-empty string, got {e.point!r}")
            if e.point in taken:
                raise LinkageError(f"joint {e.point!r} is placed twice")
        angles = [a for x in self._elements for a in x.angle_names()]
        for a in e.angle_names():
            if a in angles:
                raise LinkageError(f"angle {a!r} is defined twice")
        joints = [j for x in self._elements for j in x.joints()]
        for j in e.joints():
            if j in joints:
                raise LinkageError(f"joint {j!r} has two transmission rules")
        margins = [m for x in self._elements for m in x.margin_names() if m]
        for m in e.margin_names():
            if m and m in margins:
                raise LinkageError(f"margin {m!r} is recorded twice")
        self._elements.append(e)
        self._plan = None
        return self

    def elements(self) -> tuple:
        """The declared elements in the order they are evaluated (each after the points it reads): what the
        relative-motion analysis walks (``qropt.mechanisms.relative_motion``)."""
        order = self._build()[0]
        return tuple(self._elements[i] for i in order)

    def ground(self, name: str, xy) -> Linkage:
        """A frame pivot at (x, y): numbers, parameter names or linear expressions ('-r1 + h')."""
        return self._add(_Ground(name, xy))

    def crank(self, name: str, about: str, length, angle: str = "theta2", body: str = "crank") -> Linkage:
        """The input crank: pin ``name`` at ``length`` from the ground pivot ``about`` along theta2."""
        if any(e.kind == "crank" for e in self._elements):
            raise LinkageError("a one-degree-of-freedom linkage has one crank")
        return self._add(_Crank(name, about, length, angle, body))

    def rrr(
        self,
        name: str,
        first,
        second,
        sign="sigma",
        around: float = 0.0,
        angles="default",
        margin: str | None = None,
        bodies=("coupler", "follower"),
    ) -> Linkage:
        """RRR: joint ``name`` at distance a from P and b from Q, ``first = (P, a)`` (the driving side),
        ``second = (Q, b)``, on the branch ``sign`` = sign((P - Q) x (X - Q)). ``angles``: names of P->X and Q->X
        (None to skip; default theta<k> for lengths r<k>); ``margin``: its name (default: see the module)."""
        return self._add(_RRR(name, first, second, sign, around, angles, margin, bodies))

    def rrp(
        self,
        name: str,
        rod,
        line_y,
        sign="sigma_slider",
        angle="default",
        margin: str | None = None,
        bodies=("rod", "ram"),
    ) -> Linkage:
        """RRP: slider ``name`` on the slide line y = ``line_y`` (along +x) driven by the rod ``rod = (P, r)``;
        ``sign`` +1 puts it on the +x side of P. ``angle``: the rod's angle P->X (default theta<k> for r<k>)."""
        return self._add(_RRP(name, rod, line_y, sign, angle, margin, bodies))

    def rpr(self, pin: str, pivot: str, angle: str = "theta4", bodies=("block", "lever")) -> Linkage:
        """RPR: the block on ``pin`` in a slotted lever turning about the ground ``pivot``; defines the lever's
        angle pivot->pin (``angle``)."""
        return self._add(_RPR(pin, pivot, angle, bodies))

    def rpp(self, pin: str, body: str = "yoke") -> Linkage:
        """RPP: a yoke, the pin in a slot normal to the slide line; the ram follows the pin's x (``output(pin)``)."""
        return self._add(_RPP(pin, body))

    def slot_line(self, name: str, lever, line_y, margin: str | None = None, body: str = "ram") -> Linkage:
        """A pin on two lines: ``name`` rides in the slotted lever ``lever = (pivot, through)`` and on the slide line
        y = ``line_y``. ``margin``: record t >= 0 (the pin on the pivot's ray) under this name (default none)."""
        return self._add(_SlotLine(name, lever, line_y, margin, body))

    def on_ray(self, name: str, origin: str, through: str, length) -> Linkage:
        """A point fixed on the body carrying ``origin`` and ``through``, at ``length`` along origin->through."""
        return self._add(_OnBody(name, origin, through, length, None))

    def coupler_point(self, name: str, origin: str, through: str, length, angle) -> Linkage:
        """A point fixed on the body carrying ``origin`` and ``through``, at ``length`` from origin and ``angle``
        (rad, counter-clockwise) from the ray origin->through: P = A + r5 (cos(theta3 + beta), sin(theta3 + beta))."""
        return self._add(_OnBody(name, origin, through, length, angle))

    def output(self, name: str) -> Linkage:
        """The output: a point's x (a ram on a +x slide line) or a declared angle (a follower's theta4)."""
        if not isinstance(name, str):
            raise LinkageError(f"output: a joint or angle name, got {name!r}")
        self._output, self._plan = name, None
        return self

    # -- the plan: evaluation order and checks
    def _build(self) -> tuple:
        if self._plan is not None:
            return self._plan
        els = self._elements
        placed = {e.point: i for i, e in enumerate(els) if e.point}
        for e in els:
            for j in e.needs:
                if j not in placed:
                    raise LinkageError(f"{e.kind} {e.point or getattr(e, 'pin', '')!r} reads joint {j!r}, never placed")
        if not any(e.kind == "crank" for e in els):
            raise LinkageError("a linkage needs a crank")
        angles = [a for e in els for a in e.angle_names()]
        if self._output is None:
            raise LinkageError("no output: call output(joint or angle)")
        if self._output not in placed and self._output not in angles:
            raise LinkageError(f"output {self._output!r} is neither a placed joint nor a declared angle")
        for e in els:
            if e.kind == "crank":
                pivot = els[placed[e.about]]
                if pivot.kind != "ground":
                    raise LinkageError(f"crank {e.point!r} turns about {e.about!r}, which is not a ground pivot")
                e.pivot_zero = (pivot.xy[0].zero, pivot.xy[1].zero)
        order, done, visiting = [], set(), set()

        def visit(i):
            if i in done:
                return
            if i in visiting:
                raise LinkageError(f"joint {els[i].point!r} depends on itself")
            visiting.add(i)
            for j in els[i].needs:
                visit(placed[j])
            visiting.discard(i)
            done.add(i)
            order.append(i)

        for i in range(len(els)):
            visit(i)
        cranks = {e.point for e in els if e.kind == "crank"}
        grounds = {e.point for e in els if e.kind == "ground"}
        for e in els:
            if e.kind == "rrr":
                p_, q_ = els[placed[e.p_]], els[placed[e.q_]]
                if p_.kind == q_.kind == "ground" and _same_place(p_.xy, q_.xy):
                    raise LinkageError(f"rrr {e.point!r}: its centres {e.p_!r} and {e.q_!r} are one point")
                four = e.p_ in cranks and e.q_ in grounds
                e.margin = e.margin_given or (f"four-bar closure at {e.point}" if four else f"closure at {e.point}")
        self._plan = (tuple(order), self._bodies(order), self._compile(order))
        return self._plan

    def _compile(self, order):
        """The loop as one straight-line Python function, generated once from the plan: the closures' calls in
        dependency order with every expression spelled out (no interpretation per evaluation)."""
        els, lines, ns = self._elements, [], {"cl": cl, "Loop": Loop}
        var = {e.point: f"_p{i}" for i, e in enumerate(els) if e.point}
        rays: dict = {}  # (origin, through) -> variable name, or ("lazy", code) computed on first use
        angles: dict = {}
        trans: dict = {}  # element index -> [(joint, code)]
        margins: dict = {}  # element index -> [(name, variable)]
        tmp = iter(range(1 << 30))

        def new():
            return f"_t{next(tmp)}"

        def scalar(sc):
            if sc.code is not None:
                return sc.code
            name = f"_f{next(tmp)}"
            ns[name] = sc.f
            return f"{name}(xp, p)"

        def ray(o, t):
            v = rays.get((o, t))
            if v is None:
                v = new()
                lines.append(f"{v} = cl.pin_in_slot(xp, {var[o]}, {var[t]})")
            elif isinstance(v, tuple):
                code = v[1]() if callable(v[1]) else v[1]
                v = new()
                lines.append(f"{v} = {code}")
            rays[(o, t)] = v
            return v

        def atan2(frm, to):
            a, b = var[frm], var[to]
            return ("lazy", f"xp.atan2({b}[1] - {a}[1], {b}[0] - {a}[0])")

        for i in order:
            e, X = els[i], var.get(els[i].point)
            if e.kind == "ground":
                lines.append(f"{X} = ({scalar(e.xy[0])}, {scalar(e.xy[1])})")
            elif e.kind == "crank":
                r, o = new(), var[e.about]
                lines.append(f"{r} = {scalar(e.length)}")
                x = f"{r} * xp.cos(theta2)" if e.pivot_zero[0] else f"{o}[0] + {r} * xp.cos(theta2)"
                y = f"{r} * xp.sin(theta2)" if e.pivot_zero[1] else f"{o}[1] + {r} * xp.sin(theta2)"
                lines.append(f"{X} = ({x}, {y})")
                rays[(e.about, e.point)] = "theta2"
                if e.angle:
                    angles[e.angle] = "theta2"
            elif e.kind == "rrr":
                P, Q, aq, m = var[e.p_], var[e.q_], new(), new()
                args = f"{scalar(e.a)}, {Q}, {scalar(e.b)}, {scalar(e.sign)}, {e.around!r}"
                lines.append(f"{X}, {aq}, {m} = cl.circle_circle(xp, {P}, {args})")
                rays[(e.q_, e.point)] = aq
                rays[(e.p_, e.point)] = atan2(e.p_, e.point)
                for name, r in zip(e.angles, ((e.p_, e.point), (e.q_, e.point)), strict=True):
                    if name:
                        angles[name] = ray(*r)
                trans[i] = [(e.point, f"cl.joint_lines({P}, {Q}, {X})")]
                margins[i] = [(e.margin, m)]
            elif e.kind == "rrp":
                c, m = var[e.pin], new()
                args = f"{scalar(e.r)}, {scalar(e.h)}, {scalar(e.sign)}"
                lines.append(f"{X}, {m} = cl.rod_to_line(xp, {c}, {args})")
                rays[(e.pin, e.point)] = atan2(e.pin, e.point)
                if e.angle:
                    angles[e.angle] = ray(e.pin, e.point)
                trans[i] = [(e.point, f"cl.rod_lines({c}, {X})")]
                margins[i] = [(e.margin, m)]
            elif e.kind == "rpr":
                t = new()
                lines.append(f"{t} = cl.pin_in_slot(xp, {var[e.pivot]}, {var[e.pin]})")
                rays[(e.pivot, e.pin)] = t
                if e.angle:
                    angles[e.angle] = t
                trans[i] = [(e.pin, "cl.RIGHT_ANGLE")]
            elif e.kind == "rpp":
                trans[i] = [(e.pin, "cl.RIGHT_ANGLE")]
            elif e.kind == "slot_line":
                o, a, t = var[e.pivot], var[e.through], new()
                lines.append(f"{X}, {t} = cl.slot_to_line(xp, {o}, {a}, {scalar(e.h)})")
                rays[(e.pivot, e.point)] = ("lazy", lambda e=e: ray(e.pivot, e.through))
                trans[i] = [(e.point, f"cl.slot_line_lines({o}, {a})")]
                if e.margin:
                    margins[i] = [(e.margin, t)]
            else:  # on_ray, coupler_point
                phi = ray(e.origin, e.through)
                if e.offset is not None:
                    v = new()
                    lines.append(f"{v} = {phi} + {scalar(e.offset)}")
                    phi = v
                lines.append(f"{X} = cl.on_ray(xp, {var[e.origin]}, {phi}, {scalar(e.length)})")
                rays[(e.origin, e.point)] = phi
        out = self._output
        x = f"{var[out]}[0]" if out in var else angles[out]
        n = range(len(els))
        points = ", ".join(f"{e.point!r}: {var[e.point]}" for e in els if e.point)
        angs = ", ".join(f"{a!r}: {angles[a]}" for e in els for a in e.angle_names())
        tr = ", ".join(f"{j!r}: {c}" for i in n for j, c in trans.get(i, ()))
        mg = ", ".join(f"({k!r}, {v})" for i in n for k, v in margins.get(i, ()))
        body = "\n    ".join([*lines, f"return Loop({{{points}}}, {{{angs}}}, {x}, {{{tr}}}, [{mg}])"])
        src = f"def loop(xp, theta2, p):\n    {body}\n"
        exec(compile(src, f"<linkage loop {id(self):#x}>", "exec"), ns)  # noqa: S102 - our own generated source
        fn = ns["loop"]
        fn.source = src
        return fn

    def _bodies(self, order) -> tuple:
        els = self._elements
        bodies: list = []  # [declaration index, sub-index, name, joints, kind]

        def carrier(a, b, who):
            for body in bodies:
                if body[4] in ("bar", "plate", "slot-lever") and a in body[3] and b in body[3]:
                    return body
            raise LinkageError(f"{who}: no link carries both {a!r} and {b!r}")

        for i in order:
            e = els[i]
            if e.kind == "crank":
                bodies.append([i, 0, e.body, [e.about, e.point], "bar"])
            elif e.kind == "rrr":
                bodies.append([i, 0, e.bodies[0], [e.p_, e.point], "bar"])
                bodies.append([i, 1, e.bodies[1], [e.q_, e.point], "bar"])
            elif e.kind == "rrp":
                bodies.append([i, 0, e.bodies[0], [e.pin, e.point], "bar"])
                bodies.append([i, 1, e.bodies[1], [e.point], "ram"])
            elif e.kind == "rpr":
                bodies.append([i, 0, e.bodies[0], [e.pin, e.pivot], "block"])
                bodies.append([i, 1, e.bodies[1], [e.pivot, e.pin], "slot-lever"])
            elif e.kind == "rpp":
                bodies.append([i, 0, e.body, [e.pin], "yoke"])
            elif e.kind == "slot_line":
                carrier(e.pivot, e.through, f"slot_line {e.point!r}")[3].append(e.point)
                bodies.append([i, 0, e.body, [e.point], "ram"])
            elif e.kind in ("on_ray", "coupler_point"):
                body = carrier(e.origin, e.through, f"{e.kind} {e.point!r}")
                body[3].append(e.point)
                if e.kind == "coupler_point" and body[4] == "bar":
                    body[4] = "plate"
        bodies.sort(key=lambda b: (b[0], b[1]))
        names = [b[2] for b in bodies]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise LinkageError(f"body names {dup} are used twice: name the dyads' bodies (bodies=...)")
        return tuple(Body(name, tuple(joints), kind) for _, _, name, joints, kind in bodies)

    def check(self, params, branches=()) -> None:
        """LinkageError unless every parameter the linkage reads is one of ``params`` and every branch sign it names
        is one of ``branches`` (a type's PARAMS and BRANCHES: ``Mechanism`` checks its own linkage when defined),
        and the declaration builds (every joint placed, no cycle, no degenerate dyad)."""
        self._build()
        missing = [n for n in self.parameters() if n not in params]
        if missing:
            raise LinkageError(
                f"the linkage reads {missing}, which the type does not take: its PARAMS are {list(params)}"
            )
        for e in self._elements:
            sign = getattr(e, "sign", None)
            if sign is not None and sign.names and sign.names[0] not in branches:
                raise LinkageError(
                    f"{e.kind} {e.point!r}: its sign {sign.names[0]!r} is not a branch sign of the type "
                    f"(BRANCHES: {list(branches)}); a branch sign is +1 or -1"
                )

    # -- what a type reads
    def loop(self, xp, theta2, p) -> Loop:
        """The closed-form loop at crank angle theta2 with parameters p in the math namespace xp (a type's
        ``loop = staticmethod(L.loop)``)."""
        return (self._plan or self._build())[2](xp, theta2, p)

    def bodies(self) -> tuple[Body, ...]:
        """Every moving body (``Body``), in the order the elements that make them were declared."""
        return self._build()[1]

    def connections(self) -> tuple[Connection, ...]:
        """How the bodies hold each other (what the force analysis reads), in declaration order: a 'pin' (a
        revolute joint: a force of any direction), a 'slot' (a pin or block sliding in a slot: a force normal to
        the slot, the line ``line`` = (a, b) of joints, or normal to the slide line's normal for a yoke, where
        ``line`` is None) and a 'guide' (the ram on its slide line: a force normal to the line, and a moment for
        a yoke-ram). ``giver`` is the body the motion comes from ('ground' for the frame), ``receiver`` the one it
        drives."""
        order, bodies = self._build()[:2]
        grounds = set(self.ground_joints())
        made: list = []  # bodies made so far, in declaration order

        def carrier(j):
            if j in grounds:
                return "ground"
            for b in made:
                if j in b.joints and b.kind not in ("ram", "yoke", "block"):
                    return b.name
            raise LinkageError(f"no body carries joint {j!r}")

        by_name = {b.name: b for b in bodies}
        out = []
        for i in order:
            e = self._elements[i]
            if e.kind == "crank":
                out.append(Connection(e.about, carrier(e.about), e.body, "pin"))
                made.append(by_name[e.body])
            elif e.kind == "rrr":
                coupler, follower = e.bodies
                out += [
                    Connection(e.p_, carrier(e.p_), coupler, "pin"),
                    Connection(e.q_, carrier(e.q_), follower, "pin"),
                    Connection(e.point, coupler, follower, "pin"),
                ]
                made += [by_name[coupler], by_name[follower]]
            elif e.kind == "rrp":
                rod, ram = e.bodies
                out += [
                    Connection(e.pin, carrier(e.pin), rod, "pin"),
                    Connection(e.point, rod, ram, "pin"),
                    Connection(e.point, "ground", ram, "guide"),
                ]
                made += [by_name[rod], by_name[ram]]
            elif e.kind == "rpr":
                block, lever = e.bodies
                out += [
                    Connection(e.pin, carrier(e.pin), block, "pin"),
                    Connection(e.pivot, carrier(e.pivot), lever, "pin"),
                    Connection(e.pin, block, lever, "slot", (e.pivot, e.pin)),
                ]
                made += [by_name[block], by_name[lever]]
            elif e.kind == "rpp":
                out += [Connection(e.pin, carrier(e.pin), e.body, "slot"), Connection(e.pin, "ground", e.body, "guide")]
                made.append(by_name[e.body])
            elif e.kind == "slot_line":
                lever = next(b.name for b in made if b.kind != "block" and {e.pivot, e.through} <= set(b.joints))
                out += [
                    Connection(e.point, lever, e.body, "slot", (e.pivot, e.through)),
                    Connection(e.point, "ground", e.body, "guide"),
                ]
                made.append(by_name[e.body])
        return tuple(out)

    def ground_joints(self) -> tuple[str, ...]:
        """The frame pivots, in declaration order (a type's GROUND)."""
        return tuple(e.point for e in self._elements if e.kind == "ground")

    def output_joint(self) -> str | None:
        """The joint whose x is the output (a type's OUTPUT_JOINT); None for an angle output."""
        self._build()
        return self._output if any(e.point == self._output for e in self._elements) else None

    def parameters(self) -> tuple[str, ...]:
        """The parameter names the linkage reads, in first-use order (declaration order)."""
        names: list[str] = []
        for e in self._elements:
            for v in vars(e).values():
                for s in v if isinstance(v, tuple) else (v,):
                    if isinstance(s, _Scalar):
                        names += s.names
        return tuple(dict.fromkeys(names))
