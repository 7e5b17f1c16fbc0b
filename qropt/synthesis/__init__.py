"""Synthesis: a Problem and its criteria -> a Formulation (the NLP) -> local solves from planned starts -> a
certificate by exact evaluation -> a Result."""

from qropt.synthesis import cut, dynamic, motor  # noqa: F401 - register the cut-window, dynamic and motor criteria
