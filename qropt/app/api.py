"""The web API's work, free of the web framework: a JSON payload in, a JSON-ready dict out, and ``ApiError``
(status 4xx, one-line reason) for every input the library refuses.

Angles in the payloads are radians (``theta2``), speeds rad/s; the answers give angles in degrees under names ending
in ``_deg``, as ``qropt analyze --json`` does (``qropt.io.records``). A type is a shipped KIND or class name, or a
type of the user's loaded at start-up (``qropt app PROBLEM_FILE``): the API never imports a module a request
names, because a module is code.
"""

from __future__ import annotations

import math
from numbers import Real

import numpy as np

from qropt import units as units_
from qropt import validate
from qropt.errors import QroptError
from qropt.io import records
from qropt.mechanisms import REGISTRY, Mechanism, mechanism_type, type_reference

SAMPLES = 181  # crank angles of the cycle curves (every 2 deg)
MAX_FRAMES = 360  # frames of an animation in one answer


class ApiError(QroptError):
    """A request the API cannot answer: ``status`` 400 (bad input), 404 (no such thing) or 429 (busy); ``field``:
    the part of the request at fault where a page shows it beside its input ("loads": the mass model and load
    panel's masses, loads or drive), else None."""

    def __init__(self, message: str, status: int = 400, field: str | None = None):
        super().__init__(message)
        self.status = status
        self.field = field


def panel_error(e: Exception) -> ApiError:
    """The mass model and load panel's error: the library's reason in one line, marked as the panel's."""
    return ApiError(" ".join(str(e).split()), 400, "loads")


def fields(payload, required: tuple, optional: tuple = ()) -> dict:
    """The payload as a dict with the required fields and no unknown ones."""
    if not isinstance(payload, dict):
        raise ApiError(f"the request body is a JSON object, got {type(payload).__name__}")
    missing = [k for k in required if k not in payload]
    unknown = sorted(set(payload) - set(required) - set(optional))
    if missing:
        raise ApiError(f"missing field(s): {', '.join(missing)}")
    if unknown:
        raise ApiError(f"unknown field(s): {', '.join(unknown)}; fields are {', '.join(required + optional)}")
    return payload


def number(d: dict, key: str, default=None, *, low=-math.inf, high=math.inf) -> float:
    """A finite number field within [low, high]."""
    v = d.get(key, default)
    if isinstance(v, bool) or not isinstance(v, Real) or not math.isfinite(v):
        raise ApiError(f"{key} is a finite number, got {v!r:.60}")
    return validate.within(key, v, low, high, error=ApiError)


def flag(d: dict, key: str, default: bool) -> bool:
    """A true-or-false field."""
    return validate.flag(key, d.get(key, default), error=ApiError)


def report_input(payload) -> dict:
    """A report job's input ``{type, params, units?, theta2?, omega2?}`` (rad, rad/s), checked whole."""
    d = fields(payload, ("type", "params"), ("units", "theta2", "omega2"))
    mechanism(d)
    out = dict(
        d, theta2=number(d, "theta2", 0.0, low=-1e6, high=1e6), omega2=number(d, "omega2", 1.0, low=-1e4, high=1e4)
    )
    if out["omega2"] == 0.0:
        raise ApiError("omega2 must be nonzero (rad/s; its sign is the crank's sense of rotation)")
    return out


def needs_drive(c) -> bool:
    """Whether a criterion needs the problem's drive (``Problem(drive=...)``): the motor's RMS torque, or a
    registered criterion that says so (``needs_drive = True``)."""
    try:
        from qropt.synthesis.motor import RmsMotorTorque
    except ImportError:  # pragma: no cover - a qropt without the drive's criterion
        RmsMotorTorque = ()
    return isinstance(c, RmsMotorTorque) or bool(getattr(c, "needs_drive", False))


def objectives() -> list[dict]:
    """Every objective of the criteria registry (``qropt.synthesis.criteria.CRITERIA``, a user's registered ones
    included), one entry per criterion: its ``objective`` and, for ``min_size``, the ``size`` measure; the
    criterion's name, label and unit; ``dynamic`` where it needs a mass model or loads (and a time budget helps);
    ``drive`` where it needs the drive (a gearbox's ratio and efficiency)."""
    from qropt.synthesis import criteria

    return [
        {
            "objective": c.objective,
            "size": c.size,
            "criterion": c.name,
            "label": c.label,
            "unit": c.unit,
            "maximise": c.maximise,
            "dynamic": c.needs_masses,
            "drive": needs_drive(c),
        }
        for c in criteria.CRITERIA.values()
    ]


