"""The quick-return mechanism types, one module each, and their registry."""

from qropt.mechanisms.base import REGISTRY, DeadCentres, GammaMin, Loop, Mechanism, Motion, Positions
from qropt.mechanisms.crank_rocker_slider import CrankRockerSlider
from qropt.mechanisms.crank_shaper import CrankShaper
from qropt.mechanisms.drag_link_slider import DragLinkSlider
from qropt.mechanisms.four_bar import FourBar, FourBarSlider, Grashof, grashof
from qropt.mechanisms.slider_crank import SliderCrank
from qropt.mechanisms.whitworth import Whitworth

TYPES = (SliderCrank, CrankShaper, Whitworth, CrankRockerSlider, DragLinkSlider, FourBar)


def mechanism_type(name) -> type[Mechanism]:
    """A mechanism class from itself, its class name or its kind (e.g. 'drag-link-slider')."""
    from qropt.errors import InvalidParameter

    if isinstance(name, type) and issubclass(name, Mechanism):
        return name
    by_class = {t.__name__.lower(): t for t in TYPES}
    key = str(name).lower().replace("_", "-")
    t = REGISTRY.get(key) or by_class.get(key.replace("-", ""))
    if t is None:
        raise InvalidParameter(f"unknown mechanism type {name!r}; known: {sorted(REGISTRY)}")
    return t


__all__ = [
    "TYPES",
    "REGISTRY",
    "mechanism_type",
    "Mechanism",
    "Loop",
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
]
