"""One classroom project per seed: the paper's quick-return design and analysis project (Podhorodeski, Nokleby and
Wittchen, its "Example project requirements"), drawn for one mechanism type.

A project states: a time ratio and a stroke; an existing mechanism of the type (the given links, which stay, and
the current lengths of the links to find); design requirement 1 (the links to find for the TR and stroke, best
minimum transmission angle over the turn); design requirement 2 (the travel of one adjustable link: its whole
working interval, and the part that covers a band of TRs); the four discussion issues; the analysis at a crank
angle and speed by relative motion (polygons) and by computer; a simulation over a turn.

The draws (numpy ``default_rng`` seeded with the seed for an open project, or with HMAC-SHA256 of the type and seed
under the instructor's secret for a class's: see ``project``; in this order each attempt): the TR from the type's
range (two decimals), the stroke from STROKE_RANGE = 0.1..0.6 m (three decimals), each given link as a multiple of
the stroke (three decimals), the TR band of requirement 2 (the TR minus 0.1..0.3, at least 1.05, to the TR plus
0.1..0.3), the crank angle (a multiple of 15 deg from 15 to 345) and omega2 (an integer from 5 to 20 rad/s). The TR
ranges per type (``SPECS``): drag-link slider 1.45-1.8, crank-rocker slider 1.1-1.4, slider-crank 1.1-1.4,
Whitworth, crank-shaper and slot-ram shaper 1.3-2.2 (a crank-rocker or an offset slider-crank gives only modest TRs
with fair transmission angles; a drag-link with r1 about a third of the stroke no TR below about 1.45). A draw
counts when requirement 1 solves to a certified optimum (``qropt.solve``, status 'optimal') with gamma_min at least
15 deg (MIN_GAMMA), requirement 2's band lies on one monotone branch of the adjustable link, and the polygons exist;
otherwise the next draw of the same generator is taken (at most MAX_DRAWS) and the number of redraws is recorded.
Then the current lengths of the links to find are drawn (the solution's times 0.75..1.25, three decimals, a
mechanism that works). Every number comes from the library code behind the command line.
"""

from __future__ import annotations

import base64
import hashlib
import hmac
import html
import math
import secrets
from dataclasses import dataclass

import numpy as np

from qropt.errors import InvalidParameter, QroptError
from qropt.mechanisms import (
    CrankRockerSlider,
    CrankShaper,
    DragLinkSlider,
    Mechanism,
    SliderCrank,
    SlotRamShaper,
    Whitworth,
)
from qropt.studies._design import bounds_of

STROKE_RANGE = (0.1, 0.6)  # m
THETA2_STEP_DEG = 15
OMEGA2_RANGE = (5, 20)  # rad/s, integers
MAX_DRAWS = 50
MIN_GAMMA = math.radians(15.0)  # a design worth building: its gamma_min over the turn at least this


@dataclass(frozen=True)
class Spec:
    """A type's project: the mechanism type, the given links (multiples of the stroke), the links to find, the
    adjustable link, the TR range, the solve's conditions, each link's name, the four discussion issues and the
    worked answer to the third (how many designs the links to find and the further free link leave)."""

    mechanism: type[Mechanism]
    title: str
    layout: str
    given: dict
    find: tuple
    adjustable: str
    time_ratio: tuple
    conditions: dict
    names: dict
    issues: tuple
    freedom: str


_FOUR_BAR_NAMES = {
    "r1": "distance between the fixed centres O2 and O4",
    "r2": "crank O2A",
    "r3": "coupler AB",
    "r4": "follower O4B",
    "r5": "pin C on the follower, O4C",
    "r6": "slider's rod CD",
}
_FOUR_BAR_FREEDOM = (
    "A single infinity of solutions: with both r1 and r3 free the TR is one equation in two unknowns, which "
    "leaves a curve of (r1, r3) designs (within the Grashof class); the stroke still fixes r5 alone."
)
_LEVER_FREEDOM = (
    "A single infinity: the TR depends on the ratio of r1 and r2 only, so it fixes the ratio and every centre "
    "distance r1 has its crank r2; the stroke then fixes the remaining link."
)
_LEVER_ISSUES = (
    "How many mechanisms providing the specified TR are possible if only the crank radius r2 is varied?",
    "What is the range of TR that would be possible by adjusting the crank radius r2 (within its bounds)?",
    "How many feasible mechanism solutions would exist for a given TR if both the centre distance r1 and the "
    "crank radius r2 could be changed?",
    "Discuss the issues you would consider in the isolation of a unique mechanism design.",
)