def objective_names() -> tuple:
    """The objective names a request may give (``criteria.objectives()`` without None)."""
    from qropt.synthesis import criteria

    return tuple(o for o in criteria.objectives() if o)


def design_types() -> list[dict]:
    """The rows the Design page offers: ``design``'s built-in rows (every shipped slider type and its options)
    and every other slider type the app serves (a user's, from ``qropt app PROBLEM_FILE``), each its row name,
    the name a request gives for it (``type``), its class and whether it is built in (``design`` runs the built-in
    rows when a request names no ``types``)."""
    from qropt.mechanisms import TYPES as SHIPPED
    from qropt.studies._design import TYPES

    out = [
        {"name": k, "type": k, "class": mechanism_type(v[0]).__name__, "built_in": True} | row_points(k)
        for k, v in TYPES.items()
    ]
    for name in types():
        cls = known_type(name)
        if cls.TRAVEL != "stroke" or cls in SHIPPED:
            continue
        row = cls.__dict__.get("KIND") or cls.__name__
        out.append({"name": row, "type": name, "class": cls.__name__, "built_in": False} | row_points(name))
    return out


def points(bodies, ram) -> dict:
    """Where loads may act: ``joints`` (a force's or a point mass's place), ``bodies`` (a torque's) and ``ram``,
    the output's joint (None without a slider)."""
    return {"joints": sorted({j for b in bodies for j in b.joints}), "bodies": [b.name for b in bodies], "ram": ram}


def row_points(kind) -> dict:
    """``points`` of a design row's type as ``design`` builds it (its options: the crank-shaper-rod's rod)."""
    from qropt.studies._design import type_problem

    p = type_problem(kind, 1.5, 1.0)
    params = {**p.fixed, **{k: (lo + hi) / 2 for k, (lo, hi) in p.free.items()}}
    link = p.mechanism.linkage(params)
    if link is None:
        return points(p.mechanism.BODIES, p.mechanism.OUTPUT_JOINT)
    return points(link.bodies(), link.output_joint() if callable(getattr(link, "output_joint", None)) else None)


def design_type(name) -> str:
    """A type a design request names: a row of ``design_types`` or a served slider type (never imported)."""
    from qropt.studies._design import TYPES

    if isinstance(name, str) and name in TYPES:
        return name
    cls = known_type(name)
    if cls.TRAVEL != "stroke":
        raise ApiError(f"{cls.__name__} has no slider (its output is a {cls.TRAVEL}): design compares strokes")
    return name


EXTREME_ACCEL = 10.0  # peak acceleration over stroke x omega2^2 above which a design is flagged (a crank's is ~1)
SMALL_GAMMA = 10.0  # deg: a least transmission angle below this is flagged


def row_words(status: str, reachable: dict, time_ratio: float, stroke: float, units: str) -> str:
    """Why a design row has no design, in a sentence a student reads: each target against the range the type
    reaches within its bounds (``Result.reachable``; 'can reach' where a closed form proves the range, 'was found
    to reach' where designs were sampled), else that no design meets the targets together."""
    proved = status == "infeasible"
    names = {"time_ratio": ("TR", time_ratio, ""), "stroke": ("the stroke", stroke, f" {units}")}
    said, inside = [], []
    for k, (lo, hi) in (reachable or {}).items():
        if k not in names:
            continue
        word, v, u = names[k]
        if not (math.isfinite(lo) and math.isfinite(hi)):
            return "No design of this type turns fully within its bounds and conditions."
        span = f"{lo:.4g} to {hi:.4g}{u}"
        if lo - 1e-6 * abs(v) <= v <= hi + 1e-6 * abs(v):
            inside.append(f"{word} {span}")
            continue
        side = "above the highest" if v > hi else "below the lowest"
        reach = "this type can reach" if proved else "found for this type"
        said.append(f"{word} {v:g}{u} is {side} {reach} within its bounds ({span})")
    if said:
        return "No design: " + "; ".join(said) + "."
    if inside:
        return (
            f"No design found: each target alone is within reach ({', '.join(inside)}), but no design found "
            "meets them together with the conditions."
        )
    return ""


