"""Notebook representations: small, self-contained HTML for Jupyter's ``_repr_html_``.

Each function returns one ``<div class="qropt-nb ...">`` of a few kB to a few tens of kB: a table of the key numbers
and pictures as inline SVG (no scripts, no stylesheets, no external files or links, no element ids, only inline
styles, so that several outputs in one notebook cannot clash). Every text is escaped. Long tables show their first
``MAX_ROWS`` rows and say how many more there are. Angles are shown in degrees, lengths in the object's unit.

``mechanism_html``, ``result_html``, ``comparison_html``, ``front_html``, ``chart_html`` and ``family_html`` are what
``Mechanism``, ``Result``, ``Comparison``, ``Front``, ``Chart`` and ``Family`` show; ``mechanism_svg`` is the picture
alone (one scale for several pictures through ``px_per_unit``).
"""

from __future__ import annotations

import html
import math

import numpy as np

from qropt import units as units_
from qropt.errors import QroptError
from qropt.io import drawing
from qropt.io._labels import LINE_WEIGHTS, SOLIDS, place_labels

MAX_ROWS = 20  # table rows shown; the rest are counted
MAX_PICTURES = 12  # design pictures in a comparison
MAX_CELLS = 2000  # heat-map cells drawn (a larger chart is drawn by every k-th value of each axis)
MAX_CURVE = 400  # points of a family branch drawn
MARGIN = 22  # px around a mechanism picture (room for the joints' names)
NAME_CHAR, NAME_HEIGHT, NAME_GAPS = 8.4, 10.0, (2.0, 4.0, 8.0, 13.0)  # a joint's name at 12 px: its box, px
FONT = "font-family:sans-serif;font-size:12px"
INK, PATH, SLIDE, BAD = "#222", "#1f77b4", "#888", "#d62728"
VIRIDIS = ("#440154", "#3b528b", "#21918c", "#5ec962", "#fde725")


# ---- text --------------------------------------------------------------------------------------------------
def _e(text) -> str:
    return html.escape(str(text), quote=True)


def _g(v, digits: int = 6) -> str:
    """A number to ``digits`` significant digits; 'n/a' for None or nan."""
    if v is None or isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
        return "n/a" if v is None else str(v)
    v = float(v)
    return "n/a" if math.isnan(v) else f"{v:.{digits}g}"


def _deg(v, digits: int = 6) -> str:
    return "n/a" if v is None else f"{_g(math.degrees(v), digits)} deg"


def _at(theta) -> str:
    """A crank angle (rad) in degrees in [0, 360) to three decimals."""
    d = round(math.degrees(theta) % 360.0, 3) % 360.0
    return f"{d:.3f} deg"


def _short(text, n: int = 240) -> str:
    text = str(text)
    return text if len(text) <= n else text[: n - 3] + "..."


def _box(kind: str, *parts: str) -> str:
    return f'<div class="qropt-nb qropt-nb-{kind}" style="{FONT};line-height:1.35">' + "".join(parts) + "</div>"


def _title(text: str) -> str:
    return f'<div style="font-weight:bold;margin:2px 0 4px 0">{text}</div>'


def _kv(rows) -> str:
    """A two-column table of (name, value) rows; both are HTML already escaped."""
    body = "".join(
        f'<tr><th style="text-align:left;padding:1px 8px 1px 0;vertical-align:top;white-space:nowrap">{k}</th>'
        f'<td style="text-align:left;padding:1px 4px">{v}</td></tr>'
        for k, v in rows
    )
    return f'<table style="border-collapse:collapse;margin:0;max-width:640px">{body}</table>'


def _table(head, rows, total: int | None = None, align: str = "") -> str:
    """A table of escaped cells, column k aligned by align[k] ('l' left, 'r' right; default: the first column
    left, the others right); a last line counts the rows left out of ``total``."""
    cell = "padding:1px 6px;border-bottom:1px solid #ddd;text-align:{}"
    sides = [{"l": "left", "r": "right"}[a] for a in align.ljust(len(head), "r")] if align else []
    sides = sides or ["left"] + ["right"] * (len(head) - 1)
    th = "".join(f'<th style="{cell.format(side)}">{h}</th>' for h, side in zip(head, sides, strict=True))
    body = "".join(
        "<tr>"
        + "".join(f'<td style="{cell.format(side)}">{c}</td>' for c, side in zip(r, sides, strict=True))
        + "</tr>"
        for r in rows
    )
    more = ""
    if total is not None and total > len(rows):
        more = f'<div style="color:#666">... {total - len(rows)} more (of {total})</div>'
    return f'<table style="border-collapse:collapse;margin:2px 0">{th and f"<tr>{th}</tr>"}{body}</table>{more}'


def _note(text: str) -> str:
    return f'<div style="color:#666">{text}</div>'


