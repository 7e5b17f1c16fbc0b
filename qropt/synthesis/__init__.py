"""Synthesis: a Problem and its criteria -> a Formulation (the NLP) -> local solves from planned starts -> a
certificate by exact evaluation -> a Result."""

from qropt.synthesis import dynamic  # noqa: F401 - registers the dynamic criteria in criteria.CRITERIA
