"""What leaves qropt for CAD and other tools: the mechanism at one crank angle as DXF (ezdxf) or SVG, and a
design file (JSON) that ``load_design`` and ``qropt analyze --from`` read back.

Drawings are in the mechanism's own length unit (the DXF header's $INSUNITS and the SVG's title name it), x right
and y up (the SVG flips y for the screen), and draw the bodies the type declares (``qropt.io.drawing``). Layers:
LINKS (bar and lever centre lines at their true lengths; a plate as a closed polygon, hatched in DXF), PIVOTS
(ground pivots), JOINTS (moving joints), SLIDE_LINE, SLIDER_PATH (the output joint's path over a turn) and BLOCKS
(sliding blocks, rams and slots, as outlines).
"""

from __future__ import annotations

import json
import math
from xml.sax.saxutils import escape

from qropt import schema, validate
from qropt import units as units_
from qropt.errors import InvalidParameter, QroptError
from qropt.io import drawing
from qropt.mechanisms import Mechanism, mechanism_type, type_reference
from qropt.validate import output_path

LAYERS = drawing.LAYERS  # name -> DXF colour
RESERVED = ("type", "params", "units", *schema.FIELDS)  # the design file's own fields
LEGACY_UNITS = "lengths in one consistent unit, angles in rad"  # what design files said before units were stated
DXF_UNITS = {"m": 6, "cm": 5, "mm": 4, "um": 13, "in": 1, "ft": 2}  # $INSUNITS codes (ezdxf.units)


def declared_unit(d: dict) -> str | None:
    """The length unit a design dictionary states (a design file's "units": "mm", or a Result's "units" table
    with its "length"), None where it states none (a file from before units were stated); InvalidParameter for
    a unit that is not one of qropt.units.LENGTH_UNITS."""
    u = d.get("units")
    if isinstance(u, dict):
        u = u.get("length")
    if u is None or u == LEGACY_UNITS:
        return None
    return units_.length_unit(u)


def geometry(m: Mechanism, theta2: float = 0.0, n: int = drawing.TURN) -> dict:
    """Layer -> primitives of m's declared bodies at crank angle theta2 (rad): ('line', p, q), ('circle', centre,
    r), ('polyline', points) or ('polygon', points, filled) (closed; filled for a plate); n: crank angles of the
    output's path over a turn."""
    out = {name: [] for name in LAYERS}
    for s in drawing.at(drawing.scene(m, n), theta2):
        if s.kind == "line":
            out[s.layer].append(("line", *s.points))
        elif s.kind == "circle":
            out[s.layer].append(("circle", s.points[0], s.radius))
        elif s.kind == "polyline":
            out[s.layer].append(("polyline", list(s.points)))
        else:
            out[s.layer].append(("polygon", list(s.points), s.part == "plate"))
    return out


def _mechanism(m) -> Mechanism:
    if not isinstance(m, Mechanism):
        raise InvalidParameter(f"expected a qropt mechanism, got {type(m).__name__}")
    return m


def _write(p, write) -> None:
    try:
        write(p)
    except OSError as e:
        raise InvalidParameter(f"{p}: cannot write: {e.strerror or e}") from None


PLATE_FILL = 9  # AutoCAD colour index of a plate's fill: light grey


def to_dxf(m: Mechanism, path, theta2: float = 0.0) -> None:
    """The mechanism at theta2 (rad) as a DXF drawing in its own length unit, one layer per kind of entity."""
    import ezdxf

    _mechanism(m)
    p = output_path(path, (".dxf",), "DXF drawing")
    geo = geometry(m, theta2)
    doc = ezdxf.new("R2010")
    doc.units = DXF_UNITS[m.units]  # $INSUNITS: CAD reads the drawing in the mechanism's unit
    doc.header["$MEASUREMENT"] = 0 if m.units in ("in", "ft") else 1  # imperial or metric
    for name, colour in LAYERS.items():
        doc.layers.add(name, color=colour)
    msp = doc.modelspace()
    for layer, items in geo.items():
        for kind, *args in items:
            attribs = {"layer": layer}
            if kind == "line":
                msp.add_line(args[0], args[1], dxfattribs=attribs)
            elif kind == "circle":
                msp.add_circle(args[0], args[1], dxfattribs=attribs)
            elif kind == "polyline":
                msp.add_lwpolyline(args[0], dxfattribs=attribs)
            else:
                msp.add_lwpolyline(args[0], close=True, dxfattribs=attribs)
                if args[1]:  # a plate: filled light grey inside its outline (joints and links stay visible)
                    hatch = msp.add_hatch(color=PLATE_FILL, dxfattribs=attribs)
                    hatch.paths.add_polyline_path(args[0], is_closed=True)
    _write(p, doc.saveas)