def _flex(*parts: str) -> str:
    return '<div style="display:flex;flex-wrap:wrap;gap:14px;align-items:flex-start">' + "".join(parts) + "</div>"


# ---- numbers of a mechanism ----------------------------------------------------------------------------------
def _param_text(m, k: str, v: float) -> str:
    kind = m.kinds().get(k, "offset")
    if kind == "angle":
        return f"{_g(math.degrees(v))} deg"
    if kind == "branch":
        return f"{v:+g}"
    return f"{_g(v)} {m.units}"


def _params(m, params=None) -> str:
    """The parameters with their units; an offset below 1e-12 of the largest length is shown as 0 (rounding)."""
    params = dict(m.params if params is None else params)
    kinds = m.kinds()
    scale = max((abs(v) for k, v in params.items() if kinds.get(k) in ("length", "offset")), default=0.0)
    params = {k: 0.0 if kinds.get(k) == "offset" and abs(v) < 1e-12 * scale else v for k, v in params.items()}
    return ", ".join(f"{_e(k)} = {_e(_param_text(m, k, v))}" for k, v in params.items())


def _attempt(f):
    """f() or, for a qropt error, its message as an 'n/a' text (escaped)."""
    try:
        return f()
    except QroptError as e:
        return f"n/a ({_e(_short(e, 160))})"


def _mechanism_rows(m) -> list:
    follower = m.TRAVEL != "stroke"
    kind = type(m).__dict__.get("KIND") or ""
    rows = [
        ("type", _e(type(m).__name__) + (f" ({_e(kind)})" if kind else "")),
        ("parameters", _params(m)),
        ("time ratio", _attempt(lambda: f"{_g(m.time_ratio())} (slow / fast)")),
    ]
    if follower:
        rows.append(("swing", _attempt(lambda: _e(_deg(m.stroke())))))
    else:
        rows.append(("stroke", _attempt(lambda: f"{_g(m.stroke())} {_e(m.units)}")))

    def gamma():
        g = m.gamma_min()
        return f"{_deg(g.value)} (at theta2 = {_at(g.theta2)}, joint {_e(g.joint)})"

    def dead():
        d = m.dead_centres()
        x = (lambda v: _deg(v)) if follower else (lambda v: f"{_g(v)} {_e(m.units)}")
        return f"theta2 = {_at(d.theta_max)} (x_max {x(d.x_max)}), {_at(d.theta_min)} (x_min {x(d.x_min)})"

    rows += [("gamma_min", _attempt(gamma)), ("dead centres", _attempt(dead))]
    return rows


def _drawn_at(m) -> float:
    """A crank angle that shows the links apart: 30% into the working stroke (rad); 60 deg if there is none."""
    try:
        start, length = m.working_arc()
        return start + 0.3 * length
    except QroptError:
        return math.radians(60.0)


# ---- the mechanism picture -----------------------------------------------------------------------------------
def _extent(m, theta2: float) -> tuple:
    shapes = drawing.at(drawing.scene(m), theta2)
    return shapes, drawing.bounds(shapes)


