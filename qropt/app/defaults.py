"""A valid design of every type, the one a page opens with: the design of the problem file that loaded the type
(``remember``), else the type's own example design (``Mechanism.EXAMPLE``: every shipped type has one, the drag-link
slider's the paper's design of ``qropt.examples.paper_mechanism``)."""

from __future__ import annotations

from qropt.mechanisms import type_reference

_USER: dict = {}


def remember(cls, params: dict) -> None:
    """Open a user type with these parameters (a design of its problem file)."""
    _USER[type_reference(cls)] = dict(params)


def default_params(cls) -> dict:
    """The design a page opens with for type cls ({} if none is known: the page asks for every parameter): the one
    its problem file solved, else the example the class itself declares (``EXAMPLE``, not a base class's)."""
    if type_reference(cls) in _USER:  # by name: a reloaded module's class is the same type
        return dict(_USER[type_reference(cls)])
    return {k: v for k, v in cls.__dict__.get("EXAMPLE", {}).items() if k in cls.PARAMS}
