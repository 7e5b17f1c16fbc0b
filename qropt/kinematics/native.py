"""CasADi Functions compiled to machine code by the machine's C compiler, kept in a cache on disk.

A kernel evaluated often (``kernel.Batched`` counts its calls) is written out by CasADi's code generator,
compiled once per machine (``cc -O2 -ffp-contract=off``: no fused multiply-adds, so the numbers are those of
CasADi's virtual machine, operation for operation) and loaded back as an external Function. The shared library
is named by a hash of its C source, the compiler command and CasADi's version, so a changed loop compiles anew
and parallel processes share the same file (written under a temporary name, then renamed).

Where no compiler works (none installed, or ``QROPT_NATIVE=0``), the Function runs on CasADi's virtual machine,
with the same results. ``QROPT_CACHE`` moves the cache (default ``~/.cache/qropt``).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi

FLAGS = ("-O2", "-ffp-contract=off", "-fPIC", "-shared")
_STATE: dict = {}  # "compiler": the compiler path or "" when none works


def enabled() -> bool:
    """Whether kernels are compiled (a C compiler is found and ``QROPT_NATIVE`` is not '0')."""
    if os.environ.get("QROPT_NATIVE", "1") == "0":
        return False
    return bool(_compiler())


def _compiler() -> str:
    if "compiler" not in _STATE:
        _STATE["compiler"] = os.environ.get("CC") or shutil.which("cc") or shutil.which("gcc") or ""
    return _STATE["compiler"]


def cache_dir() -> Path:
    return Path(os.environ.get("QROPT_CACHE") or Path.home() / ".cache" / "qropt") / "kernels"


def compiled(f: casadi.Function) -> casadi.Function:
    """f as machine code (an external Function with the same inputs and outputs), or f itself where it cannot
    be compiled (no compiler, a compiler error, an unwritable cache)."""
    if not enabled():
        return f
    try:
        lib = library(f.name(), source(f))
        return f if lib is None else casadi.external(f.name(), str(lib))
    except (OSError, RuntimeError):
        return f


def source(f: casadi.Function) -> str:
    """f as C, by CasADi's code generator (no header), for ``library``."""
    gen = casadi.CodeGenerator(f.name() + ".c", {"with_header": False})
    gen.add(f)
    return gen.dump()


def library(name: str, code: str) -> Path | None:
    """The shared library of C ``code`` (compiled once per machine into the cache, named ``name`` and a hash of
    the source, the compiler command and CasADi's version), or None where it cannot be built."""
    if not enabled():
        return None
    key = hashlib.sha256("\n".join([code, _compiler(), *FLAGS, casadi.__version__]).encode()).hexdigest()[:24]
    lib = cache_dir() / f"{name}_{key}.so"
    if lib.exists():
        return lib
    try:
        lib.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=lib.parent) as tmp:
            src, out = Path(tmp) / "kernel.c", Path(tmp) / "kernel.so"
            src.write_text(code)
            done = subprocess.run(
                [_compiler(), *FLAGS, str(src), "-o", str(out), "-lm"], capture_output=True, timeout=120
            )
            if done.returncode != 0:
                return None
            os.replace(out, lib)
    except (OSError, subprocess.SubprocessError):
        return None
    return lib


__all__ = ["compiled", "source", "library", "enabled", "cache_dir"]