def mechanism_svg(
    m,
    theta2: float | None = None,
    *,
    width: int = 340,
    height: int = 260,
    px_per_unit: float | None = None,
    labels: bool = True,
    color: str = INK,
) -> str:
    """The mechanism at crank angle theta2 (rad; default 30% into its working stroke) as inline SVG: its bodies,
    ground pivots (squares), joints (circles, named), the output's path over a turn and a scale bar in the
    mechanism's unit. It fits width x height px, or is drawn at ``px_per_unit`` (one scale for several pictures).
    A mechanism that cannot be drawn gives a note saying why instead."""
    theta2 = _drawn_at(m) if theta2 is None else float(theta2)
    try:
        shapes, (x0, x1, y0, y1) = _extent(m, theta2)
    except QroptError as e:
        return _note(f"no picture: {_e(_short(e))}")
    dx, dy = max(x1 - x0, 1e-12), max(y1 - y0, 1e-12)
    s = px_per_unit or min((width - 2 * MARGIN) / dx, (height - 2 * MARGIN - 14) / dy)
    w, h = dx * s + 2 * MARGIN, dy * s + 2 * MARGIN + 14  # 14 px below for the scale bar

    def xy(p):
        return f"{MARGIN + (p[0] - x0) * s:.1f},{MARGIN + (y1 - p[1]) * s:.1f}"

    def up(p):  # px, y up (as _labels.place_labels takes them)
        p = np.asarray(p, float).reshape(-1, 2)
        return np.c_[MARGIN + (p[:, 0] - x0) * s, -(MARGIN + (y1 - p[:, 1]) * s)]

    layers = {k: [] for k in ("path", "slide", "link", "plate", "slot", "block", "joint", "label")}
    names = []  # (name, (x, y) px with y up, marker radius px)
    for sh in shapes:
        pts = sh.points
        if sh.part == "path":
            layers["path"].append(
                f'<polyline points="{" ".join(xy(p) for p in _simplified(pts, s))}" fill="none" stroke="{PATH}" '
                'stroke-width="3" stroke-opacity="0.45"/>'
            )
        elif sh.part == "slide":
            layers["slide"].append(
                f'<polyline points="{xy(pts[0])} {xy(pts[1])}" stroke="{SLIDE}" stroke-dasharray="8 3 2 3"/>'
            )
        elif sh.part == "link":
            layers["link"].append(
                f'<polyline points="{xy(pts[0])} {xy(pts[1])}" stroke="{color}" stroke-width="3" '
                'stroke-linecap="round"/>'
            )
        elif sh.part == "plate":
            layers["plate"].append(
                f'<polygon points="{" ".join(map(xy, pts))}" fill="{color}" fill-opacity="0.2" stroke="{color}" '
                'stroke-width="2" stroke-linejoin="round"/>'
            )
        elif sh.part == "slot":
            layers["slot"].append(
                f'<polygon points="{" ".join(map(xy, pts))}" fill="none" stroke="{color}" stroke-width="1"/>'
            )
        elif sh.part in ("block", "ram"):
            layers["block"].append(
                f'<polygon points="{" ".join(map(xy, pts))}" fill="#fff" stroke="{color}" stroke-width="1.5"/>'
            )
        else:  # a ground pivot or a joint
            cx, cy = (float(v) for v in xy(pts[0]).split(","))
            if sh.part == "pivot":
                layers["joint"].append(f'<rect x="{cx - 4:.1f}" y="{cy - 4:.1f}" width="8" height="8" fill="{color}"/>')
            else:
                layers["joint"].append(
                    f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="3.2" fill="#fff" stroke="{color}" stroke-width="1.5"/>'
                )
            names.append((sh.name, (cx, -cy), 4 * math.sqrt(2) if sh.part == "pivot" else 4.0))
    if labels and names:
        layers["label"] = _names(names, shapes, up, (0.0, 14.0 - h, w, 0.0), color)  # above the scale bar
    bar = _scale_bar(s, dx, h, m.units)
    label = f"{type(m).__name__} at theta2 = {math.degrees(theta2):.1f} deg"
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w:.0f}" height="{h:.0f}" viewBox="0 0 {w:.1f} {h:.1f}" '
        f'role="img" aria-label="{_e(label)}" style="background:#fff;{FONT}" font-size="10" fill="none">'
        f"<title>{_e(label)}</title>" + "".join("".join(v) for v in layers.values()) + bar + "</svg>"
    )


def _names(names, shapes, up, frame, color) -> list:
    """The joints' names as SVG texts, each beside its joint where ``_labels.place_labels`` finds room (px, y up
    from ``up``; the text's box estimated from NAME_CHAR and NAME_HEIGHT)."""
    lines = [
        (up([*sh.points, sh.points[0]] if sh.kind == "polygon" else sh.points), LINE_WEIGHTS[sh.part])
        for sh in shapes
        if sh.part in LINE_WEIGHTS
    ]
    placed = place_labels(
        [at for _, at, _ in names],
        [(NAME_CHAR * len(name) + 2.0, NAME_HEIGHT) for name, _, _ in names],
        [r for _, _, r in names],
        NAME_GAPS,
        lines,
        [up(sh.points) for sh in shapes if sh.part in SOLIDS],
        frame,
    )
    return [
        f'<text x="{x0 + 1.0:.1f}" y="{-y0 - 1.0:.1f}" stroke="#fff" stroke-width="3" paint-order="stroke" '
        f'fill="{color}">{_e(name)}</text>'
        for (name, _, _), (_, _, (x0, y0, _, _)) in zip(names, placed, strict=True)
    ]


def _simplified(points, s: float, tol_px: float = 0.3) -> list:
    """The polyline's points without those within tol_px of the segment between kept neighbours (Douglas-Peucker;
    a path that goes back and forth along a line keeps its turning points)."""
    p = np.asarray(points, float) * s
    keep = np.zeros(len(p), bool)
    keep[[0, -1]] = True
    stack = [(0, len(p) - 1)]
    while stack:
        a, b = stack.pop()
        if b <= a + 1:
            continue
        seg, rel = p[b] - p[a], p[a + 1 : b] - p[a]
        n2 = float(seg @ seg)
        t = np.clip(rel @ seg / n2, 0.0, 1.0) if n2 > 0 else np.zeros(len(rel))  # distance to the segment
        d = np.nan_to_num(np.hypot(*(rel - t[:, None] * seg).T))
        k = int(np.argmax(d)) if d.size else -1
        if d.size and d[k] > tol_px:
            keep[a + 1 + k] = True
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return [tuple(q) for q in np.asarray(points, float)[keep]]


