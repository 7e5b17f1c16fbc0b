"""A mechanism's declared bodies as shapes on layers: what every picture (plot, DXF, SVG, animation) draws.

Nothing here knows a type: the bodies (``Mechanism.bodies()``), the ground pivots (``GROUND``) and the output
joint (``output_joint()``) are the type's declarations, checked against the joints of its loop before anything is
drawn (``BodyError`` naming the joint). How each kind of body is drawn is in ``qropt.mechanisms.values.Body``. Sizes
of blocks and joint circles follow the size of the whole mechanism over a turn; lengths in the mechanism's unit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from qropt.errors import AssemblyError, BodyError, InvalidParameter
from qropt.kinematics.ops import NUMPY
from qropt.mechanisms import Mechanism
from qropt.mechanisms.values import BODY_KINDS, Body

LAYERS = {"LINKS": 7, "PIVOTS": 1, "JOINTS": 5, "SLIDE_LINE": 8, "SLIDER_PATH": 4, "BLOCKS": 3}  # name -> DXF colour
JOINTS = {"bar": (2, None), "plate": (3, None), "slot-lever": (2, None), "block": (2, 2), "ram": (1, 1), "yoke": (1, 1)}
TURN = 361  # crank angles of a turn for the output path, a lever's reach and a slot's or a ram's travel
BLOCK, RAM, JOINT, PAD = 0.06, 0.08, 0.015, 0.15  # sizes as fractions of the mechanism's size over a turn


class Shape(NamedTuple):
    """One drawn primitive: kind 'line' (two points), 'circle' (its centre; radius), 'polyline' or 'polygon'
    (closed); part: 'link', 'plate', 'slot', 'block', 'ram', 'slide' (the slide line), 'path' (the output's path
    over a turn), 'pivot' (ground) or 'joint'; name: the body's name, or the joint's for pivots and joints."""

    layer: str
    kind: str
    points: tuple
    part: str
    name: str = ""
    radius: float = 0.0


@dataclass(frozen=True)
class Scene:
    """What a whole turn fixes for the drawings of one mechanism: its checked bodies, ground pivots and output
    joint, the output's path (n, 2), each slot lever's reach, the travel of each slot's sliding joint
    ((nearest, farthest) from the pivot) and of each ram's or yoke's pin ((x_lo, x_hi, y_lo, y_hi)), and the
    size that blocks and circles scale with (None if the mechanism cannot turn: the configuration's own)."""

    mechanism: Mechanism
    bodies: tuple[Body, ...]
    ground: tuple[str, ...]
    output: str | None
    path: np.ndarray | None
    reach: dict
    travel: dict
    scale: float | None


def check(m) -> tuple[tuple[Body, ...], tuple[str, ...], str | None]:
    """The bodies, ground pivots and output joint m declares, checked against the joints of its loop
    (BodyError naming the body and the joint that is missing, or what else is wrong)."""
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"a drawing needs a qropt mechanism, got {type(m).__name__}")
    name = type(m).__name__
    bodies = m.bodies()
    if not isinstance(bodies, (tuple, list)) or not bodies:
        raise BodyError(f"{name} declares no bodies (BODIES or bodies()): there is nothing to draw")
    with np.errstate(all="ignore"):
        have = set(m.evaluate(NUMPY, np.zeros(1)).points)
    joints = ", ".join(sorted(have))
    checked = []
    for b in bodies:
        if not isinstance(b, tuple) or len(b) != 3:
            raise BodyError(f"{name}: a body is Body(name, joints, kind), got {b!r}")
        bname, bj, kind = b
        if kind not in BODY_KINDS:
            raise BodyError(f"{name}: body {bname!r} is of kind {kind!r}; the kinds are {', '.join(BODY_KINDS)}")
        lo, hi = JOINTS[kind]
        if isinstance(bj, str) or not isinstance(bj, (tuple, list)) or not lo <= len(bj) <= (hi or len(bj)):
            count = f"{lo}" if hi == lo else f"at least {lo}"
            raise BodyError(f"{name}: body {bname!r} ({kind}) carries {count} joint(s), got {bj!r}")
        for j in bj:
            if j not in have:
                raise BodyError(
                    f"{name}: body {bname!r} names joint {j!r}, which its positions do not have (joints: {joints})"
                )
        checked.append(Body(bname, tuple(bj), kind))
    ground = tuple(m.GROUND)
    for j in ground:
        if j not in have:
            raise BodyError(f"{name}: ground pivot {j!r} (GROUND) is not a joint of its positions (joints: {joints})")
    out = m.output_joint()
    if out is not None and out not in have:
        raise BodyError(f"{name}: output joint {out!r} is not a joint of its positions (joints: {joints})")
    if out is None and m.OUTPUT == "slider":
        raise BodyError(f"{name}: a slider output needs its output joint (OUTPUT_JOINT or output_joint())")
    return tuple(checked), ground, out


