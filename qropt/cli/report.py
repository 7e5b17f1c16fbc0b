"""``qropt report``: one self-contained HTML report of the paper's project, or of a problem file's design."""

from __future__ import annotations

import argparse

COMMAND = "report"
HELP = "one self-contained HTML report: the paper's whole project, or a problem file's design"
EXAMPLES = ("qropt report -o report.html", "qropt report problems/whitworth_accel.py -o whitworth.html")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("problem", nargs="?", help="a problem file (.py, .toml, .json); default: the paper's project")
    parser.add_argument("-o", "--output", default="report.html", help="the HTML file (default report.html)")


def run(args) -> int:
    from qropt.cli import load_problem, progress_bar
    from qropt.io.report import render, report_path

    report_path(args.output)  # a bad output path fails before anything is computed
    problem = load_problem(args.problem) if args.problem else None
    with progress_bar("report sections", unit="section") as bar:
        render(problem, args.output, progress=bar.update)
    print(f"report written to {args.output}")
    return 0