def row_warnings(row: dict, time_ratio: float, stroke: float, omega2: float) -> list[str]:
    """What makes a design row's answer doubtful though the solve succeeded: a peak acceleration many times
    stroke x omega2^2 (the return stroke squeezed into a small part of the turn), a least transmission angle near
    zero (the links push along each other and the mechanism may jam)."""
    out = []
    a, g = row.get("peak_accel"), row.get("gamma_min")
    if a is not None and omega2:
        k = a / (stroke * omega2**2)
        if k > EXTREME_ACCEL:
            arc = 360.0 / (1.0 + time_ratio)
            out.append(
                f"extreme: its peak acceleration is {k:.0f} times stroke × omega2² (about 1 for an ordinary "
                f"crank); the return stroke takes only {arc:.3g}° of the crank's turn"
            )
    if g is not None and math.degrees(g) < SMALL_GAMMA:
        out.append(
            f"gamma_min is only {math.degrees(g):.3g}°: the links push nearly along each other and the "
            "mechanism may jam"
        )
    return out


def known_type(name) -> type[Mechanism]:
    """A registered type by its KIND, class name or ``module:Class`` reference; never imports."""
    if isinstance(name, str) and ":" in name:
        for cls in list(REGISTRY.values()):
            if type_reference(cls) == name:
                return cls
        raise ApiError(
            f"unknown mechanism type {name!r:.80}: the app serves {', '.join(types())}; load a type of your own "
            "at start-up: qropt app PROBLEM_FILE"
        )
    try:
        return mechanism_type(name)
    except QroptError as e:
        raise ApiError(str(e)) from None


def types() -> list[str]:
    """Every type the app serves, by the name files use."""
    return sorted({type_reference(c) for c in list(REGISTRY.values())})


def type_info() -> list[dict]:
    """Each type's name, class, output, parameters (name -> kind), a valid default design and its summary (the
    first paragraph of the class's docstring, which says which parameter is which link)."""
    from qropt.app.defaults import default_params

    out = []
    for name in types():
        cls = known_type(name)
        params = default_params(cls)
        try:
            where = design_points(cls(**params))
        except (QroptError, TypeError):  # no valid default design: the class's own declaration
            where = points(cls.BODIES, cls.OUTPUT_JOINT)
        out.append(
            {
                "type": name,
                "class": cls.__name__,
                "output": cls.OUTPUT,
                "kinds": cls.kinds(),
                "required": cls.required(),
                "params": params,
                "summary": " ".join((cls.__doc__ or "").strip().split("\n\n")[0].split()),
            }
            | where
        )
    return out


def design_points(m: Mechanism) -> dict:
    """``points`` of a design: its bodies and joints (which depend on its options) and the output's joint."""
    return points(m.bodies(), m.output_joint())


def mechanism(d: dict) -> Mechanism:
    """The mechanism of ``{type, params, units?}``."""
    cls = known_type(d.get("type"))
    params = d.get("params")
    if not isinstance(params, dict):
        raise ApiError(f"params is an object of parameter values, got {type(params).__name__}")
    for k, v in params.items():
        if isinstance(v, bool) or not isinstance(v, Real) or not math.isfinite(v):
            raise ApiError(f"parameter {k} is a finite number, got {v!r:.60}")
    units = d.get("units", units_.DEFAULT)
    try:
        return cls(**params, units=units)
    except TypeError as e:
        raise ApiError(f"{cls.__name__}: {e}") from None


