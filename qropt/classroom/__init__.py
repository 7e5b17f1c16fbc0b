"""Classroom projects: the paper's quick-return design and analysis project, drawn per seed for a whole class.

``project(kind, seed)`` draws one solvable project of a mechanism type; ``render(project, solution)`` writes its
statement (or its worked solution) as one self-contained HTML page. See docs/classroom.md.
"""

from qropt.classroom.project import KINDS, STROKE_RANGE, Project, project, render

__all__ = ["KINDS", "STROKE_RANGE", "Project", "project", "render"]
