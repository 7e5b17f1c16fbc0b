"""Synthesis problems: one file per problem, each with ``build() -> Problem`` and its oracle."""
