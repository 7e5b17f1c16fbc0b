"""The quick-return mechanism types, one module each, and their registry.

The public building blocks of a type of one's own (see docs/extending.md): ``Mechanism`` (the protocol),
``Loop`` (what a loop returns), ``Rule`` (a feasibility rule), ``Body`` (a moving body to draw), ``REQUIRED``
(a parameter without default), ``SynthesisHints`` (what a type tells the synthesis: ``Mechanism.SYNTHESIS``), the
``closures`` every loop is written with (``qropt.mechanisms.closures`` re-exports ``qropt.kinematics.closures``), the
four-bar helpers ``four_bar`` and ``grashof_rules``, the closed forms a type names for its synthesis starts
(``qropt.mechanisms.closed_forms``: ``Context``, ``WarmStarts``), and the registry:
``mechanism_type`` finds a type by its class, KIND, class name or a ``"module:Class"`` reference, and
``type_reference`` names a type so that another process finds it (a shipped type by its KIND, any other as
``"module:Class"``). Installed packages add types through the entry-point group ``qropt.mechanisms``, loaded
on the first name that is not found.
"""

import importlib
import warnings

from qropt.mechanisms import closures
from qropt.mechanisms.base import PARAMETER_KINDS, REQUIRED, Loop, Mechanism
from qropt.mechanisms.coupler_slider import CouplerSlider
from qropt.mechanisms.crank_rocker_slider import CrankRockerSlider
from qropt.mechanisms.crank_shaper import CrankShaper
from qropt.mechanisms.drag_link_slider import DragLinkSlider
from qropt.mechanisms.four_bar import FourBar, FourBarSlider, Grashof, four_bar, grashof, grashof_rules
from qropt.mechanisms.hints import SynthesisHints
from qropt.mechanisms.registry import REGISTRY, RegistryError, register
from qropt.mechanisms.slider_crank import SliderCrank
from qropt.mechanisms.slot_ram_shaper import SlotRamShaper
from qropt.mechanisms.values import Body, DeadCentres, GammaMin, Motion, Positions, Rule
from qropt.mechanisms.whitworth import Whitworth

TYPES = (SliderCrank, CrankShaper, Whitworth, CrankRockerSlider, DragLinkSlider, FourBar, CouplerSlider, SlotRamShaper)


ENTRY_POINTS = "qropt.mechanisms"  # the entry-point group of installed packages' mechanism types
_plugins_loaded = False


def _normal(name: str) -> str:
    return name.strip().lower().replace("_", "-")


def _lookup(name: str):
    key = _normal(name)
    for t in REGISTRY.values():
        if _normal(t.KIND) == key or t.__name__.lower() == key.replace("-", "") or t.__name__.lower() == key:
            return t
    return None


def load_plugins(force: bool = False) -> list[str]:
    """Import every entry point of the group ``qropt.mechanisms`` (each names a module or a Mechanism class; its
    import registers the types). Done once, on the first name ``mechanism_type`` does not find; a plugin that
    fails to import is skipped with a warning. The names of the entry points loaded."""
    global _plugins_loaded
    if _plugins_loaded and not force:
        return []
    _plugins_loaded = True
    from importlib.metadata import entry_points

    done = []
    for ep in entry_points(group=ENTRY_POINTS):
        try:
            ep.load()
            done.append(ep.name)
        except Exception as e:  # noqa: BLE001 - a broken plugin must not break the lookup of the others
            warnings.warn(f"qropt: mechanism plugin {ep.name!r} ({ep.value}) does not load: {e}", stacklevel=2)
    return done


def _by_reference(ref: str) -> type[Mechanism]:
    module, _, qualname = (x.strip() for x in ref.partition(":"))
    if not module or not qualname:
        raise RegistryError(f"a mechanism type reference is 'module:Class', got {ref!r}")
    try:
        obj = importlib.import_module(module)
    except ModuleNotFoundError as e:
        raise RegistryError(
            f"mechanism type {ref!r}: module {module!r} is not found ({e}); put its folder on sys.path "
            "(PYTHONPATH) or install it"
        ) from None
    except Exception as e:  # noqa: BLE001 - a user module may fail in any way: one line naming it
        raise RegistryError(
            f"mechanism type {ref!r}: module {module!r} fails to import ({type(e).__name__}: {e})"
        ) from None
    for part in qualname.split("."):
        if not hasattr(obj, part):
            raise RegistryError(f"mechanism type {ref!r}: module {module!r} has no class {qualname!r}")
        obj = getattr(obj, part)
    if not (isinstance(obj, type) and issubclass(obj, Mechanism)):
        raise RegistryError(f"mechanism type {ref!r} is {obj!r}, not a qropt Mechanism subclass")
    return obj


def mechanism_type(name) -> type[Mechanism]:
    """A mechanism class from itself, its KIND (e.g. 'drag-link-slider'), its class name or a ``"module:Class"``
    reference (the module is imported; its import registers the class). An unknown KIND or class name loads the
    installed plugins (entry-point group ``qropt.mechanisms``) once and looks again. RegistryError (an
    InvalidParameter) says why a name finds no type."""
    if isinstance(name, type):
        if issubclass(name, Mechanism):
            return name
        raise RegistryError(f"{name!r} is not a qropt Mechanism subclass")
    if not isinstance(name, str) or not name.strip():
        raise RegistryError(f"unknown mechanism type {name!r}: a type is a Mechanism class, a KIND or 'module:Class'")
    if ":" in name:
        return _by_reference(name)
    t = _lookup(name)
    if t is None and load_plugins():
        t = _lookup(name)
    if t is None:
        raise RegistryError(
            f"unknown mechanism type {name!r}; known: {sorted(REGISTRY)} (or 'module:Class' for a type of your own)"
        )
    return t


def shipped(cls) -> bool:
    """Whether a type ships with qropt (defined in the qropt package with its own KIND)."""
    return cls.__module__.split(".")[0] == "qropt" and bool(cls.__dict__.get("KIND"))


def type_reference(cls) -> str:
    """The name under which files and other processes find a type: a shipped type's KIND; any other type's
    ``"module:Class"`` (its KIND where that reference does not lead back to it, e.g. a class defined in
    ``__main__`` or inside a function, which only this process knows)."""
    cls = mechanism_type(cls)
    if shipped(cls):
        return cls.KIND
    ref = f"{cls.__module__}:{cls.__qualname__}"
    registered = bool(cls.__dict__.get("KIND")) and REGISTRY.get(cls.KIND) is cls
    if cls.__module__ == "__main__" or "<" in cls.__qualname__:
        return cls.KIND if registered else ref
    try:
        found = _by_reference(ref)
    except RegistryError:
        found = None
    return ref if found is cls or not registered else cls.KIND


__all__ = [
    "TYPES",
    "REGISTRY",
    "RegistryError",
    "mechanism_type",
    "type_reference",
    "shipped",
    "register",
    "load_plugins",
    "ENTRY_POINTS",
    "Mechanism",
    "Loop",
    "Rule",
    "Body",
    "REQUIRED",
    "SynthesisHints",
    "PARAMETER_KINDS",
    "closures",
    "four_bar",
    "grashof_rules",
    "Positions",
    "Motion",
    "DeadCentres",
    "GammaMin",
    "Grashof",
    "grashof",
    "SliderCrank",
    "CrankShaper",
    "Whitworth",
    "FourBar",
    "FourBarSlider",
    "CrankRockerSlider",
    "DragLinkSlider",
    "CouplerSlider",
    "SlotRamShaper",
]
