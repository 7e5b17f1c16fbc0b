"""The registry of mechanism types: every type with a KIND, by that KIND (``Mechanism`` registers each subclass
when it is defined; ``qropt.mechanisms.mechanism_type`` finds one by name)."""

from __future__ import annotations

from qropt.errors import InvalidParameter

REGISTRY: dict[str, type] = {}  # KIND -> the type (shipped types and every user type with a KIND)


class RegistryError(InvalidParameter):
    """A mechanism type cannot be registered (its KIND or class name is another class's) or found (an unknown
    name, a ``"module:Class"`` reference whose module does not import, that has no such class, or that names
    something that is not a Mechanism)."""


def _identity(cls) -> str:
    """module + qualname: the same class re-imported (a module reload) has the same identity."""
    return f"{cls.__module__}.{cls.__qualname__}"


def register(cls) -> None:
    """Register a type by its own KIND (``Mechanism.__init_subclass__`` calls it). A KIND or class name (either
    compared without case, '_' as '-') already held by another class is refused with RegistryError naming both;
    the same class again (same module and qualname, e.g. a reloaded module) replaces itself."""
    kind = cls.__dict__.get("KIND")
    if not kind:
        return
    if not isinstance(kind, str):
        raise RegistryError(f"{_identity(cls)}: KIND is a string (e.g. 'my-slider'), got {kind!r}")
    key, name = kind.lower().replace("_", "-"), cls.__name__.lower()
    for other in list(REGISTRY.values()):
        if _identity(other) == _identity(cls):
            continue
        if other.KIND.lower().replace("_", "-") == key:
            raise RegistryError(
                f"mechanism KIND {kind!r} of {_identity(cls)} is already taken by {_identity(other)}; "
                "give the new type its own KIND"
            )
        if other.__name__.lower() == name:
            raise RegistryError(
                f"mechanism class name {cls.__name__!r} of {_identity(cls)} is already taken by {_identity(other)} "
                f"(KIND {other.KIND!r}); give the new type its own class name"
            )
    for k in [k for k, v in REGISTRY.items() if _identity(v) == _identity(cls)]:
        del REGISTRY[k]  # a reloaded class (and its earlier KIND, if it changed)
    REGISTRY[kind] = cls


__all__ = ["REGISTRY", "RegistryError", "register"]