def _nice(v: float) -> float:
    """The largest 1, 2 or 5 times a power of ten not above v."""
    e = 10.0 ** math.floor(math.log10(v))
    return max(k * e for k in (1, 2, 5) if k * e <= v * (1 + 1e-12))


def _scale_bar(s: float, dx: float, h: float, unit: str) -> str:
    length = _nice(dx / 4)
    x, y, w = MARGIN, h - 8, length * s
    return (
        f'<polyline points="{x:.1f},{y - 3:.1f} {x:.1f},{y:.1f} {x + w:.1f},{y:.1f} {x + w:.1f},{y - 3:.1f}" '
        f'stroke="#555"/><text x="{x + w + 4:.1f}" y="{y + 3:.1f}" fill="#555">{_g(length)} {_e(unit)}</text>'
    )


# ---- plots ---------------------------------------------------------------------------------------------------
def _ticks(lo: float, hi: float, n: int = 5) -> list:
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return []
    if hi <= lo:
        return [lo]
    step = _nice((hi - lo) / n)
    if (hi - lo) / step > n + 1:
        step *= 2
    start = math.ceil(lo / step - 1e-9) * step
    return [start + k * step for k in range(int((hi - start) / step + 1e-9) + 1)]


def _plot(series, xlabel: str, ylabel: str, width: int = 420, height: int = 280, title: str = "") -> str:
    """An SVG plot. series: dicts with 'x', 'y' (sequences), 'mode' ('line', 'dots' or 'marks': crosses),
    'color', optional 'label' (the legend) and 'tips' (a tooltip per point); labels are plain text."""
    xs = np.concatenate([np.asarray(d["x"], float) for d in series]) if series else np.zeros(0)
    ys = np.concatenate([np.asarray(d["y"], float) for d in series]) if series else np.zeros(0)
    ok = np.isfinite(xs) & np.isfinite(ys)
    if not ok.any():
        xs, ys, ok = np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.array([True, True])
    x0, x1, y0, y1 = xs[ok].min(), xs[ok].max(), ys[ok].min(), ys[ok].max()
    padx, pady = (x1 - x0) * 0.05 or max(abs(x0) * 0.05, 1e-9), (y1 - y0) * 0.05 or max(abs(y0) * 0.05, 1e-9)
    x0, x1, y0, y1 = x0 - padx, x1 + padx, y0 - pady, y1 + pady
    left, right, top, bottom = 62, 12, 22 if title else 10, 40
    pw, ph = width - left - right, height - top - bottom

    def X(v):
        return left + (v - x0) / (x1 - x0) * pw

    def Y(v):
        return top + (y1 - v) / (y1 - y0) * ph

    out = [f'<rect x="{left}" y="{top}" width="{pw}" height="{ph}" stroke="#999" fill="none"/>']
    for t in _ticks(x0, x1):
        out.append(
            f'<line x1="{X(t):.1f}" y1="{top + ph}" x2="{X(t):.1f}" y2="{top + ph + 4}" stroke="#999"/>'
            f'<text x="{X(t):.1f}" y="{top + ph + 15}" text-anchor="middle">{_g(t, 4)}</text>'
        )
    for t in _ticks(y0, y1):
        out.append(
            f'<line x1="{left - 4}" y1="{Y(t):.1f}" x2="{left}" y2="{Y(t):.1f}" stroke="#999"/>'
            f'<text x="{left - 6}" y="{Y(t) + 4:.1f}" text-anchor="end">{_g(t, 4)}</text>'
        )
    out.append(f'<text x="{left + pw / 2:.1f}" y="{height - 6}" text-anchor="middle">{_e(xlabel)}</text>')
    out.append(
        f'<text transform="translate(13,{top + ph / 2:.1f}) rotate(-90)" text-anchor="middle">{_e(ylabel)}</text>'
    )
    if title:
        out.append(f'<text x="{left}" y="14" font-weight="bold">{_e(title)}</text>')
    legend = []
    for d in series:
        pts = [(X(a), Y(b)) for a, b in zip(d["x"], d["y"], strict=True) if math.isfinite(a) and math.isfinite(b)]
        c, mode, tips = d.get("color", PATH), d.get("mode", "line"), d.get("tips")
        if mode == "line" and len(pts) > 1:
            out.append(
                f'<polyline points="{" ".join(f"{a:.1f},{b:.1f}" for a, b in pts)}" fill="none" stroke="{c}" '
                'stroke-width="1.5"/>'
            )
        for k, (a, b) in enumerate(pts if mode != "line" else ()):
            tip = f"<title>{_e(tips[k])}</title>" if tips else ""
            if mode == "marks":
                out.append(
                    f'<path d="M{a - 5:.1f},{b - 5:.1f}l10,10m0,-10l-10,10" stroke="{c}" stroke-width="2">{tip}</path>'
                )
            else:
                out.append(f'<circle cx="{a:.1f}" cy="{b:.1f}" r="3.5" fill="{c}" stroke="#fff">{tip}</circle>')
        if d.get("label"):
            legend.append((c, d["label"]))
    x, y = 8, height + 6  # the legend, in rows below the axis label
    for c, text in legend:
        need = 24 + 6.2 * len(text)
        if x > 8 and x + need > width:
            x, y = 8, y + 15
        out.append(
            f'<rect x="{x:.1f}" y="{y}" width="9" height="9" fill="{c}"/>'
            f'<text x="{x + 13:.1f}" y="{y + 9}">{_e(text)}</text>'
        )
        x += need
    height = y + 18 if legend else height
    return (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" '
        f'role="img" aria-label="{_e(f"{ylabel} against {xlabel}")}" style="background:#fff;{FONT}" font-size="11" '
        f'fill="#333">' + "".join(out) + "</svg>"
    )


