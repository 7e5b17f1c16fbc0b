"""``qropt app``: a local web application over the library (Design, Mechanism and Synthesis pages and a JSON
API under ``/api``); see ``qropt.app.server`` for the API and docs/app.md for the pages."""

from qropt.app.server import create_app

__all__ = ["create_app"]
