"""What a type tells the synthesis about itself: one record, ``Mechanism.SYNTHESIS``, that only qropt.synthesis
reads. A type declares ``SYNTHESIS = SynthesisHints(...)``; a subclass changes some fields by
``dataclasses.replace(Base.SYNTHESIS, ...)``."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from types import MappingProxyType


@dataclasses.dataclass(frozen=True)
class SynthesisHints:
    """The synthesis hints of a mechanism type; every field has a default."""

    exact_transmission: Mapping[str, tuple[float, ...]] = dataclasses.field(default_factory=dict)
    """joint -> crank angles (rad) where its transmission angle is extreme, where known exactly (default none)."""
    ruled_margins: tuple[str, ...] = ()
    """closures that assemble wherever the type's rules hold: the NLP states no margin for them (default none)."""
    accel_extremes: int = 2
    """acceleration extremes the NLP lifts for a peak-acceleration objective (default 2)."""
    ties: tuple[str, ...] = ()
    """lengths that, scaled together by one factor, leave the motion the same: a solve breaks such ties by the
    least size along that scale (default none)."""
    one_reversal: bool = False
    """every design that turns has an output reversing exactly once a turn; else the NLP states it (default
    False)."""
    crank: str = "r2"
    """the length parameter of the input crank (O2A): the evolution and the descents move it to meet the TR (default
    "r2")."""
    closed_forms: tuple[Callable, ...] = ()
    """the closed forms that give a problem's starts, tried in order: functions of a ``closed_forms.Context``
    returning ``closed_forms.WarmStarts``, or None where they do not apply (default none)."""

    def __post_init__(self):
        object.__setattr__(self, "exact_transmission", MappingProxyType(dict(self.exact_transmission)))
        for name in ("ruled_margins", "ties", "closed_forms"):
            object.__setattr__(self, name, tuple(getattr(self, name)))


OLD_NAMES = {f.name.upper(): f.name for f in dataclasses.fields(SynthesisHints)}
"""The class attributes that once held these hints -> the field that holds each now."""
