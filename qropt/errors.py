"""Typed errors: the only exceptions qropt raises, all for invalid input."""

from __future__ import annotations

import math


class QroptError(ValueError):
    """Base class of every qropt error: the input cannot be used as given."""


class InvalidParameter(QroptError):
    """A parameter is missing, unknown, not a finite number, out of range, or of the wrong sign."""


class GrashofError(QroptError):
    """A four-bar is not of the Grashof class the mechanism type needs."""

    def __init__(self, message, *, params, kind, required):
        super().__init__(message)
        self.params, self.kind, self.required = dict(params), kind, required


class AssemblyError(QroptError):
    """The mechanism cannot assemble over a full crank turn.

    ``failures`` lists ``(closure, theta2_from, theta2_to)`` in radians.
    """

    def __init__(self, mechanism, params, failures):
        self.mechanism, self.params, self.failures = mechanism, dict(params), list(failures)
        by_closure: dict[str, list[str]] = {}
        for what, lo, hi in self.failures:
            if hi - lo >= 2 * math.pi - 1e-9:
                by_closure.setdefault(what, []).append("the whole turn")
                continue
            span = f"[{math.degrees(lo) % 360:.4f}, {math.degrees(hi) % 360:.4f}]"
            by_closure.setdefault(what, []).append(span)
        parts = [
            f"{what} fails for theta2 in {' and '.join(s)}" + (" deg" if s[-1][0] == "[" else "")
            for what, s in by_closure.items()
        ]
        given = ", ".join(f"{k}={v:g}" for k, v in self.params.items())
        super().__init__(f"{mechanism}({given}) cannot turn through a full revolution: " + "; ".join(parts))


class NoDeadCentres(QroptError):
    """The output has no extremes over a crank turn (for example a drag-link follower)."""


class DegenerateMechanism(QroptError):
    """A quantity is undefined because the mechanism sits on a singular configuration over its whole turn."""


class SlideLocked(DegenerateMechanism):
    """Friction locks the slide at crank angle ``theta2`` (rad): the guide's force grows with its own friction."""

    def __init__(self, message: str, theta2: float):
        super().__init__(message)
        self.theta2 = theta2


class PinLocked(DegenerateMechanism):
    """Friction at the pins locks the linkage at crank angle ``theta2`` (rad), at pin ``joint``: the friction
    moments could hold the linkage jammed by themselves (the joint forces grow with their own friction)."""

    def __init__(self, message: str, theta2: float, joint: str):
        super().__init__(message)
        self.theta2, self.joint = theta2, joint


class UnsupportedLoad(InvalidParameter):
    """A part of qropt that cannot apply a load yet was given one (a general force, torque, gravity vector, point
    mass or named working stroke in the synthesis NLP, the servo's convex problem or a picture)."""


class ProblemError(QroptError):
    """A synthesis problem is malformed: unknown names, empty or contradictory bounds, no free parameter."""


class ChartError(QroptError):
    """A chart cannot be made as asked: a bad axis, tile, worker count or scheduler."""


class BodyError(InvalidParameter):
    """A mechanism type's declared bodies cannot be drawn: none declared, an unknown kind, or a joint (of a body,
    the ground or the output) that the mechanism's positions do not have."""