def _viridis(t: float) -> str:
    if not math.isfinite(t):
        return "#e6e6e6"
    t = min(max(t, 0.0), 1.0) * (len(VIRIDIS) - 1)
    k = min(int(t), len(VIRIDIS) - 2)
    a, b = (np.array([int(c[i : i + 2], 16) for i in (1, 3, 5)]) for c in VIRIDIS[k : k + 2])
    r = a + (b - a) * (t - k)
    return "#" + "".join(f"{int(round(v)):02x}" for v in r)


# ---- the six objects -----------------------------------------------------------------------------------------
def mechanism_html(m, theta2: float | None = None) -> str:
    """A mechanism: its picture at theta2 (rad; default 30% into the working stroke) and its key numbers."""
    theta2 = _drawn_at(m) if theta2 is None else float(theta2)
    head = _title(f"{_e(type(m).__name__)} (lengths in {_e(m.units)}, drawn at theta2 = {_deg(theta2, 4)})")
    return _box("mechanism", head, _flex(mechanism_svg(m, theta2), _kv(_mechanism_rows(m))))


def _objective_text(r) -> str:
    v, q, u = r.objective, r.quantities, r.units
    if v is None:
        return "none (a feasibility problem or no design)"
    close = (lambda a: isinstance(a, (int, float)) and abs(a - v) <= 1e-9 * max(1.0, abs(v))) if q else None
    if close and close(q.get("gamma_min")):
        return f"{_g(v, 10)} rad = {_deg(v)} (gamma_min)"
    if close and close(q.get("size")):
        return f"{_g(v, 10)} {_e(u)} (size)"
    if close and close(q.get("peak_accel")):
        return f"{_g(v, 10)} {_e(units_.named('length/s^2', u))} (peak acceleration)"
    if close and close(q.get("peak_velocity")):
        return f"{_g(v, 10)} {_e(units_.named('length/s', u))} (peak working velocity)"
    return _g(v, 10)


def _quantity_rows(r) -> list:
    from qropt.synthesis import criteria

    q, u, rows = r.quantities, r.units, []
    if "time_ratio" in q:
        rows.append(("time ratio", f"{_g(q['time_ratio'])} (slow / fast)"))
    if "stroke" in q:
        rows.append(("stroke", f"{_g(q['stroke'])} {_e(u)}"))
    if "swing" in q:
        rows.append(("swing", _deg(q["swing"])))
    if "gamma_min" in q:
        rows.append(("gamma_min", _deg(q["gamma_min"])))
    w = r.stats.get("omega2", 1.0)
    for k, unit in (("peak_accel", "length/s^2"), ("peak_velocity", "length/s")):
        if isinstance(q.get(k), (int, float)):
            rows.append((k.replace("_", " "), f"{_g(q[k])} {_e(units_.named(unit, u))} at omega2 = {_g(w)} rad/s"))
    if isinstance(q.get("size"), (int, float)):
        rows.append(("size", f"{_g(q['size'])} {_e(u)}"))
    for name, c in criteria.CRITERIA.items():  # registered criteria beyond the built-in ones
        if name not in criteria.BUILT_IN and isinstance(q.get(name), (int, float)):
            shown = _deg(q[name]) if c.unit == "rad" else f"{_g(q[name])} {_e(units_.named(c.unit, u))}"
            rows.append((_e(name), shown))
    extra = [q[k] for k in ("grashof", "working_direction") if q.get(k)]
    if extra:
        rows.append(("class, working stroke", _e(", ".join(map(str, extra)))))
    return rows