def scene(m, n: int = TURN) -> Scene:
    """The checked declarations of m and what its drawings take from a whole turn (n crank angles)."""
    bodies, ground, out = check(m)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or not 2 <= n <= 100_000:
        raise InvalidParameter(f"n (crank angles of a turn) must be an integer from 2 to 100000, got {n!r}")
    needs_turn = out is not None or any(b.kind in ("slot-lever", "ram", "yoke") for b in bodies)
    try:
        pos = m.positions(np.linspace(0.0, 2 * math.pi, int(n))).points
    except AssemblyError:
        if needs_turn:
            raise
        return Scene(m, bodies, ground, out, None, {}, {}, None)
    reach, travel = {}, {}
    for b in bodies:
        q = [pos[j] for j in b.joints]
        if b.kind == "slot-lever":
            d = [np.hypot(*(r - q[0]).T) for r in q[1:]]
            reach[b.name] = float(max(np.nanmax(x) for x in d))
            travel[b.name] = (float(np.nanmin(d[0])), float(np.nanmax(d[0])))
        elif b.kind in ("ram", "yoke"):
            travel[b.name] = (*_span(q[0][:, 0]), *_span(q[0][:, 1]))
    every = np.concatenate(list(pos.values()))
    scale = max(float(np.nanmax(np.ptp(every, axis=0))), 1e-12)
    return Scene(m, bodies, ground, out, None if out is None else pos[out], reach, travel, scale)


def _span(v) -> tuple[float, float]:
    return float(np.nanmin(v)), float(np.nanmax(v))


