"""Synthesis: a Problem and its criteria -> a Formulation (the NLP) -> local solves from planned starts -> a
certificate by exact evaluation -> a Result."""