def analyze(payload) -> dict:
    """``POST /api/analyze``: ``{type, params, theta2, omega2}`` (rad, rad/s; optional ``alpha2``, ``units``,
    ``masses`` (``Masses.to_dict`` form), ``loads`` (``Loads.to_dict`` form), ``drive`` (``Drive.to_dict`` form:
    ``{ratio, efficiency}``; with masses), ``frames`` (crank angles of an animation, 0-360), ``polygons`` (bool,
    default true), ``extremes`` (bool, default true: the exact dynamic extremes, flywheel, efficiency and drive,
    the costly part; false while a slider moves)): the state at theta2, the cycle quantities, x, v, a over the
    turn, the drawing at theta2, the polygons at theta2, where loads may act (``joints``, ``bodies``, ``ram``)
    and, with masses, the forces (``forces``). A mass model, load or drive the library refuses or cannot apply
    is a 400 with ``field: "loads"``."""
    d = fields(
        payload,
        ("type", "params"),
        ("theta2", "omega2", "alpha2", "units", "masses", "loads", "drive", "frames", "polygons", "extremes"),
    )
    theta2 = number(d, "theta2", 0.0, low=-1e6, high=1e6)
    omega2 = number(d, "omega2", 1.0, low=-1e4, high=1e4)
    alpha2 = number(d, "alpha2", 0.0, low=-1e6, high=1e6)
    frames = d.get("frames", 0)
    if isinstance(frames, bool) or not isinstance(frames, int) or not 0 <= frames <= MAX_FRAMES:
        raise ApiError(f"frames is an integer from 0 to {MAX_FRAMES}, got {frames!r:.40}")
    if omega2 == 0.0:
        raise ApiError("omega2 must be nonzero (rad/s; its sign is the crank's sense of rotation)")
    show_polygons, extremes = flag(d, "polygons", True), flag(d, "extremes", True)
    m = mechanism(d)
    out = records.analysis(m, theta2, omega2, alpha2)
    peak = m.peak_acceleration(omega2)
    out["peak_accel"] = {"value": peak.value, "theta2_deg": math.degrees(peak.theta2)}
    start, length = m.working_arc(omega2)
    out["working_arc_deg"] = [math.degrees(start) % 360.0, math.degrees(length)]
    th = np.linspace(0.0, 2 * math.pi, SAMPLES)
    mo = m.motion(th, omega2, alpha2)
    out["cycle"] = {
        "theta2_deg": np.degrees(th).tolist(),
        "x": mo.x.tolist(),
        "v": mo.v.tolist(),
        "a": mo.a.tolist(),
        "working": working(th, start, length),
    }
    out["drawing"] = drawing(m, theta2, frames, start, length)
    if show_polygons:
        shown = polygons(m, theta2, omega2, alpha2)
        out["polygons"], out["polygons_reason"] = (None, shown) if isinstance(shown, str) else (shown, "")
    out |= design_points(m)
    if d.get("masses") is not None:
        out["dynamics"] = forces(m, theta2, omega2, alpha2, d["masses"], d.get("loads"), extremes, d.get("drive"))
    elif d.get("loads") is not None or d.get("drive") is not None:
        raise ApiError(
            "loads and a drive act with a mass model: send masses too (Masses.to_dict's form)", field="loads"
        )
    return out


def drawing(m: Mechanism, theta2: float, frames: int, start: float, length: float) -> dict:
    """The shapes at theta2, the view box of the whole turn, the output's path split into working and return
    strokes, and ``frames`` evenly spaced frames of the turn (each its crank angle, stroke and shapes)."""
    from qropt.io import drawing as dr

    sc = dr.scene(m, 121)
    now = dr.at(sc, theta2)
    pos = m.positions(np.linspace(0.0, 2 * math.pi, 73)).points
    turn = [dr.shapes(sc, {k: v[i] for k, v in pos.items()}) for i in range(0, 73, 6)]
    x0, x1, y0, y1 = dr.bounds([s for f in [now, *turn] for s in f])
    out = {
        "view": [x0, y0, x1 - x0, y1 - y0],
        "shapes": [_shape(s) for s in now if s.part != "path"],
        "path": None,
        "frames": [],
    }
    if sc.path is not None:
        th = np.linspace(0.0, 2 * math.pi, sc.path.shape[0])
        out["path"] = {
            "points": np.round(sc.path, 12).tolist(),
            "working": working(th, start, length),
        }
    if frames:
        th = np.linspace(0.0, 2 * math.pi, frames, endpoint=False)
        pos = m.positions(th).points
        for i, t in enumerate(th):
            shapes = dr.shapes(sc, {k: v[i] for k, v in pos.items()})
            out["frames"].append(
                {
                    "theta2_deg": math.degrees(t),
                    "working": working([t], start, length)[0],
                    "shapes": [_shape(s) for s in shapes if s.part != "path"],
                }
            )
    return out


def working(theta2, start: float, length: float) -> list[bool]:
    """Which crank angles (rad) lie on the working stroke, the arc ``start`` + [0, ``length``] (``working_arc``)."""
    return (((np.asarray(theta2, float) - start) % (2 * math.pi)) <= length).tolist()


def _shape(s) -> dict:
    d = {"kind": s.kind, "part": s.part, "name": s.name, "points": [[float(x), float(y)] for x, y in s.points]}
    if s.kind == "circle":
        d["radius"] = float(s.radius)
    return d


