"""What leaves qropt for CAD and other tools: the mechanism at one crank angle as DXF (ezdxf) or SVG, and a
design file (JSON) that ``load_design`` and ``qropt analyze --from`` read back.

Drawings are in the mechanism's own length unit, x right and y up (the SVG flips y for the screen). Layers:
LINKS (link centre lines at their true lengths), PIVOTS (ground pivots O2, O4), JOINTS (moving joints),
SLIDE_LINE and SLIDER_PATH (the output joint's path over a turn).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from xml.sax.saxutils import escape

import numpy as np

from qropt.errors import InvalidParameter, QroptError
from qropt.mechanisms import FourBar, Mechanism, mechanism_type

LAYERS = {"LINKS": 7, "PIVOTS": 1, "JOINTS": 5, "SLIDE_LINE": 8, "SLIDER_PATH": 4}  # name -> DXF colour
GROUND = ("O2", "O4")


def link_segments(points: dict) -> list[tuple[str, str]]:
    """Joint pairs joined by a link at one configuration: crank, coupler, follower or slotted lever, rod.

    A slotted lever runs from O4 through the crank-pin block at A to the farther of A and C."""
    segs = [("O2", "A")]
    if "B" in points:
        segs += [("A", "B"), ("O4", "B"), ("O4", "C")]
    elif "O4" in points:
        a, c, o = (np.asarray(points[k], float) for k in ("A", "C", "O4"))
        segs += [("O4", "A" if np.hypot(*(a - o)) > np.hypot(*(c - o)) else "C")]
    segs += [("C", "D")] if "D" in points else [("A", "C")] if "O4" not in points else []
    return [(a, b) for a, b in segs if a in points and b in points]


def geometry(m: Mechanism, theta2: float = 0.0, n: int = 361) -> dict:
    """Layer -> primitives of m at crank angle theta2 (rad): ('line', p, q), ('circle', centre, r) or
    ('polyline', points)."""
    pts = {k: tuple(float(c) for c in v[0]) for k, v in m.positions(np.array([theta2])).points.items()}
    scale = max(np.ptp([p[0] for p in pts.values()]), np.ptp([p[1] for p in pts.values()]), 1e-12)
    out = {name: [] for name in LAYERS}
    out["LINKS"] = [("line", pts[a], pts[b]) for a, b in link_segments(pts)]
    for k, p in pts.items():
        out["PIVOTS" if k in GROUND else "JOINTS"].append(("circle", p, 0.015 * scale))
    if not isinstance(m, FourBar):
        out_joint = "D" if "D" in pts else "C"
        path = m.positions(np.linspace(0.0, 2 * math.pi, n)).points[out_joint]
        out["SLIDER_PATH"] = [("polyline", [tuple(map(float, q)) for q in path])]
        if np.ptp(path[:, 1]) <= 1e-9 * scale:
            pad = 0.15 * scale
            y = float(path[0, 1])
            out["SLIDE_LINE"] = [("line", (float(path[:, 0].min()) - pad, y), (float(path[:, 0].max()) + pad, y))]
    return out


def _path(path, suffix: str) -> Path:
    p = Path(path)
    if p.suffix.lower() != suffix:
        raise InvalidParameter(f"{path}: expected a {suffix} file")
    return p


def to_dxf(m: Mechanism, path, theta2: float = 0.0) -> None:
    """The mechanism at theta2 (rad) as a DXF drawing in its own length unit, one layer per kind of entity."""
    import ezdxf

    p = _path(path, ".dxf")
    doc = ezdxf.new("R2010")
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    for layer, items in geometry(m, theta2).items():
        for kind, *args in items:
            attribs = {"layer": layer}
            if kind == "line":
                msp.add_line(args[0], args[1], dxfattribs=attribs)
            elif kind == "circle":
                msp.add_circle(args[0], args[1], dxfattribs=attribs)
            else:
                msp.add_lwpolyline(args[0], dxfattribs=attribs)
    doc.saveas(p)


def to_svg(m: Mechanism, path, theta2: float = 0.0) -> None:
    """The same drawing as SVG: one group per layer, lengths in the mechanism's unit (y up, flipped for screens)."""
    p = _path(path, ".svg")
    geo = geometry(m, theta2)
    xs = [c for items in geo.values() for _, *a in items for c in _coords(a)[0]]
    ys = [c for items in geo.values() for _, *a in items for c in _coords(a)[1]]
    pad = 0.05 * max(max(xs) - min(xs), max(ys) - min(ys))
    x0, x1, y0, y1 = min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad
    width = (x1 - x0) / 200  # stroke widths relative to the drawing
    colours = {"LINKS": "black", "PIVOTS": "red", "JOINTS": "blue", "SLIDE_LINE": "gray", "SLIDER_PATH": "teal"}
    body = []
    for layer, items in geo.items():
        parts = []
        for kind, *a in items:
            if kind == "line":
                (ax, ay), (bx, by) = a
                parts.append(f'<line x1="{ax:.12g}" y1="{ay:.12g}" x2="{bx:.12g}" y2="{by:.12g}"/>')
            elif kind == "circle":
                (cx, cy), r = a
                parts.append(f'<circle cx="{cx:.12g}" cy="{cy:.12g}" r="{r:.12g}" fill="none"/>')
            else:
                d = " ".join(f"{x:.9g},{y:.9g}" for x, y in a[0])
                parts.append(f'<polyline points="{d}" fill="none"/>')
        body.append(f'<g id="{layer}" stroke="{colours[layer]}" stroke-width="{width:.6g}">' + "".join(parts) + "</g>")
    title = escape(f"{m!r} at theta2 = {math.degrees(theta2):.6g} deg")
    svg = (
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0:.12g} {-y1:.12g} {x1 - x0:.12g} {y1 - y0:.12g}">'
        f'<title>{title}</title><g transform="scale(1,-1)">{"".join(body)}</g></svg>\n'
    )
    p.write_text(svg)


def _coords(args):
    if isinstance(args[0], list):
        return [q[0] for q in args[0]], [q[1] for q in args[0]]
    if len(args) == 2 and isinstance(args[1], tuple):
        return [args[0][0], args[1][0]], [args[0][1], args[1][1]]
    (cx, cy), r = args
    return [cx - r, cx + r], [cy - r, cy + r]


def save_design(m: Mechanism, path, **extra) -> None:
    """A design file: the type (kind), every parameter, the units, and any extra JSON-ready fields."""
    p = _path(path, ".json")
    d = {"type": m.KIND, "params": dict(m.params), "units": "lengths in one consistent unit, angles in rad", **extra}
    p.write_text(json.dumps(d, indent=2, allow_nan=False) + "\n")


def load_design(path) -> Mechanism:
    """The mechanism of a design file (``save_design``, or the JSON of ``qropt synth/analyze --json``)."""
    p = Path(path)
    try:
        d = json.loads(p.read_text())
    except FileNotFoundError:
        raise InvalidParameter(f"no design file {path}") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise InvalidParameter(f"{path} is not a JSON design: {e}") from None
    if not isinstance(d, dict) or not isinstance(d.get("params"), dict) or not d.get("type"):
        raise InvalidParameter(f"{path}: a design file has 'type' and 'params'")
    try:
        return mechanism_type(d["type"])(**d["params"])
    except QroptError as e:
        raise InvalidParameter(f"{path}: {e}") from None
    except TypeError as e:
        raise InvalidParameter(f"{path}: {e}") from None


__all__ = ["LAYERS", "link_segments", "geometry", "to_dxf", "to_svg", "save_design", "load_design"]
