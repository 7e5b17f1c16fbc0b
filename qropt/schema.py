"""The version of qropt and the schema version of the files it saves (a base module: it imports no layer).

``VERSION`` is read from the installed package's metadata (the one place the number is written is
pyproject.toml). ``SCHEMA`` numbers the form of every file qropt saves (a problem's JSON or TOML, a design file,
a Result's dictionary, a chart's JSON): each carries ``"schema": SCHEMA`` and ``"qropt": VERSION`` (``stamp``).
Raise ``SCHEMA`` when a file's form changes so that an older qropt would misread it. A reader (``check``)
refuses a file of a newer schema than this qropt's, in one line naming both; a file of an older schema, or of
none (written before files carried one), is read as before.
"""

from __future__ import annotations

from collections.abc import Mapping
from importlib import metadata

from qropt.errors import QroptError

SCHEMA = 1  # the form of the files this qropt writes; raise it when an older qropt would misread them
FIELDS = ("schema", "qropt")  # what ``stamp`` adds to a saved table

try:
    VERSION = metadata.version("qropt")
except metadata.PackageNotFoundError:  # pragma: no cover - a checkout imported without being installed
    VERSION = "0+unknown"


def stamp() -> dict:
    """The fields every saved file carries first: its schema and the qropt that wrote it."""
    return {"schema": SCHEMA, "qropt": VERSION}


def check(d, what: str, error: type[QroptError] = QroptError) -> None:
    """Refuse a table (a file's top level) of a newer schema than this qropt reads: ``error`` in one line naming
    ``what`` (the file), its schema and this qropt's. A table with no schema, or an older one, passes."""
    if not isinstance(d, Mapping) or "schema" not in d:
        return
    n = d["schema"]
    if not isinstance(n, int) or isinstance(n, bool) or n < 0:
        raise error(f"{what}: 'schema' is the schema version of the file, a whole number >= 0; got {n!r:.40}")
    if n > SCHEMA:
        wrote = d.get("qropt")
        by = f" (written by qropt {wrote})" if isinstance(wrote, str) and len(wrote) <= 40 else ""
        raise error(
            f"{what} has schema {n}{by}, newer than this qropt's schema {SCHEMA} (qropt {VERSION}): "
            "upgrade qropt to read it"
        )


__all__ = ["SCHEMA", "VERSION", "FIELDS", "stamp", "check"]
