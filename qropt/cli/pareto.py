"""``qropt pareto``: the trade-off front between two objectives of a problem file."""

from __future__ import annotations

import argparse
import math

COMMAND = "pareto"
HELP = "the trade-off front between two objectives (epsilon-constraint, every point certified)"
EXAMPLES = (
    "qropt pareto problems/crank_rocker_slider_size.py --objectives max_gamma_min min_size --n 20 --plot front.png",
    "qropt pareto problems/slider_crank_size.py --objectives max_gamma_min min_peak_accel --n 5 --json",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.cli import objective_help

    parser.add_argument("problem", help="a problem file (.py, .toml, .json)")
    parser.add_argument(
        "--objectives",
        nargs=2,
        required=True,
        metavar=("A", "B"),
        help=objective_help("two objectives"),
    )
    parser.add_argument("--n", type=int, default=20, help="points along the front, ends included (default 20)")
    parser.add_argument("--csv", metavar="FILE", help="write the front as CSV")
    parser.add_argument("--plot", metavar="FILE", help="draw the front and designs along it (.png, .pdf, .svg)")
    parser.add_argument("--json", action="store_true", help="print the front as JSON")


def run(args) -> int:
    from qropt.cli import load_problem, picture_path, progress_bar
    from qropt.studies._pareto import pareto

    plot = picture_path(args.plot) if args.plot else None
    problem = load_problem(args.problem)
    with progress_bar("front points", total=max(args.n - 2, 0)) as bar:
        front = pareto(problem, tuple(args.objectives), n=args.n, progress=bar.update)
    if args.csv:
        front.to_csv(args.csv)
    if plot:
        front.plot(plot)
    if args.json:
        print(front.to_json())
        return 0
    a, b = front.criteria
    print(
        f"{problem.name or args.problem}: {front.objectives[0]} vs {front.objectives[1]}, "
        f"{len(front.points)} non-dominated points"
    )
    for va, vb in front.values:
        print(f"  {_show(a, va, problem.units)}   {_show(b, vb, problem.units)}")
    for eps, why in front.removed:
        print(f"  removed (bound {eps if eps is None else format(eps, '.6g')}): {why}")
    if args.csv:
        print(f"front written to {args.csv}")
    if plot:
        print(f"picture written to {plot}")
    return 0


def _show(q, v, length: str):
    from qropt.synthesis.criteria import CRITERIA
    from qropt.units import named

    unit = named(CRITERIA[q].unit, length)
    return f"{q} {math.degrees(v):.4f} deg" if unit == "rad" else f"{q} {v:.6g} {unit}"