def shapes(sc: Scene, points: dict) -> list[Shape]:
    """The shapes of sc's mechanism with its joints at ``points`` (joint -> (x, y)): its bodies, then its
    joints, then the output's path."""
    p = {k: np.asarray(v, float).reshape(2) for k, v in points.items()}
    scale = sc.scale or max(float(np.ptp(np.array(list(p.values())), axis=0).max()), 1e-12)
    w, big, pad = BLOCK * scale, RAM * scale, PAD * scale
    out = []
    for name, joints, kind in sc.bodies:
        q = [p[j] for j in joints]
        if kind == "bar":
            far = max(q[1:], key=lambda r: float(np.hypot(*(r - q[0]))))
            out.append(Shape("LINKS", "line", (_xy(q[0]), _xy(far)), "link", name))
        elif kind == "plate":
            out.append(Shape("LINKS", "polygon", tuple(_xy(r) for r in q), "plate", name))
        elif kind == "slot-lever":
            d = [float(np.hypot(*(r - q[0]))) for r in q[1:]]
            u = _unit(q[1] - q[0]) if d[0] > 0 else _unit(q[1 + int(np.argmax(d))] - q[0])
            length = max(sc.reach.get(name, 0.0), *d)
            out.append(Shape("LINKS", "line", (_xy(q[0]), _xy(q[0] + length * u)), "link", name))
            lo, hi = sc.travel.get(name, (d[0], d[0]))
            lo, hi = max(min(lo, d[0]) - w / 2, 0.0), min(max(hi, d[0]) + w / 2, length)  # the slot within the lever
            out.append(Shape("BLOCKS", "polygon", _rectangle(q[0] + lo * u, q[0] + hi * u, w), "slot", name))
        elif kind == "block":
            along = math.atan2(*(q[0] - q[1])[::-1]) if np.hypot(*(q[0] - q[1])) > 0 else 0.0
            out.append(Shape("BLOCKS", "polygon", _square(q[0], along, w), "block", name))
        elif kind == "ram":
            x_lo, x_hi, *_ = sc.travel.get(name, (q[0][0], q[0][0], q[0][1], q[0][1]))
            x_lo, x_hi, y = min(x_lo, q[0][0]), max(x_hi, q[0][0]), float(q[0][1])
            out.append(Shape("SLIDE_LINE", "line", ((x_lo - pad, y), (x_hi + pad, y)), "slide", name))
            out.append(Shape("BLOCKS", "polygon", _square(q[0], 0.0, big), "ram", name))
        else:  # a yoke: the slot normal to the slide line through its pin, the ram on top of it on the slide line
            x, y = float(q[0][0]), float(q[0][1])
            x_lo, x_hi, y_lo, y_hi = sc.travel.get(name, (x, x, y, y))
            x_lo, x_hi, y_lo, y_hi = min(x_lo, x), max(x_hi, x), min(y_lo, y), max(y_hi, y)
            top = y_hi + w / 2
            slot = _rectangle(np.array([x, y_lo - w / 2]), np.array([x, top]), w)
            ram = top + big / 2
            out.append(Shape("SLIDE_LINE", "line", ((x_lo - pad, ram), (x_hi + pad, ram)), "slide", name))
            out.append(Shape("BLOCKS", "polygon", slot, "slot", name))
            out.append(Shape("BLOCKS", "polygon", _square(q[0], math.pi / 2, w), "block", name))
            out.append(Shape("BLOCKS", "polygon", _square((x, ram), 0.0, big), "ram", name))
    for k, r in p.items():
        ground = k in sc.ground
        out.append(
            Shape(
                "PIVOTS" if ground else "JOINTS", "circle", (_xy(r),), "pivot" if ground else "joint", k, JOINT * scale
            )
        )
    if sc.path is not None:
        out.append(Shape("SLIDER_PATH", "polyline", tuple(map(_xy, sc.path)), "path", sc.output))
    return out


def at(sc: Scene, theta2: float) -> list[Shape]:
    """The shapes of sc's mechanism at crank angle theta2 (rad)."""
    pos = sc.mechanism.positions(np.array([theta2])).points
    return shapes(sc, {k: v[0] for k, v in pos.items()})


def bounds(drawn) -> tuple[float, float, float, float]:
    """(x_min, x_max, y_min, y_max) of shapes (a circle by its radius); nan-free."""
    xs, ys = [], []
    for s in drawn:
        r = s.radius
        for x, y in s.points:
            xs += [x - r, x + r]
            ys += [y - r, y + r]
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    return float(np.nanmin(xs)), float(np.nanmax(xs)), float(np.nanmin(ys)), float(np.nanmax(ys))


def _xy(r) -> tuple[float, float]:
    return float(r[0]), float(r[1])


def _unit(v) -> np.ndarray:
    n = float(np.hypot(*v))
    return np.asarray(v, float) / n if n > 0 else np.array([1.0, 0.0])


def _square(centre, angle: float, size: float) -> tuple:
    c, s = math.cos(angle), math.sin(angle)
    corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]]) * size / 2
    return tuple(_xy(r) for r in corners @ np.array([[c, s], [-s, c]]) + np.asarray(centre, float))


def _rectangle(a, b, width: float) -> tuple:
    """The rectangle of the given width about the segment a-b."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    n = _unit(b - a)[::-1] * np.array([-1.0, 1.0]) * width / 2
    return tuple(_xy(r) for r in (a + n, b + n, b - n, a - n))


__all__ = ["LAYERS", "Shape", "Scene", "check", "scene", "shapes", "at", "bounds"]