def _status(status: str, success: bool) -> str:
    c = "#1a7f37" if success else BAD
    return f'<span style="color:#fff;background:{c};padding:0 5px;border-radius:3px">{_e(status)}</span>'


def result_html(r) -> str:
    """A synthesis Result: status, message, objective, design, quantities, counterweight, certificate, picture."""
    rows = [("status", f"{_status(r.status, r.success)} {_e(_short(r.message, 400))}")]
    rows.append(("objective", _objective_text(r)))
    if r.params:
        rows.append(("design", _params(r.mechanism, r.params) if r.mechanism is not None else _e(_plain(r.params))))
    rows += _quantity_rows(r)
    if r.counterweight is not None:
        cw = r.counterweight
        rows.append(("counterweight", f"{_g(cw.mass)} kg at {_g(cw.radius)} m, {_deg(cw.angle, 5)} from the crank pin"))
    c = r.certificate
    if c is not None:
        rows.append(("global claim", _e(_short(c.global_claim or "none", 400))))
        rows.append(
            (
                "certificate",
                f"exact: {'yes' if c.exact else 'no'}, gap {c.gap:.1e} after {c.rounds} round(s); "
                f"{_e(_short(c.local))}",
            )
        )
    if r.local_optima:
        rows.append(("local optima", str(len(r.local_optima))))
    if r.reachable:
        rows.append(("reachable", ", ".join(f"{_e(k)} {_g(lo)} .. {_g(hi)}" for k, (lo, hi) in r.reachable.items())))
    rows.append(("max violation", f"{r.max_violation:.1e}"))
    picture = mechanism_svg(r.mechanism) if r.mechanism is not None else ""
    return _box("result", _title(f"Result: {_e(r.status)}"), _flex(_kv(rows), picture))


def _plain(params) -> str:
    return ", ".join(f"{k} = {_g(v)}" for k, v in params.items())


def comparison_html(c) -> str:
    """A type comparison: the ranked table (gamma_min in degrees, each criterion in its unit) and every design
    drawn, each to its own scale (its scale bar says how large)."""
    from qropt.synthesis import criteria

    u = criteria.units(c.units)
    head = ["#", "type", "status", "gamma_min [deg]", f"footprint [{u['footprint']}]"]
    head += [f"peak accel [{u['peak_accel']}]", f"peak velocity [{u['peak_velocity']}]", "parameters"]
    rows = []
    for k, r in enumerate(c.rows[:MAX_ROWS]):
        if not r.success:
            rows.append([str(k + 1), _e(r.type), _e(r.result.status), f"no design: {_e(_short(r.reason))}", "", "", ""])
            rows[-1].append("")
            continue
        q = r.criteria
        rows.append(
            [
                str(k + 1),
                _e(r.type),
                _e(r.result.status),
                _g(math.degrees(q["gamma_min"]), 4) if q.get("gamma_min") is not None else "n/a",
                _g(q.get("footprint"), 4),
                _g(q.get("peak_accel"), 4),
                _g(q.get("peak_velocity"), 4),
                _params(r.result.mechanism, {p: v for p, v in r.result.params.items() if not p.startswith("sigma")}),
            ]
        )
    title = (
        f"Comparison: TR {_g(c.time_ratio)}, stroke {_g(c.stroke)} {_e(c.units)}, best by {_e(c.objective)} first "
        f"(omega2 = {_g(c.omega2)} rad/s)"
    )
    parts = [_title(title), _table([_e(h) for h in head], rows, len(c.rows), align="rllrrrrl")]
    drawn = [r for r in c.rows if r.success][:MAX_PICTURES]
    if drawn:
        pics = [
            f'<div><div style="font-size:11px">{k + 1}. {_e(r.type)}</div>'
            f"{mechanism_svg(r.result.mechanism, width=230, height=190, labels=False)}</div>"
            for k, r in enumerate(drawn)
        ]
        parts.append(_note(f"each design 30% into its working stroke, to its own scale (the bar, in {_e(c.units)})"))
        parts.append(_flex(*pics))
    if c.fronts:
        fronts = [
            f"{_e(k)}: " + (_e(_short(f, 120)) if isinstance(f, str) else f"{len(f.points)} points")
            for k, f in c.fronts.items()
        ]
        parts.append(_note("fronts: " + "; ".join(fronts)))
    return _box("comparison", *parts)


def _criterion(q: str, unit: str) -> tuple:
    """(to display, axis label) of a criterion: gamma_min in degrees, the others in their unit."""
    from qropt.synthesis import criteria

    if q == "gamma_min":
        return math.degrees, "gamma_min [deg]"
    return (lambda v: v), f"{q} [{criteria.units(unit).get(q, '')}]"


