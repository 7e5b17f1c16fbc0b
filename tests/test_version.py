"""qropt's version: one number, written in pyproject.toml only, read from the installed package's metadata by
``qropt.__version__``, ``qropt --version``, the app's health answer and every saved file's "qropt" field."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from importlib import metadata
from pathlib import Path

import qropt
from qropt import schema

ROOT = Path(__file__).resolve().parents[1]


def test_the_version_is_the_installed_packages():
    assert qropt.__version__ == schema.VERSION == metadata.version("qropt")
    assert re.fullmatch(r"\d+\.\d+\.\d+([.+-].*)?", qropt.__version__)


def test_pyproject_is_the_one_place_the_number_is_written():
    number = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert number == qropt.__version__
    literal = re.compile(r"""["']""" + re.escape(number) + r"""["']""")
    written = [p for p in (ROOT / "qropt").rglob("*.py") if literal.search(p.read_text())]
    assert written == []


def test_version_is_not_a_public_name_of_the_api():
    assert "__version__" not in qropt.__all__  # the package's convention: __all__ lists the API's objects


def test_command_line_version():
    code = "import sys; from qropt.cli import main; sys.exit(main())"
    out = subprocess.run([sys.executable, "-c", code, "--version"], capture_output=True, text=True, check=True)
    assert out.stdout == f"qropt {qropt.__version__}\n" and out.stderr == ""