def polygons(m: Mechanism, theta2: float, omega2: float, alpha2: float) -> list[dict] | str:
    """The velocity and acceleration equations at theta2, term by term (components and the joint's exact
    vector), for a type built from dyads; for a type without a linkage declaration, why not (a string)."""
    try:
        rm = m.relative_motion(theta2, omega2, alpha2)
    except QroptError as e:
        return str(e)
    return [
        {
            "joint": e.joint,
            "quantity": e.quantity,
            "exact": [float(e.exact[0]), float(e.exact[1])],
            "terms": [
                {"name": t.name, "kind": t.kind, "vector": [float(t.vector[0]), float(t.vector[1])], "solved": t.solved}
                for t in e.terms
            ],
        }
        for e in rm.equations
    ]


def forces(
    m: Mechanism, theta2: float, omega2: float, alpha2: float, masses, loads, extremes: bool = True, drive=None
) -> dict:
    """With a mass model: the crank torque over the turn, the torque and every joint force at theta2 (N m, N)
    and, with ``extremes``, the exact dynamic extremes over the turn and the flywheel (``records.dynamics``); with
    friction (the slide's or the pins') the efficiency of each stroke and of the turn (``m.efficiency``); with a
    ``drive`` the motor's torque (``m.drive_check``). Every error of the masses, loads or drive is the panel's
    (``panel_error``): a load the library cannot apply is refused, never dropped."""
    from qropt.dynamics.cycle import CycleDynamics
    from qropt.dynamics.drive import Drive
    from qropt.dynamics.model import Loads, Masses

    if not isinstance(masses, dict) or (loads is not None and not isinstance(loads, dict)):
        raise ApiError("masses and loads are objects in the form of Masses.to_dict and Loads.to_dict", field="loads")
    if drive is not None and not isinstance(drive, dict):
        raise ApiError("drive is an object in the form of Drive.to_dict ({ratio, efficiency})", field="loads")
    try:
        ms = Masses.from_dict(masses)
        ld = Loads() if loads is None else Loads.from_dict(loads)
        dr = None if drive is None else Drive.from_dict(drive)
        if dr is not None and alpha2 != 0:
            raise ApiError("the drive is checked at a constant crank speed: alpha2 must be 0", field="loads")
        cd = CycleDynamics(m, omega2, alpha2, ms, ld)
        th = np.linspace(0.0, 2 * math.pi, SAMPLES)
        dy = cd.at(th)
        now = cd.at(np.array([theta2]))
        if extremes:
            out = records.dynamics(cd, ms, cd.extremes(), cd.flywheel(0.05) if alpha2 == 0 else None)
            if alpha2 == 0 and (ld.friction or (ld.pin_friction is not None and ld.pin_friction.active)):
                out["efficiency"] = efficiency(m.efficiency(omega2, masses=ms, loads=ld))
            if dr is not None:
                out["drive"] = drive_numbers(m.drive_check(dr, omega2, masses=ms, loads=ld))
        else:
            out = {"type": type(m).__name__, "omega2": omega2, "alpha2": alpha2, "masses": ms.to_dict()}
            out["loads"] = ld.to_dict()
    except ApiError:
        raise
    except QroptError as e:
        raise panel_error(e) from None
    out["torque"] = {"theta2_deg": np.degrees(th).tolist(), "value": dy.torque.tolist()}
    out["at"] = {
        "theta2_deg": math.degrees(theta2),
        "torque": float(now.torque[0]),
        "joint_forces": {k: [float(v[0, 0]), float(v[0, 1])] for k, v in sorted(now.joint_forces.items())},
    }
    return out


def _finite(v):
    return float(v) if math.isfinite(v) else None


def efficiency(e) -> dict:
    """``m.efficiency``'s strokes as plain data (J; an efficiency of NaN, where the loads do no work, as None)."""

    def stroke(w):
        return {
            "input": w.input,
            "output": w.output,
            "friction": w.friction,
            "pins": dict(w.pins),
            "efficiency": _finite(w.efficiency),
            "driven_by": w.driven_by,
        }

    return {"working": stroke(e.working), "return": stroke(e.return_stroke), "turn": stroke(e.turn)}


def drive_numbers(dc) -> dict:
    """``drive_check``'s figures at the motor (N m, rad/s, W; angles in degrees)."""
    return {
        "drive": dc.drive.to_dict(),
        "peak_torque": {"value": dc.peak_torque.value, "theta2_deg": math.degrees(dc.peak_torque.theta2)},
        "rms_torque": dc.rms_torque,
        "mean_torque": dc.mean_torque,
        "peak_power": {"value": dc.peak_power.value, "theta2_deg": math.degrees(dc.peak_power.theta2)},
        "mean_power": dc.mean_power,
        "motor_speed": dc.motor_speed,
    }
