"""The checks at qropt's boundary, each written once: a number, a branch sign, a file to read, a JSON document and
a path to write, from a user, refused with a typed qropt error that names what is wrong. The library, the command
line and the web application read their inputs through these."""

from __future__ import annotations

import json
import math
import os
import stat
from pathlib import Path

import numpy as np

from qropt.errors import InvalidParameter

MAGNITUDE = 1e100  # largest |value| of a length, offset or angle (their squares stay finite)
LIMIT = 1e12  # largest |value| of a mass, force, torque, speed or inertia
MAX_FILE = 16 << 20  # bytes of a file qropt reads (a problem, a design, a result, a chart)
MAX_NESTING = 200  # levels of nested tables and lists in a document (qropt's own files need fewer than 10)
_REAL = (int, float, np.integer, np.floating)


def number(name: str, value, *, limit: float = MAGNITUDE, error: type[InvalidParameter] = InvalidParameter) -> float:
    """A real, finite number with |value| <= ``limit`` as a float, or ``error`` naming ``name``."""
    if type(value) is float and -limit <= value <= limit:  # the common case, checked first
        return value
    if isinstance(value, bool) or not isinstance(value, _REAL):
        raise error(f"{name} must be a number, got {value!r:.80}")
    try:
        v = float(value)
    except OverflowError:
        v = math.inf
    if not math.isfinite(v):
        raise error(f"{name} must be finite, got {v}")
    if abs(v) > limit:
        raise error(f"{name} = {v:g} is out of range (|value| <= {limit:g})")
    return v


def within(name: str, value, low: float, high: float, *, error: type[InvalidParameter] = InvalidParameter) -> float:
    """A finite number in [low, high], or ``error`` naming ``name`` and the interval."""
    v = number(name, value, limit=math.inf, error=error)
    if not low <= v <= high:
        raise error(f"{name} must lie in [{low:g}, {high:g}], got {v:g}")
    return v


def branch_sign(name: str, value, *, error: type[InvalidParameter] = InvalidParameter) -> float:
    """A branch sign: +1.0 or -1.0 (an assembly's branch; no other number selects one)."""
    v = number(name, value, error=error)
    if v not in (-1.0, 1.0):
        raise error(f"{name} must be +1 or -1, got {v:g}")
    return v


def flag(name: str, value, *, error: type[InvalidParameter] = InvalidParameter) -> bool:
    """True or False exactly (not 1, "yes" or None)."""
    if not isinstance(value, bool):
        raise error(f"{name} is true or false, got {value!r:.40}")
    return value