def front_html(f) -> str:
    """A trade-off front: the non-dominated points as a scatter in the two criteria (with units) and a table."""
    a, b = f.criteria
    u = f.problem.units
    fa, la = _criterion(a, u)
    fb, lb = _criterion(b, u)
    xs = [fa(v) for v, _ in f.values]
    ys = [fb(v) for _, v in f.values]
    tips = [f"{k + 1}: {a} {_g(x, 5)}, {b} {_g(y, 5)}" for k, (x, y) in enumerate(zip(xs, ys, strict=True))]
    series = [
        {"x": xs, "y": ys, "mode": "line", "color": PATH},
        {"x": xs, "y": ys, "mode": "dots", "color": PATH, "label": f"non-dominated ({len(xs)})", "tips": tips},
    ]
    svg = _plot(series, la, lb, title=f"{f.objectives[0]} vs {f.objectives[1]}")
    free = list(f.problem.free)
    head = ["#", _e(la), _e(lb), "status", *(f"{_e(k)} [{_e(u)}]" for k in free)]
    rows = [
        [str(k + 1), _g(x), _g(y), _e(r.status), *(_g(r.params.get(p)) for p in free)]
        for k, (x, y, r) in enumerate(zip(xs, ys, f.points, strict=True))
    ][:MAX_ROWS]
    name = f.problem.name or f.problem.mechanism.__name__
    title = (
        f"Front of {_e(name)}: {len(f.points)} non-dominated points, {len(f.removed)} removed "
        f"(dominated or without a design)"
    )
    return _box("front", _title(title), _flex(svg, _table(head, rows, len(f.points))))