def _four_bar(mechanism, title, grashof, given, tr) -> Spec:
    return Spec(
        mechanism,
        title,
        f"a {grashof} four-bar O2-A-B-O4 (O4 = (r1, 0)) drives pin C on the follower O4B; a rod CD drives the "
        "slider D on the line through O2 and O4 (h = 0)",
        given,
        ("r3", "r5"),
        "r3",
        tr,
        {"grashof": grashof},
        _FOUR_BAR_NAMES,
        (
            "How many mechanisms providing a specific TR are possible if only r3 is varied?",
            "What is the range of TR that would be possible by adjusting the length of the coupler?",
            "How many feasible mechanism solutions would exist for a given TR if both the base length O2O4 and "
            "the coupler length could be changed?",
            "Discuss the issues you would consider in the isolation of a unique mechanism design.",
        ),
        _FOUR_BAR_FREEDOM,
    )


SPECS = (
    _four_bar(
        DragLinkSlider,
        "drag-link-driven slider",
        "drag-link",
        {"r1": (0.25, 0.4), "r2": (0.65, 0.85), "r4": (0.85, 1.05), "r6": (0.9, 1.3)},
        (1.45, 1.8),
    ),
    _four_bar(
        CrankRockerSlider,
        "crank-rocker-driven slider",
        "crank-rocker",
        {"r1": (0.9, 1.2), "r2": (0.25, 0.4), "r4": (0.7, 1.0), "r6": (1.8, 2.4)},
        (1.1, 1.4),
    ),
    Spec(
        Whitworth,
        "Whitworth quick-return",
        "the crank O2A (O2 at the origin) turns the slotted lever about O4 = (0, -r1), r2 > r1; pin C on the "
        "lever drives the rod CD and the ram D on the line through O4 (h = 0)",
        {"r1": (0.15, 0.35), "r6": (1.2, 1.8)},
        ("r2", "r5"),
        "r2",
        (1.3, 2.2),
        {},
        {
            "r1": "distance between the fixed centres O2 and O4",
            "r2": "crank O2A, the crank pin's radius",
            "r5": "pin C on the slotted lever, O4C",
            "r6": "ram's rod CD",
        },
        _LEVER_ISSUES,
        _LEVER_FREEDOM,
    ),
    Spec(
        CrankShaper,
        "crank-shaper",
        "the crank O2A (O2 at the origin) rocks the slotted lever about O4 = (0, -r1), r2 < r1; pin C on the lever "
        "at O4C = r4 drives the ram through a yoke (the ram moves with x_C)",
        {"r1": (0.6, 1.0)},
        ("r2", "r4"),
        "r2",
        (1.3, 2.2),
        {},
        {
            "r1": "distance between the fixed centres O2 and O4",
            "r2": "crank O2A, the crank pin's radius",
            "r4": "pin C on the slotted lever, O4C",
        },
        _LEVER_ISSUES,
        _LEVER_FREEDOM,
    ),
    Spec(
        SlotRamShaper,
        "slot-ram shaper",
        "the crank O2A (O2 at the origin) rocks the slotted lever about O4 = (0, -r1), r2 < r1; the ram's pin D "
        "rides in the lever's slot on the slide line a height h above O4",
        {"r1": (0.6, 1.0)},
        ("r2", "h"),
        "r2",
        (1.3, 2.2),
        {},
        {
            "r1": "distance between the fixed centres O2 and O4",
            "r2": "crank O2A, the crank pin's radius",
            "h": "height of the slide line above O4",
        },
        _LEVER_ISSUES,
        _LEVER_FREEDOM,
    ),
    Spec(
        SliderCrank,
        "offset slider-crank",
        "the crank O2A (O2 at the origin) drives the slider C through the rod AC on the slide line y = e",
        {"r3": (0.9, 1.4)},
        ("r2", "e"),
        "e",
        (1.1, 1.4),
        {},
        {"r2": "crank O2A", "r3": "connecting rod AC", "e": "offset of the slide line from O2"},
        (
            "How many mechanisms providing the specified TR are possible if only the offset e is varied?",
            "What is the range of TR that would be possible by adjusting the offset e (an adjustable slide)?",
            "How many feasible mechanism solutions would exist for the given TR and stroke if the rod length r3 "
            "could be changed too?",
            "Discuss the issues you would consider in the isolation of a unique mechanism design.",
        ),
        "A single infinity: the TR and the stroke are two equations in r2, r3 and e, which leaves a curve of "
        "designs; each rod length has its crank and offset.",
    ),
)
KINDS = tuple(spec.mechanism.KIND for spec in SPECS)


