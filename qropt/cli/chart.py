"""``qropt chart FILE``: a problem file solved over a grid of target or fixed-parameter values (qropt.chart),
in-process or on a Dask cluster; prints a summary, writes the picture, CSV and JSON asked for."""

from __future__ import annotations

import argparse
import math

import numpy as np

import qropt.cli as cli
from qropt.mechanisms import type_reference
from qropt.synthesis.criteria import maximises, of_problem
from qropt.units import named

COMMAND = "chart"
HELP = "solve a problem file over a grid of time ratios, strokes, swings or fixed parameters (a design chart)"
MAX_VALUES = 100_000
EXAMPLES = (
    "qropt chart problems/chart_slider_crank.py --plot slider_crank_chart.png",
    "qropt chart problems/chart_crank_rocker.py --x time_ratio 1.1:2.5:15 --y swing 40deg:100deg:13 --json small.json",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("problem", help="a problem file (build() -> Problem; its X and Y are the default axes)")
    parser.add_argument(
        "--x",
        nargs=2,
        metavar=("NAME", "VALUES"),
        help="x axis: a target (time_ratio, stroke, swing) or fixed parameter, and its values as "
        "FROM:TO:COUNT or V1,V2,... (swing in deg unless suffixed rad)",
    )
    parser.add_argument("--y", nargs="+", metavar="NAME VALUES", help="y axis, as --x; 'none' for a one-axis chart")
    parser.add_argument("--scheduler", help="'local' or the address of a running Dask scheduler (tcp://host:8786)")
    parser.add_argument("--workers", type=int, help="worker processes of a local Dask cluster")
    parser.add_argument("--tile", nargs=2, type=int, metavar=("NX", "NY"), help="cells per tile (default 10 10)")
    parser.add_argument(
        "--check",
        type=int,
        help="the full solve also runs at the centre of every CHECK x CHECK block (default 10; 1: everywhere)",
    )
    parser.add_argument("--plot", help="picture (PNG, PDF, SVG): contours of the objective and the optimal links")
    parser.add_argument("--csv", help="CSV file: one row per cell")
    parser.add_argument("--json", help="JSON file: the whole chart, every cell's Result")


def values(name: str, text: str) -> list[float]:
    """Axis values: FROM:TO:COUNT (evenly spaced, both ends included) or V1,V2,...; angles for swing."""
    one = cli.angle if name == "swing" else cli.real
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise cli.CliError(f"{name} values {text!r}: use FROM:TO:COUNT or V1,V2,...")
            count = int(parts[2])
            if not 2 <= count <= MAX_VALUES:
                raise cli.CliError(f"{name} values {text!r}: COUNT must be from 2 to {MAX_VALUES:,}")
            return [float(v) for v in np.linspace(one(parts[0]), one(parts[1]), count)]
        return [one(v) for v in text.split(",")]
    except (argparse.ArgumentTypeError, ValueError) as e:
        raise cli.CliError(f"{name} values {text!r}: {e}") from None


def file_axes(path: str) -> dict:
    """The default axes X and Y a .py problem file defines (none for TOML and JSON files)."""
    import importlib.util

    if not path.endswith(".py"):
        return {}
    spec = importlib.util.spec_from_file_location("qropt_chart_axes", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # load_problem has run it already: it loads
    return {k.lower(): getattr(module, k) for k in ("X", "Y") if getattr(module, k, None) is not None}


def run(args) -> int:
    from qropt.studies._chart_run import chart

    problem = cli.load_problem(args.problem)
    defaults = file_axes(args.problem)
    x = (args.x[0], values(*args.x)) if args.x else defaults.get("x")
    if x is None:
        raise cli.CliError(f"{args.problem} defines no X axis: give --x NAME VALUES")
    if args.y is None:
        y = defaults.get("y")
    elif args.y == ["none"]:
        y = None
    elif len(args.y) == 2:
        y = (args.y[0], values(*args.y))
    else:
        raise cli.CliError("--y takes NAME VALUES, or none")
    options = {k: v for k, v in (("tile", tuple(args.tile) if args.tile else None), ("check", args.check)) if v}
    ch = chart(problem, x, y, scheduler=args.scheduler, workers=args.workers, progress=not cli.QUIET, **options)
    for line in summary(ch):
        print(line)
    written = []
    for path, write in ((args.plot, ch.plot), (args.csv, ch.to_csv), (args.json, ch.to_json)):
        if path:
            write(path)
            written.append(path)
    if written:
        print("wrote " + ", ".join(written))
    return 0 if ch.stats["certified"] else 1


def _axis_text(axis) -> str:
    lo, hi = axis.values[0], axis.values[-1]
    if axis.name == "swing":
        return f"{axis.name} ({len(axis.values)} values, {math.degrees(lo):.6g}..{math.degrees(hi):.6g} deg)"
    return f"{axis.name} ({len(axis.values)} values, {lo:.6g}..{hi:.6g})"


def summary(ch) -> list[str]:
    """A few lines: the chart, how its cells were solved, the objective's range and where it is best."""
    p, s = ch.problem, ch.stats
    axes = _axis_text(ch.x) + (f" x {_axis_text(ch.y)}" if ch.y else "")
    lines = [
        f"{p.name or p.mechanism.__name__}: {type_reference(p.mechanism)}, {p.objective} over {axes}",
        f"{s['cells']} cells in {s['seconds']:.3g} s ({s['cells_per_second']:.3g} cells/s, {s['scheduler']}): "
        f"{s['certified']} certified, {s['no_design']} without a design",
        f"  {s['continued']} continued from a neighbour, {s['full']} full solves ({s['needed']} needed: the "
        f"warm start failed or jumped), {s['jumps']} jumps, {s['switched']} cells where a better branch "
        "took over",
    ]
    z = ch.grid()
    if np.isfinite(z).any():
        deg = maximises(p.objective)  # gamma_min, shown in degrees
        best = np.nanargmax(z) if deg else np.nanargmin(z)
        c = ch.cells[int(best)]
        lo, hi = (math.degrees(v) if deg else v for v in (np.nanmin(z), np.nanmax(z)))
        at = ", ".join(
            f"{a.name} {math.degrees(a.values[k]) if a.name == 'swing' else a.values[k]:.6g}"
            for a, k in ((ch.x, c.i), (ch.y, c.j))
            if a
        )
        design = ", ".join(f"{k}={c.params[k]:.6g}" for k in p.free)
        unit = " deg" if deg else f" {named(of_problem(p).unit, p.units)}" if p.objective else ""
        lines.append(f"objective {lo:.6g}..{hi:.6g}{unit}; best at {at}: {design}")
    bad = [c for c in ch.cells if not c.success]
    lines += [f"  no design at cell ({c.i}, {c.j}): {c.message}" for c in bad[:5]]
    if len(bad) > 5:
        lines.append(f"  ... and {len(bad) - 5} more cells without a design (their reasons are in --csv and --json)")
    return lines
