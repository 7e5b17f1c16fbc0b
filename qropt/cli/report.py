"""``qropt report``: one self-contained HTML report of the paper's project, or of a problem file's design."""

from __future__ import annotations

import argparse

COMMAND = "report"
HELP = "one self-contained HTML report: the paper's whole project, or a problem file's design"
EXAMPLES = ("qropt report -o report.html", "qropt report problems/whitworth_accel.py -o whitworth.html")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.cli import loads_arguments

    parser.add_argument("problem", nargs="?", help="a problem file (.py, .toml, .json); default: the paper's project")
    parser.add_argument("-o", "--output", default="report.html", help="the HTML file (default report.html)")
    loads_arguments(
        parser,
        flags=False,
        instead=" instead of the problem file's, or of the paper project's assumed load (1000 N, gravity 9.81 m/s^2)",
    )


def run(args) -> int:
    from qropt.cli import load_problem, loads_of, point_masses, progress_bar
    from qropt.io.report import render, report_path

    report_path(args.output)  # a bad output path fails before anything is computed
    loads, points = loads_of(args), point_masses(args)
    problem = load_problem(args.problem) if args.problem else None
    with progress_bar("report sections", unit="section") as bar:
        render(problem, args.output, progress=bar.update, loads=loads, points=points)
    print(f"report written to {args.output}")
    return 0