@dataclass(frozen=True)
class Project:
    """One drawn project and everything its solution needs (computed once, by the library).

    Lengths in ``units`` (m), angles in rad, omega2 in rad/s. ``given``: the links that stay; ``current``: the
    existing mechanism's lengths of the links to find (None where no drawn one works); ``band``: requirement 2's
    TRs; ``redraws``: draws rejected before this one; ``problem``/``result``: requirement 1 and its solve;
    ``reach``/``adjust``: requirement 2 (``qropt.reachable`` and ``Reachable.adjustable``)."""

    kind: str
    seed: int
    time_ratio: float
    stroke: float
    given: dict
    current: dict | None
    find: tuple
    adjustable: str
    band: tuple
    theta2: float
    omega2: float
    redraws: int
    problem: object
    result: object
    reach: object
    adjust: object
    units: str = "m"
    code: str = ""
    keyed: bool = False

    @property
    def spec(self) -> Spec:
        return _spec(self.kind)

    @property
    def mechanism(self):
        """The solved design (requirement 1)."""
        return self.result.mechanism

    def relative_motion(self):
        """The solved design's velocity and acceleration equations at the project's theta2, omega2, alpha2 = 0."""
        return self.mechanism.relative_motion(self.theta2, self.omega2, 0.0)

    def polygon_ram(self) -> tuple[float, float]:
        """(v, a) of the ram along the slide line from the polygons: the sums of the output joint's terms."""
        rm, joint = self.relative_motion(), self.mechanism.output_joint()
        out = {e.quantity: float(sum(t.vector for t in e.terms)[0]) for e in rm.equations if e.joint == joint}
        return out["velocity"], out["acceleration"]

    def computer_ram(self) -> tuple[float, float]:
        """(v, a) of the ram from the exact analysis (``Mechanism.motion``, as ``qropt analyze``)."""
        mo = self.mechanism.motion(np.array([self.theta2]), self.omega2, 0.0)
        return float(mo.v[0]), float(mo.a[0])


def _spec(kind: str) -> Spec:
    """The project of the type whose KIND this is."""
    return next(spec for spec in SPECS if kind == spec.mechanism.KIND)


def _kind(kind) -> str:
    if not isinstance(kind, str) or kind not in KINDS:
        raise InvalidParameter(f"unknown project type {kind!r}; the types are {', '.join(KINDS)}")
    return kind


MIN_SECRET = 8  # characters


def new_secret() -> str:
    """A fresh instructor's secret (16 random bytes, base32: 26 characters), for a class set's key file."""
    return base64.b32encode(secrets.token_bytes(16)).decode().rstrip("=").lower()


def _secret(secret) -> bytes | None:
    if secret is None:
        return None
    if not isinstance(secret, str) or len(secret.strip()) < MIN_SECRET or secret != secret.strip():
        raise InvalidParameter(
            f"a project secret is a string of at least {MIN_SECRET} characters without leading or trailing spaces"
        )
    return secret.encode()


def _mac(secret: bytes, what: str, kind: str, seed: int) -> bytes:
    return hmac.new(secret, f"qropt-project:{what}:{kind}:{seed}".encode(), hashlib.sha256).digest()


def statement_code(kind: str, seed: int, secret: str | None = None) -> str:
    """The statement's code (8 base32 characters as XXXX-XXXX): HMAC-SHA256 of the type and seed under the
    instructor's secret, so that the code says nothing of the seed without the secret; without a secret (an open
    project, drawn from the seed alone) a plain SHA-256 of them."""
    kind, seed, key = _kind(kind), _seed(seed), _secret(secret)
    if key:
        digest = _mac(key, "code", kind, seed)
    else:
        digest = hashlib.sha256(f"qropt-project:open:{kind}:{seed}".encode()).digest()
    raw = base64.b32encode(digest).decode()[:8]
    return f"{raw[:4]}-{raw[4:]}"


def _seed(seed) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InvalidParameter(f"a project seed is an integer >= 0, got {seed!r}")
    return int(seed)


def _free_bounds(cls, name: str, stroke: float) -> tuple:
    """A link's bounds in requirement 1: design's default bounds of its kind (``Mechanism.kinds()``)."""
    return bounds_of(cls.kinds()[name], stroke)


def _scan_bounds(cls, p: dict, name: str, stroke: float) -> tuple:
    """The adjustable link's scanned interval: its bounds in requirement 1, for a slotted lever kept where the TR
    stays below about 9 (r2 / r1 or r1 / r2 at most 0.95: the TR grows without bound as the ratio nears 1)."""
    lo, hi = _free_bounds(cls, name, stroke)
    if name == "r2" and "r1" in p:
        lo, hi = (max(lo, p["r1"] / 0.95), hi) if p["r2"] > p["r1"] else (lo, min(hi, 0.95 * p["r1"]))
    return lo, hi


