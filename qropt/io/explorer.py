"""An interactive explorer for a notebook: a slider per parameter, the time ratio, stroke, gamma_min and the picture
following them (``qropt.io.notebook``). Needs ipywidgets (``pip install "qropt[notebook]"``)."""

from __future__ import annotations

import html
import math

from qropt.errors import InvalidParameter, QroptError
from qropt.mechanisms import Mechanism

EXTRA = 'pip install "qropt[notebook]"'


class MissingExtra(QroptError):
    """An optional dependency is missing: the message names the extra that installs it."""


def view(kind: type, params: dict, units: str) -> str:
    """The HTML the explorer shows for a type at these parameters (angles in rad): the mechanism's, or why these
    parameters give none."""
    from qropt.io.notebook import mechanism_html

    try:
        return mechanism_html(kind(**params, units=units))
    except QroptError as e:
        text = html.escape(str(e)[:400])
        return f'<div class="qropt-nb qropt-nb-explorer" style="color:#d62728;font-family:sans-serif">{text}</div>'


def explore(mechanism: Mechanism, span: float = 0.5):
    """Sliders for every parameter of ``mechanism`` but its branch signs (lengths and offsets within +/- span of
    their value, or of the largest length for a zero offset; angles in degrees within +/- 180 deg), and its
    HTML (picture, time ratio, stroke, gamma_min) redrawn as they move: an ipywidgets box for a notebook cell.
    MissingExtra if ipywidgets is not installed."""
    if not isinstance(mechanism, Mechanism):
        raise InvalidParameter(f"explore takes a qropt mechanism, got {type(mechanism).__name__}")
    if isinstance(span, bool) or not isinstance(span, (int, float)) or not 0 < span < 1:
        raise InvalidParameter(f"span is a fraction in (0, 1), got {span!r}")
    try:
        import ipywidgets as w
    except ImportError:
        raise MissingExtra(f"explore needs ipywidgets: {EXTRA}") from None
    kind, units, kinds = type(mechanism), mechanism.units, mechanism.kinds()
    params = dict(mechanism.params)
    largest = max((v for k, v in params.items() if kinds[k] == "length"), default=1.0)
    sliders = {}
    for k, v in params.items():
        if kinds[k] == "branch":
            continue
        if kinds[k] == "angle":
            lo, hi, value, label = -180.0, 180.0, math.degrees(v), f"{k} [deg]"
        else:
            d = span * (abs(v) or largest)
            lo, hi, value, label = (v - d, v + d, v, f"{k} [{units}]")
            lo = max(lo, 1e-6 * largest) if kinds[k] == "length" else lo
        sliders[k] = w.FloatSlider(
            value=value,
            min=lo,
            max=hi,
            step=(hi - lo) / 400,
            description=label,
            readout_format=".4g",
            continuous_update=False,
        )
    out = w.HTML(value=view(kind, params, units))

    def update(_change=None):
        now = dict(params)
        for k, s in sliders.items():
            now[k] = math.radians(s.value) if kinds[k] == "angle" else s.value
        out.value = view(kind, now, units)

    for s in sliders.values():
        s.observe(update, names="value")
    return w.VBox([*sliders.values(), out])


__all__ = ["explore", "view", "MissingExtra", "EXTRA"]
