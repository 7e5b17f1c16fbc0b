"""Length units: a problem or mechanism states its unit once, and every printout, axis, table and export uses it.

Lengths stay numbers in that unit everywhere in qropt (the analysis and the NLP are unit-free); the unit only
names them, and converts them where a physical quantity needs SI (dynamics) or a file needs a declared unit
(DXF). Angles are radians in the API.
"""

from __future__ import annotations

from qropt.errors import InvalidParameter

LENGTH_UNITS = {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6, "in": 0.0254, "ft": 0.3048}  # in metres
DEFAULT = "m"


def length_unit(unit) -> str:
    """A valid length unit name (one of LENGTH_UNITS), or InvalidParameter naming the choices."""
    if not isinstance(unit, str) or unit not in LENGTH_UNITS:
        raise InvalidParameter(f"the length unit is one of {list(LENGTH_UNITS)}, got {unit!r}")
    return unit


def to_metres(unit: str) -> float:
    """Metres per one ``unit``."""
    return LENGTH_UNITS[length_unit(unit)]


def named(unit_text: str, unit: str) -> str:
    """A unit text with its lengths named: named('length/s^2', 'mm') == 'mm/s^2'."""
    return unit_text.replace("length", unit)


__all__ = ["LENGTH_UNITS", "DEFAULT", "length_unit", "to_metres", "named"]
