"""Where benchmark results go: a JSON file under benchmarks/results/ with the date, machine and versions."""

from __future__ import annotations

import importlib
import json
import platform
from datetime import date
from pathlib import Path

RESULTS = Path(__file__).parent / "results"


def environment() -> dict:
    """Date, machine, Python and the versions of qropt and the libraries it is measured with."""
    versions = {}
    for name in ("qropt", "casadi", "numpy", "scipy", "pylinkage"):
        try:
            versions[name] = importlib.import_module(name).__version__
        except ImportError:
            versions[name] = "not installed"
    return {
        "date": date.today().isoformat(),
        "machine": f"{platform.platform()} ({platform.machine()})",
        "python": platform.python_version(),
        "versions": versions,
    }


def save(name: str, data: dict, directory: Path = RESULTS) -> Path:
    """Write ``data`` with the environment as ``directory/name``; returns the path."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    path.write_text(json.dumps({**environment(), **data}, indent=2, default=float) + "\n")
    return path