def chart_html(ch) -> str:
    """A design chart: the objective over the grid as a heat map (gamma_min in degrees; grey: no design) and a
    compact table of its first cells."""
    values, label = ch.panel("objective")
    xs, xlabel = ch.x.shown(ch.problem)
    ys, ylabel = ch.y.shown(ch.problem) if ch.y is not None else (np.zeros(1), "")
    ny, nx = values.shape
    step = max(1, math.ceil(math.sqrt(nx * ny / MAX_CELLS)))
    ii, jj = np.arange(0, nx, step), np.arange(0, ny, step)
    cw = max(4, min(40, 360 // len(ii)))
    chh = max(4, min(40, 240 // len(jj)))
    left, top, bottom = 62, 22, 40
    w, h = left + cw * len(ii) + 80, top + chh * len(jj) + bottom
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
    span = hi - lo or 1.0
    tips = nx * ny <= 400
    out = []
    for b, j in enumerate(jj):
        for a, i in enumerate(ii):
            v = values[j, i]
            tip = ""
            if tips:
                yv = f", {ylabel} {_g(ys[j], 5)}" if ch.y is not None else ""
                tip = f"<title>{_e(f'{xlabel} {_g(xs[i], 5)}{yv}: {label} {_g(v, 5)}')}</title>"
            y = top + (len(jj) - 1 - b) * chh  # y grows upwards
            out.append(
                f'<rect x="{left + a * cw}" y="{y}" width="{cw}" height="{chh}" fill="{_viridis((v - lo) / span)}">'
                f"{tip}</rect>"
            )
    for a in _index_ticks(len(ii)):
        x = left + (a + 0.5) * cw
        out.append(f'<text x="{x:.1f}" y="{top + chh * len(jj) + 14}" text-anchor="middle">{_g(xs[ii[a]], 4)}</text>')
    if ch.y is not None:
        for b in _index_ticks(len(jj)):
            y = top + (len(jj) - 1 - b + 0.5) * chh + 4
            out.append(f'<text x="{left - 5}" y="{y:.1f}" text-anchor="end">{_g(ys[jj[b]], 4)}</text>')
        out.append(
            f'<text transform="translate(13,{top + chh * len(jj) / 2:.1f}) rotate(-90)" text-anchor="middle">'
            f"{_e(ylabel)}</text>"
        )
    out.append(
        f'<text x="{left + cw * len(ii) / 2:.1f}" y="{h - 6}" text-anchor="middle">{_e(xlabel)}</text>'
        f'<text x="{left}" y="14" font-weight="bold">{_e(label)}</text>'
    )
    lx = left + cw * len(ii) + 14  # the colour scale
    for k in range(10):
        out.append(
            f'<rect x="{lx}" y="{top + (9 - k) * 12}" width="12" height="12" fill="{_viridis((k + 0.5) / 10)}"/>'
        )
    out.append(
        f'<text x="{lx + 16}" y="{top + 10}">{_g(hi, 4)}</text><text x="{lx + 16}" y="{top + 120}">{_g(lo, 4)}</text>'
        f'<rect x="{lx}" y="{top + 128}" width="12" height="12" fill="#e6e6e6"/>'
        f'<text x="{lx + 16}" y="{top + 138}">none</text>'
    )
    svg = (
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" role="img" '
        f'aria-label="{_e(label)}" style="background:#fff;{FONT}" font-size="11" fill="#333">' + "".join(out) + "</svg>"
    )
    free = list(ch.problem.free)
    head = [_e(xlabel)] + ([_e(ylabel)] if ch.y is not None else []) + ["status", _e(label)]
    head += [f"{_e(k)} [{_e(ch.problem.units)}]" for k in free]
    rows = []
    for c in ch.cells[:MAX_ROWS]:
        v = values[c.j, c.i]
        row = [_g(xs[c.i], 5)] + ([_g(ys[c.j], 5)] if ch.y is not None else [])
        rows.append(row + [_e(c.status), _g(v), *(_g(c.params.get(k)) if c.success else "" for k in free)])
    s = ch.stats
    name = ch.problem.name or ch.problem.mechanism.__name__
    title = (
        f"Chart of {_e(name)} ({_e(ch.problem.mechanism.__name__)}, {_e(ch.problem.objective)}): {nx} x {ny} cells, "
        f"{s.get('certified', '?')} certified, {s.get('no_design', '?')} without a design"
    )
    shown = "" if step == 1 else _note(f"every {step}th value of each axis drawn")
    return _box("chart", _title(title), _flex(svg + shown, _table(head, rows, len(ch.cells))))


def _index_ticks(n: int, most: int = 6) -> list:
    return sorted(set(np.linspace(0, n - 1, min(n, most)).round().astype(int).tolist()))


def family_html(f) -> str:
    """A family of designs: every branch as a curve in the plane of two free parameters, its folds and ends, and
    a table of points spread along it."""
    free = list(f.problem.free)
    u = f.problem.units
    x = f.along
    y = next((k for k in free if k != x), x)
    series = []
    for k, b in enumerate(f.branches):
        step = max(1, math.ceil(len(b) / MAX_CURVE))
        pts = list(b[::step]) + ([b[-1]] if (len(b) - 1) % step else [])
        label = f"branch {k + 1} ({len(b)} points)" if len(f.branches) <= 6 else ""
        series.append(
            {
                "x": [p.params[x] for p in pts],
                "y": [p.params[y] for p in pts],
                "mode": "line",
                "color": VIRIDIS[k % 4],
                "label": label,
            }
        )
    if f.folds:
        tips = [f"fold: {x} = {_g(fd[x])}, {y} = {_g(fd[y])}" for fd in f.folds]
        series.append(
            {
                "x": [fd[x] for fd in f.folds],
                "y": [fd[y] for fd in f.folds],
                "mode": "marks",
                "color": BAD,
                "label": f"fold ({len(f.folds)})",
                "tips": tips,
            }
        )
    if f.ends:
        tips = [f"end: {_short(e.reason, 120)}" for e in f.ends]
        series.append(
            {
                "x": [e.params[x] for e in f.ends],
                "y": [e.params[y] for e in f.ends],
                "mode": "dots",
                "color": INK,
                "label": f"end ({len(f.ends)})",
                "tips": tips,
            }
        )
    svg = _plot(series, f"{x} [{u}]", f"{y} [{u}]", title=f"{f.problem.mechanism.__name__} family")
    pts = f.points()
    picks = [pts[i] for i in np.linspace(0, len(pts) - 1, min(len(pts), MAX_ROWS)).round().astype(int)] if pts else []
    head = ["arclength", *(f"{_e(k)} [{_e(u)}]" for k in free), "time ratio", "gamma_min [deg]"]
    rows = []
    for p in picks:
        q = p.quantities
        g = _g(math.degrees(q["gamma_min"]), 5) if "gamma_min" in q else "n/a"
        rows.append([_g(p.arclength, 5), *(_g(p.params[k]) for k in free), _g(q.get("time_ratio")), g])
    name = f.problem.name or f.problem.mechanism.__name__
    title = (
        f"Family of {_e(name)} along {_e(x)}: {len(f.branches)} branch(es), {len(pts)} points, "
        f"{len(f.folds)} fold(s), {len(f.ends)} end(s)"
    )
    table = _table(head, rows)
    if len(pts) > len(picks):
        table += _note(f"{len(picks)} of {len(pts)} points, spread along the family")
    ends = [f"end {k + 1}: {_e(_short(e.reason, 160))}" for k, e in enumerate(f.ends[:MAX_ROWS])]
    folds = [f"fold {k + 1}: {_e(x)} = {_g(fd[x])} {_e(u)}" for k, fd in enumerate(f.folds[:MAX_ROWS])]
    return _box("family", _title(title), _flex(svg, table), _note("<br>".join(folds + ends)))


__all__ = [
    "MAX_ROWS",
    "mechanism_svg",
    "mechanism_html",
    "result_html",
    "comparison_html",
    "front_html",
    "chart_html",
    "family_html",
]