def to_svg(m: Mechanism, path, theta2: float = 0.0) -> None:
    """The same drawing as SVG: one group per layer, lengths in the mechanism's unit (y up, flipped for screens)."""
    _mechanism(m)
    p = output_path(path, (".svg",), "SVG drawing")
    geo = geometry(m, theta2)
    xs = [c for items in geo.values() for _, *a in items for c in _coords(a)[0]]
    ys = [c for items in geo.values() for _, *a in items for c in _coords(a)[1]]
    pad = 0.05 * max(max(xs) - min(xs), max(ys) - min(ys))
    x0, x1, y0, y1 = min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad
    width = (x1 - x0) / 200  # stroke widths relative to the drawing
    colours = {
        "LINKS": "black",
        "PIVOTS": "red",
        "JOINTS": "blue",
        "SLIDE_LINE": "gray",
        "SLIDER_PATH": "teal",
        "BLOCKS": "dimgray",
    }
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
                d = " ".join(f"{x:.12g},{y:.12g}" for x, y in a[0])
                if kind == "polyline":
                    parts.append(f'<polyline points="{d}" fill="none"/>')
                else:
                    fill = f'fill="{colours[layer]}" fill-opacity="0.25"' if a[1] else 'fill="none"'
                    parts.append(f'<polygon points="{d}" {fill}/>')
        body.append(f'<g id="{layer}" stroke="{colours[layer]}" stroke-width="{width:.6g}">' + "".join(parts) + "</g>")
    title = escape(f"{m!r} at theta2 = {math.degrees(theta2):.6g} deg, lengths in {m.units}")
    svg = (
        f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="{x0:.12g} {-y1:.12g} {x1 - x0:.12g} {y1 - y0:.12g}" '
        f'data-units="{m.units}"><title>{title}</title><desc>user units are {m.units} (x right, y up)</desc>'
        f'<g transform="scale(1,-1)">{"".join(body)}</g></svg>\n'
    )
    _write(p, lambda q: q.write_text(svg))


def _coords(args):
    if isinstance(args[0], list):
        return [q[0] for q in args[0]], [q[1] for q in args[0]]
    if len(args) == 2 and isinstance(args[1], tuple):
        return [args[0][0], args[1][0]], [args[0][1], args[1][1]]
    (cx, cy), r = args
    return [cx - r, cx + r], [cy - r, cy + r]


def save_design(m: Mechanism, path, **extra) -> None:
    """A design file: the schema version and qropt's (``qropt.schema.stamp``), the type (its KIND; a type not
    shipped with qropt as "module:Class"), every parameter, its length unit ("units": "mm"; angles in rad), and any
    extra JSON-ready fields (strict JSON: finite numbers, strings, lists, dictionaries, booleans and null)."""
    _mechanism(m)
    p = output_path(path, (".json",), "design file")
    clash = [k for k in extra if k in RESERVED]
    if clash:
        raise InvalidParameter(f"save_design: {', '.join(map(repr, clash))} is the design file's own field")
    for k, v in extra.items():
        try:
            json.dumps(v, allow_nan=False)
        except (ValueError, TypeError, RecursionError) as e:
            why = "nan or infinite numbers" if isinstance(e, ValueError) else type(e).__name__
            raise InvalidParameter(f"save_design: extra field {k!r} is not strict JSON ({why}): {v!r:.80}") from None
    d = {**schema.stamp(), "type": type_reference(type(m)), "params": dict(m.params), "units": m.units, **extra}
    text = json.dumps(d, indent=2, allow_nan=False) + "\n"
    _write(p, lambda q: q.write_text(text))


def read_design(path) -> dict:
    """The table of a design file (``save_design``, or the JSON of ``qropt synth/analyze --json``): a JSON object
    with a type name under 'type' and a table under 'params'. InvalidParameter naming the file for a path that is
    not a regular file of at most ``qropt.validate.MAX_FILE`` bytes, or text that is not such a table, or a file
    of a newer schema than this qropt's (one of an older schema, or of none, is read as before)."""
    d = validate.json_document(validate.read_text(path, "design file"), str(path), "design")
    schema.check(d, str(path), InvalidParameter)
    if not isinstance(d, dict) or not isinstance(d.get("params"), dict) or not d.get("type"):
        raise InvalidParameter(f"{path}: a design file has 'type' and 'params'")
    if not isinstance(d["type"], str):
        raise InvalidParameter(f"{path}: the design's 'type' is a type name, got {d['type']!r:.80}")
    return d


def load_design(path) -> Mechanism:
    """The mechanism of a design file (``read_design``) in the unit the file states (the default unit,
    ``qropt.units.DEFAULT``, for a file that states none)."""
    d = read_design(path)
    try:
        unit = declared_unit(d) or units_.DEFAULT
        return mechanism_type(d["type"])(**d["params"], units=unit)
    except QroptError as e:
        raise InvalidParameter(f"{path}: {e}") from None
    except TypeError as e:
        raise InvalidParameter(f"{path}: {type(e).__name__}: {e}") from None


__all__ = ["LAYERS", "geometry", "to_dxf", "to_svg", "save_design", "read_design", "load_design", "declared_unit"]
