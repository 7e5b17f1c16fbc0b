"""A valid design of every type, the one a page opens with: for a shipped type, its best design by
gamma_min for TR 1.5 and stroke 0.3 m (``qropt.design(1.5, 0.3)``, rounded to 0.1 mm; the drag-link slider is the
paper's design); for a type of the user's, the design of the problem file that loaded it (``remember``)."""

from __future__ import annotations

from qropt.mechanisms import type_reference

SHIPPED = {
    "slider-crank": {"r2": 0.1352, "r3": 0.2499, "e": 0.0865, "sigma_slider": 1.0},
    "crank-shaper": {"r1": 0.2178, "r2": 0.0673, "r4": 0.4854, "sigma_slider": 1.0},
    "whitworth": {"r1": 0.0212, "r2": 0.0688, "r5": 0.15, "r6": 0.4, "h": 0.0, "sigma_slider": 1.0},
    "crank-rocker-slider": {
        **{"r1": 1.1124, "r2": 0.3438, "r3": 0.7075, "r4": 1.2727, "r5": 0.8676, "r6": 0.9507, "h": 0.4627},
        **{"sigma": -1.0, "sigma_slider": 1.0},
    },
    "drag-link-slider": {
        **{"r1": 0.1, "r2": 0.225, "r3": 0.2504, "r4": 0.275, "r5": 0.15, "r6": 0.3, "h": 0.0},
        **{"sigma": 1.0, "sigma_slider": 1.0},
    },
    "coupler-slider": {
        **{"r1": 1.0561, "r2": 0.0827, "r3": 0.3681, "r4": 0.9933, "r5": 1.5, "beta": -0.5201, "r6": 1.0128},
        **{"h": 0.9477, "sigma": -1.0, "sigma_slider": 1.0},
    },
    "slot-ram-shaper": {"r1": 0.2073, "r2": 0.0641, "h": 0.4617},
    "four-bar": {"r1": 0.3, "r2": 0.1, "r3": 0.35, "r4": 0.3, "sigma": -1.0},
}
_USER: dict = {}


def remember(cls, params: dict) -> None:
    """Open a user type with these parameters (a design of its problem file)."""
    _USER[type_reference(cls)] = dict(params)


def default_params(cls) -> dict:
    """The design a page opens with for type cls ({} if none is known: the page asks for every parameter)."""
    if type_reference(cls) in _USER:  # by name: a reloaded module's class is the same type
        return dict(_USER[type_reference(cls)])
    p = SHIPPED.get(cls.__dict__.get("KIND", ""))
    return {} if p is None else {k: v for k, v in p.items() if k in cls.PARAMS}