def regular_file(
    path, what: str, *, max_bytes: int = MAX_FILE, error: type[InvalidParameter] = InvalidParameter
) -> Path:
    """``path`` as a Path to a regular file of at most ``max_bytes`` bytes (looked at, not opened), or ``error``
    naming ``what`` and the path for a missing, non-regular (a device, a pipe, a folder) or oversized file."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise error(f"a {what} path is a str or path-like, got {path!r:.80}")
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise error(f"no {what} {path} (No such file or directory)") from None
    except OSError as e:
        raise error(f"cannot read the {what} {path}: {e.strerror or e}") from None
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path} is not a regular file: a {what} is a file")
    if st.st_size > max_bytes:
        raise error(f"{path} has {st.st_size:,} bytes: a {what} has at most {max_bytes:,}")
    return p


def read_text(path, what: str, *, max_bytes: int = MAX_FILE, error: type[InvalidParameter] = InvalidParameter) -> str:
    """The UTF-8 text of the ``regular_file`` at ``path``, read up to ``max_bytes`` bytes; ``error`` naming
    ``what`` and the path for a file that ``regular_file`` refuses, that cannot be read or is not UTF-8."""
    p = regular_file(path, what, max_bytes=max_bytes, error=error)
    try:
        with open(p, "rb") as fh:
            data = fh.read(max_bytes + 1)
    except OSError as e:
        raise error(f"cannot read the {what} {path}: {e.strerror or e}") from None
    if len(data) > max_bytes:
        raise error(f"{path} has more than {max_bytes:,} bytes: a {what} has at most {max_bytes:,}")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise error(f"{path} is not a {what}: not UTF-8 text ({e.reason} at byte {e.start})") from None


def nesting(text: str) -> int:
    """An upper bound on the nesting depth of JSON or TOML text: brackets and braces open at once (counting those
    inside strings too, which only overestimates)."""
    depth = most = 0
    for ch in text:
        if ch in "[{":
            depth += 1
            most = max(most, depth)
        elif ch in "]}":
            depth = max(depth - 1, 0)
    return most


def json_document(
    text,
    name: str,
    kind: str | None = None,
    *,
    max_nesting: int = MAX_NESTING,
    error: type[InvalidParameter] = InvalidParameter,
):
    """The value of strict JSON text (no nan or infinity) nested at most ``max_nesting`` levels, or ``error``
    saying that ``name`` (a path, "the request body") is not JSON (not a JSON ``kind``: "design", "chart") and why."""
    what = "JSON" if kind is None else f"a JSON {kind}"
    if isinstance(text, (bytes, bytearray)):
        try:
            text = bytes(text).decode("utf-8")
        except UnicodeDecodeError:
            raise error(f"{name} is not {what}: not UTF-8 text") from None
    if not isinstance(text, str):
        raise error(f"{name} is not {what}: JSON is text, got {type(text).__name__}")
    if nesting(text) > max_nesting:
        raise error(f"{name} is not {what}: it is nested too deeply (more than {max_nesting} levels)")

    def constant(c):
        raise ValueError(f"{c} is not a JSON number")

    try:
        return json.loads(text, parse_constant=constant)
    except RecursionError:
        raise error(f"{name} is not {what}: it is nested too deeply") from None
    except ValueError as e:
        raise error(f"{name} is not {what}: {e}") from None


def output_path(path, suffixes, what: str) -> Path:
    """``path`` as a Path to write ``what`` to, or InvalidParameter naming the problem: a str or path-like whose
    extension is one of ``suffixes`` (lower case, with the dot), not a directory, in an existing directory that
    can be written (and, if the file exists, a file that can be overwritten)."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise InvalidParameter(f"the {what} path must be a str or path-like, got {path!r}")
    if not os.fspath(path).strip():
        raise InvalidParameter(f"the {what} path is empty")
    p = Path(path)
    if p.is_dir():
        raise InvalidParameter(f"{path}: is a directory, not a {what} file")
    suffix = p.suffix.lower()
    if suffix not in suffixes:
        got = f"{suffix!r}" if suffix else "no extension"
        raise InvalidParameter(f"{path}: the {what} formats are {', '.join(suffixes)} (got {got})")
    parent = p.parent
    if not parent.is_dir():
        why = "is not a directory" if parent.exists() else "does not exist"
        raise InvalidParameter(f"{path}: cannot write the {what}: its directory {parent} {why}")
    if not os.access(parent, os.W_OK | os.X_OK) or (p.exists() and not os.access(p, os.W_OK)):
        raise InvalidParameter(f"{path}: cannot write the {what}: permission denied")
    return p


PICTURE_FORMATS = (".png", ".pdf", ".svg")  # what every picture of qropt may be written as


def picture_path(path) -> Path:
    """``output_path`` for a picture: the picture formats are PICTURE_FORMATS."""
    return output_path(path, PICTURE_FORMATS, "picture")


__all__ = [
    "MAGNITUDE",
    "LIMIT",
    "MAX_FILE",
    "MAX_NESTING",
    "number",
    "within",
    "branch_sign",
    "flag",
    "regular_file",
    "read_text",
    "nesting",
    "json_document",
    "output_path",
    "picture_path",
    "PICTURE_FORMATS",
]