def _attempt(kind: str, rng):
    """One draw: (fields, problem, result, reach, adjust), or None when it is not a solvable project."""
    from qropt import reachable, solve
    from qropt.synthesis.problem import Problem

    spec = _spec(kind)
    tr = round(float(rng.uniform(*spec.time_ratio)), 2)
    s = round(float(rng.uniform(*STROKE_RANGE)), 3)
    given = {k: round(float(rng.uniform(lo, hi)) * s, 3) for k, (lo, hi) in spec.given.items()}
    band = (round(max(1.05, tr - float(rng.uniform(0.1, 0.3))), 2), round(tr + float(rng.uniform(0.1, 0.3)), 2))
    theta2 = math.radians(THETA2_STEP_DEG * int(rng.integers(1, 360 // THETA2_STEP_DEG)))
    omega2 = float(rng.integers(OMEGA2_RANGE[0], OMEGA2_RANGE[1] + 1))
    fields = {"time_ratio": tr, "stroke": s, "given": given, "band": band, "theta2": theta2, "omega2": omega2}
    problem = Problem(
        spec.mechanism,
        fixed=given,
        free={k: _free_bounds(spec.mechanism, k, s) for k in spec.find},
        targets={"time_ratio": tr, "stroke": s},
        conditions=dict(spec.conditions),
        objective="max_gamma_min",
        name=f"{kind} TR {tr:g} stroke {s:g} m",
    )
    result = solve(problem)
    if result.status != "optimal" or result.mechanism.gamma_min().value < MIN_GAMMA:
        return None
    try:
        m = result.mechanism
        reach = reachable(m, spec.adjustable, bounds=_scan_bounds(type(m), m.params, spec.adjustable, s))
        low = math.ceil(100 * reach.time_ratio_range.low + 1) / 100  # the band within the reachable TRs
        band = fields["band"] = (max(band[0], low), band[1])
        adjust = reach.adjustable(*band)
        m.relative_motion(theta2, omega2, 0.0)
    except QroptError:
        return None
    return fields, problem, result, reach, adjust


def _current(spec: Spec, m, rng) -> dict | None:
    """The existing mechanism's lengths of the links to find: the solution's times 0.75..1.25 (a working one)."""
    for _ in range(20):
        cur = {k: round(m.params[k] * float(rng.uniform(0.75, 1.25)), 3) for k in spec.find}
        try:
            c = type(m)(**{**m.params, **cur}, units=m.units)
            if c.broken_rules(spec.conditions.get("grashof")) or c.dead_centres().reversals != 1:
                continue
            c.time_ratio()
        except QroptError:
            continue
        return cur
    return None


def project(kind: str, seed: int, secret: str | None = None) -> Project:
    """The project of this type and seed (see the module docstring for the draws and the ranges); the same seed
    (and secret) gives the same project. Without ``secret`` an open project: the draws are numpy's
    ``default_rng(seed)``, which anyone with qropt can repeat by trying seeds. With the instructor's ``secret``
    (at least MIN_SECRET characters) the generator is seeded with HMAC-SHA256(secret, type and seed), so that
    neither the statement's numbers nor its code (``statement_code``) lead back to the seed or the solution without
    the secret. InvalidParameter for an unknown type, a bad seed or secret, or when no draw of MAX_DRAWS is
    solvable."""
    kind, seed, key = _kind(kind), _seed(seed), _secret(secret)
    rng = np.random.default_rng(int.from_bytes(_mac(key, "draw", kind, seed), "big") if key else seed)
    for attempt in range(MAX_DRAWS):
        got = _attempt(kind, rng)
        if got is not None:
            fields, problem, result, reach, adjust = got
            spec = _spec(kind)
            current = _current(spec, result.mechanism, rng)
            return Project(
                kind=kind,
                seed=seed,
                current=current,
                find=spec.find,
                adjustable=spec.adjustable,
                redraws=attempt,
                problem=problem,
                result=result,
                reach=reach,
                adjust=adjust,
                code=statement_code(kind, seed, secret),
                keyed=key is not None,
                **fields,
            )
    raise InvalidParameter(f"no solvable {kind} project in {MAX_DRAWS} draws of seed {seed}")


def headline(p: Project) -> dict:
    """The solution's headline numbers (a key file's columns): the links found, gamma_min [deg], the adjustable
    link's travel for the band, and the slider's v and a at the analysis' crank angle (exact)."""
    m = p.mechanism
    out = {k: round(float(m.params[k]), 6) for k in p.find}
    out["gamma_min_deg"] = round(math.degrees(m.gamma_min().value), 4)
    lo, hi = p.adjust.interval
    out["travel_from"], out["travel_to"] = round(float(min(lo, hi)), 6), round(float(max(lo, hi)), 6)
    v, a = p.computer_ram()
    out["v"], out["a"] = round(v, 6), round(a, 6)
    return out


# ---------------------------------------------------------------------------------------------------------- render


def _f(v, digits=4) -> str:
    return f"{v:.{digits}f}"


def _link_rows(p: Project, values: dict, what: str) -> list:
    return [(f"{k} [{p.units}]", p.spec.names[k], values[k], what) for k in values]


MARKS = (
    ("Design 1", "the links to find, with the method and the design's gamma_min", 20),
    ("Design 2", "the adjustable link's working range, its TR range and the travel for the band", 15),
    ("Discussion", "issues 1 to 4 (5 marks each)", 20),
    ("Analysis 1", "velocity and acceleration polygons drawn to scale; the slider's v and a", 20),
    ("Analysis 2", "the computer check: the program or command and its output beside the polygons", 10),
    ("Analysis 3", "x, v and a of the slider over a turn, plotted against theta2", 10),
    ("Presentation", "a drawing of the designed mechanism to scale; units, labels and a clear report", 5),
)


def _deliverables(p: Project) -> str:
    finds = " and ".join(p.find)
    items = (
        f"The values of {finds} (design requirement 1), how they were found, and the design's minimum "
        "transmission angle gamma_min over the whole turn; a drawing of the designed mechanism to scale.",
        f"The working range of {p.adjustable}, the TR range it gives, a plot of TR against {p.adjustable}, and "
        f"the travel of {p.adjustable} for TR {p.band[0]:.2f} to {p.band[1]:.2f} (design requirement 2).",
        "Answers to the four discussion issues, each with its reasoning.",
        "The velocity and acceleration polygons drawn to scale, with the slider's velocity and acceleration.",
        "The computer check: the program (or the command) and its output, beside the polygons' values.",
        "Plots of the slider's position, velocity and acceleration over a complete turn of the crank.",
    )
    listed = "".join(f"<li>{html.escape(i)}</li>" for i in items)
    return f"<h2>Deliverables</h2><p>Hand in one report, the project code on its first page, with:</p><ol>{listed}</ol>"


def _marks() -> str:
    rows = "".join(
        f"<tr><td>{html.escape(part)}</td><td>{html.escape(what)}</td><td>{m}</td><td></td></tr>"
        for part, what, m in MARKS
    )
    total = sum(m for *_, m in MARKS)
    return (
        "<h2>Marks</h2><table class='text marks'><tr><th>part</th><th>what is marked</th><th>marks</th>"
        f"<th>awarded</th></tr>{rows}<tr><th>Total</th><th></th><th>{total}</th><th></th></tr></table>"
    )


def _head(p: Project, due: str | None) -> str:
    blank = "<span class=blank></span>"
    due_text = html.escape(due) if due else blank
    return (
        f"<div class=head><h1>Quick-return project: {html.escape(p.spec.title)}</h1>"
        f"<p class=code>Project code <b>{html.escape(p.code)}</b></p></div>"
        f"<table class=fill><tr><th>Name</th><td>{blank}</td></tr><tr><th>Student number</th><td>{blank}</td></tr>"
        f"<tr><th>Due</th><td>{due_text}</td></tr></table>"
    )


def _statement(p: Project, due: str | None = None) -> str:
    from qropt.io.report import _png

    spec, u = p.spec, p.units
    deg = math.degrees(p.theta2)
    rows = _link_rows(p, p.given, "given: stays")
    if p.current is not None:
        rows += _link_rows(p, p.current, "current: to be redesigned")
    finds = " and ".join(f"{k} ({spec.names[k]})" for k in p.find)
    parts = [
        "<section class=statement>",
        _head(p, due),
        "<h2>Background</h2>",
        f"<p>An application requires a quick-return mechanism with a time ratio TR = {p.time_ratio:.3f} and a "
        f"stroke of {p.stroke:.4f} {u}. Currently a {html.escape(spec.title)} exists: "
        f"{html.escape(spec.layout)}. Its lengths:</p>",
        _text_table(["link", "what", "length", ""], rows),
    ]
    if p.current is not None:
        parts.append(f"<figure>{_png(_current_figure(p))}</figure>")
    parts += [
        f"<p>The given links are expensive to modify and stay. It is proposed to redesign {html.escape(finds)} so "
        f"that the mechanism performs the task. Furthermore, {p.adjustable} ({html.escape(spec.names[p.adjustable])}"
        ") should be adjustable for future modification to other TRs.</p>",
        "<h2>Design</h2><ol>",
        f"<li>Determine {html.escape(' and '.join(p.find))} satisfying TR = {p.time_ratio:.3f} and stroke = "
        f"{p.stroke:.4f} {u} while keeping the given links; where several designs do it, choose the one with the "
        "largest minimum transmission angle over the whole turn (gamma_min).</li>",
        f"<li>Determine the range of {p.adjustable} the adjustable link should accommodate to allow the maximum "
        f"number of TRs, and the travel of {p.adjustable} that covers every TR from {p.band[0]:.2f} to "
        f"{p.band[1]:.2f}.</li></ol>",
        "<h2>Discussion issues</h2><ol>" + "".join(f"<li>{html.escape(q)}</li>" for q in spec.issues) + "</ol>",
        f"<h2>Analysis</h2><p>For the mechanism with TR = {p.time_ratio:.3f} and stroke = {p.stroke:.4f} {u}:</p><ol>",
        f"<li>Evaluate the velocity and acceleration of the slider when theta2 = {deg:.0f} deg, using relative "
        f"motion analysis (polygons). Use omega2 = {p.omega2:g} rad/s (counter-clockwise) and alpha2 = 0 "
        "rad/s^2.</li>",
        "<li>Check this result by computer (e.g. <code>qropt analyze</code>).</li>",
        "<li>Simulate the mechanism for a complete revolution of the input crank: slider position, velocity and "
        "acceleration against the crank angle.</li></ol>",
        _deliverables(p),
        _marks(),
        "<p><small>Conventions: x to the right, y up, O2 at the origin, theta2 counter-clockwise from +x; "
        "TR = slow / fast crank interval between the dead centres. Write the project code on your report.</small></p>",
        "</section>",
    ]
    return "".join(parts)


def _text_table(head, rows) -> str:
    """``qropt.io.report._table`` with its text columns left-aligned."""
    from qropt.io.report import _table

    return _table(head, rows).replace("<table>", "<table class=text>", 1)


MIN_ASPECT, MAX_ASPECT = 0.45, 1.1  # the drawing's height over its width


def _current_figure(p: Project):
    """The existing mechanism at theta2 with its joints labelled apart, in a frame at least MIN_ASPECT and at most
    MAX_ASPECT as high as wide (a long slide line makes no thin strip, a tall lever no narrow column)."""
    from qropt.io import drawing, plots

    m = p.mechanism
    cur = type(m)(**{**m.params, **p.current}, units=m.units)
    shapes = drawing.at(drawing.scene(cur), p.theta2)
    x0, x1, y0, y1 = drawing.bounds(shapes)
    pad = 0.1 * max(x1 - x0, y1 - y0)
    w, h = x1 - x0 + 2 * pad, y1 - y0 + 2 * pad
    w, h = max(w, h / MAX_ASPECT), max(h, MIN_ASPECT * w)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    fig, ax = plots.plt.subplots(figsize=(8, 1.3 + 6.2 * h / w))
    plots.draw_shapes(ax, shapes)  # each joint named where its name covers no other name or joint
    ax.set_xlim(cx - w / 2, cx + w / 2)
    ax.set_ylim(cy - h / 2, cy + h / 2)
    ax.set_aspect("equal")
    ax.set_title(f"the existing {p.spec.title} at theta2 = {math.degrees(p.theta2):.0f} deg (current lengths)")
    ax.set_xlabel(f"x [{p.units}]")
    ax.set_ylabel(f"y [{p.units}]")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def _solution(p: Project) -> str:
    from qropt.io import plots
    from qropt.io.plots import polygon_figure
    from qropt.io.report import _png, _table

    spec, u, r, m = p.spec, p.units, p.result, p.mechanism
    g = m.gamma_min()
    c = r.certificate
    rows = [(f"{k} [{u}]", spec.names.get(k, ""), m.params[k]) for k in p.find]
    rows += [
        ("time ratio [-]", "target " + f"{p.time_ratio:.3f}", m.time_ratio()),
        (f"stroke [{u}]", "target " + f"{p.stroke:.4f}", m.stroke()),
        ("gamma_min [deg]", f"at theta2 = {math.degrees(g.theta2):.2f} deg, joint {g.joint}", math.degrees(g.value)),
    ]
    optima = [
        (o.status, *(o.params[k] for k in p.find), math.degrees(o.quantities["gamma_min"])) for o in r.local_optima
    ]
    parts = [
        "<section class=solution><h1>Worked solution</h1>",
        f"<p>Project code {html.escape(p.code)}: {p.kind}, seed {p.seed}"
        + (" with the instructor's secret" if p.keyed else " (an open project: the seed's draw, no secret)")
        + f"; {p.redraws} draw(s) rejected as not solvable before this one.</p>",
        "<h2>Design requirement 1</h2>",
        f"<p>Solved by qropt (the same solve as <code>qropt synth</code>): status <b>{html.escape(r.status)}</b>. "
        f"{html.escape(r.message)}</p>",
        _table(["quantity", "", "value"], rows),
        f"<p>Certificate: exact gamma_min over the whole turn {math.degrees(c.certified):.4f} deg, the NLP's value "
        f"agreeing to {c.gap:.2g} rad after {c.rounds} exchange round(s); local: {html.escape(c.local)}; "
        f"global: {html.escape(c.global_claim)}.</p>",
        "<p>Every certified local optimum (best first):</p>",
        _table(["status", *(f"{k} [{u}]" for k in p.find), "gamma_min [deg]"], optima),
    ]
    reach, adj = p.reach, p.adjust
    t = reach.time_ratio_range
    ivs = ", ".join(f"[{a:.4f}, {b:.4f}]" for a, b in reach.intervals)
    scan = _scan_bounds(type(m), m.params, p.adjustable, p.stroke)
    parts += [
        "<h2>Design requirement 2: the adjustable link</h2>",
        f"<p>With the other links as solved, {p.adjustable} works for {p.adjustable} in {ivs} {u} (scanned within "
        f"{scan[0]:.4g}..{scan[1]:.4g} "
        f"{u}): an adjustable link over this range allows the maximum number of TRs, from {t.low:.4f} "
        f"({p.adjustable} = {t.low_at:.4f} {u}) to {t.high:.4f} ({p.adjustable} = {t.high_at:.4f} {u}). "
        f"For TR {p.band[0]:.2f} to {p.band[1]:.2f}: {html.escape(adj.explanation)}.</p>",
        _png(plots.reachable_figure(reach, p.band)),
        "<h2>Discussion issues</h2><ol>",
    ]
    sols = reach.solutions(p.time_ratio)
    parts += [
        f"<li>{len(sols)} value(s) of {p.adjustable} give TR = {p.time_ratio:.3f} with the other links kept: "
        + ", ".join(f"{x:.4f} {u}" for x in sols)
        + f" (the TR against {p.adjustable} is the figure above: zero, one or more crossings of a level).</li>",
        f"<li>Adjusting {p.adjustable} over its working range gives {t.low:.4f} &lt;= TR &lt;= {t.high:.4f}.</li>",
        f"<li>{html.escape(p.spec.freedom)}</li>",
        f"<li>{html.escape(_issue4(p))}</li></ol>",
    ]
    rm = p.relative_motion()
    (vp, ap), (vc, ac) = p.polygon_ram(), p.computer_ram()
    deg = math.degrees(p.theta2)
    order = sorted(rm.table(), key=lambda e: e["quantity"] != "velocity")  # the velocity polygon first
    every = [
        (
            e["quantity"],
            e["joint"],
            e["term"],
            e["kind"],
            e["magnitude"],
            e["direction_deg"],
            "solved" if e["solved"] else "known",
        )
        for e in order
    ]
    check = [
        (f"slider velocity v [{u}/s]", vp, vc, vp - vc),
        (f"slider acceleration a [{u}/s^2]", ap, ac, ap - ac),
    ]
    for e in sorted(rm.equations, key=lambda e: e.quantity != "velocity"):
        polygon = float(np.hypot(*sum(t.vector for t in e.terms)))
        exact = float(np.hypot(*e.exact))
        unit = f"{u}/s^2" if e.quantity == "acceleration" else f"{u}/s"
        terms = " + ".join(t.name for t in e.terms)
        check.append((f"|{e.quantity} of {e.joint}| = |{terms}| [{unit}]", polygon, exact, polygon - exact))
    parts += [
        f"<h2>Analysis 1: relative motion at theta2 = {deg:.0f} deg, omega2 = {p.omega2:g} rad/s, alpha2 = 0</h2>",
        "<p>The vector equations written dyad by dyad in the order the mechanism is built (directions "
        "counter-clockwise from +x; 'known' from what came before or from a link's rate and length, 'solved' from "
        "the polygon):</p>",
        _table(["equation", "joint", "term", "kind", "magnitude", "direction [deg]", ""], every),
        _png(polygon_figure(rm, u)),
        "<h2>Analysis 2: the polygons checked by computer</h2>",
        f"<p>The sums of each equation's terms (polygons) beside the exact analysis (<code>{html.escape(_command(p))}"
        "</code> prints the same state):</p>",
        _table(["quantity", "polygons", "computer (exact)", "difference"], check),
        f"<h2>Analysis 3: a complete revolution at omega2 = {p.omega2:g} rad/s</h2>",
        _png(plots.cycle_figure(m, p.theta2, p.omega2)),
    ]
    th = np.radians(np.arange(0, 360, 30))
    mo = m.motion(th, p.omega2, 0.0)
    rows = [(f"{math.degrees(a):.0f}", x, v, acc) for a, x, v, acc in zip(th, mo.x, mo.v, mo.a, strict=True)]
    parts.append(_table(["theta2 [deg]", f"x [{u}]", f"v [{u}/s]", f"a [{u}/s^2]"], rows))
    return "".join(parts)


def _command(p: Project) -> str:
    m = p.mechanism
    flags = " ".join(f"--{k.replace('_', '-')} {v:.10g}" for k, v in m.params.items() if not (k == "h" and v == 0.0))
    return f"qropt analyze {p.kind} {flags} --theta2 {math.degrees(p.theta2):.0f}deg --omega2 {p.omega2:g}"


def _issue4(p: Project) -> str:
    r, m = p.result, p.mechanism
    found = len(r.local_optima)
    g = math.degrees(m.gamma_min().value)
    text = (
        f"The task's equations left {found} certified local optimum(s); the minimum transmission angle over the "
        f"whole turn (not only at the dead centres) isolates the design: gamma_min = {g:.2f} deg"
    )
    text += " (30 to 45 deg is the usual lower limit)." if g >= 30 else ", below the usual 30 to 45 deg limit: a "
    if g < 30:
        text += "better design needs other given links."
    return (
        text + " Size, the peak acceleration of the ram, the uniformity of the cutting speed and the adjustable "
        "link's travel are the other issues to weigh."
    )


PRINT_CSS = (
    "@page{size:A4;margin:18mm}"
    ".text td,.text th{text-align:left}.text td:nth-child(3),.text th:nth-child(3){text-align:right}"
    ".head h1{margin-bottom:.2em}.code{font-family:monospace;font-size:1.1em;margin:0 0 .6em}"
    ".fill th{text-align:left;width:9em}.fill td{text-align:left;width:22em;height:1.6em}"
    ".blank{display:inline-block;min-width:10em}.marks td:nth-child(4){width:5em}figure{margin:.6em 0}"
    "body{padding:0 12px}td,th{overflow-wrap:break-word}"
    ".solution{border-top:2px solid #999;margin-top:2em}.wide{overflow-x:auto}"
    "@media (max-width:600px){body{padding:0 6px}td,th{padding:.2em .35em;font-size:.92em}"
    ".fill td{width:auto}}"
    "@media print{body{max-width:none;margin:0;padding:0;font-size:10.5pt}"
    "img,figure,table,tr{break-inside:avoid;page-break-inside:avoid}"
    "h1,h2{break-after:avoid;page-break-after:avoid}"
    ".solution{break-before:page;page-break-before:always;border:0;margin:0}.wide{overflow:visible}}"
)


def _due(due) -> str | None:
    if due is None:
        return None
    import datetime

    if isinstance(due, datetime.date):
        return due.strftime("%Y-%m-%d")
    try:
        return datetime.date.fromisoformat(str(due)).isoformat()
    except ValueError:
        raise InvalidParameter(f"a due date is YYYY-MM-DD, got {due!r}") from None


def render(project: Project, solution: bool = False, due=None) -> str:
    """The project's page (one self-contained HTML document, pictures inline, A4 print margins): the statement
    (project code, blanks for name and student number, the due date ``due`` (YYYY-MM-DD) or a blank,
    deliverables and marks; no seed anywhere), and with ``solution`` its worked solution (which names the seed)."""
    from qropt.io.report import CSS

    if not isinstance(project, Project):
        raise InvalidParameter(f"render takes a classroom Project, got {type(project).__name__}")
    due = _due(due)
    worked = ""
    if solution:  # its wide tables scroll sideways on a phone, not the page
        worked = _solution(project).replace("<table>", "<div class=wide><table>").replace("</table>", "</table></div>")
    body = _statement(project, due) + (worked + "</section>" if solution else "")
    what = f"solution: {project.kind} seed {project.seed}," if solution else f"project: {project.spec.title},"
    title = f"qropt {what} code {project.code}"
    head = (
        "<meta charset='utf-8'><meta name='viewport' content='width=device-width, initial-scale=1'>"
        f"<title>{html.escape(title)}</title><style>{CSS}{PRINT_CSS}</style>"
    )
    return f"<!DOCTYPE html><html><head>{head}</head><body>{body}</body></html>\n"


__all__ = [
    "KINDS",
    "MARKS",
    "SPECS",
    "STROKE_RANGE",
    "Project",
    "Spec",
    "headline",
    "new_secret",
    "project",
    "render",
    "statement_code",
]
