"""Output paths checked before anything is rendered: the extension, the directory, and that it can be written."""

from __future__ import annotations

import os
from pathlib import Path

from qropt.errors import InvalidParameter


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


__all__ = ["output_path", "picture_path", "PICTURE_FORMATS"]
