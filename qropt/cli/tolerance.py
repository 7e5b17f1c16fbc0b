"""``qropt tolerance``: exact sensitivities and the largest link tolerances that keep the time ratio, stroke,
gamma_min or peak acceleration within limits (qropt.tolerance), with a Monte Carlo check."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from qropt import units as units_
from qropt.convex.tolerance import QUANTITIES, allocate
from qropt.errors import InvalidParameter
from qropt.mechanisms import REGISTRY, mechanism_type, type_reference

COMMAND = "tolerance"
HELP = "exact sensitivities and the largest tolerances keeping TR, stroke, gamma_min within limits"
LENGTH_UNITS = {u: units_.LENGTH_UNITS[u] for u in ("um", "mm", "cm", "m")}  # a limit's suffixes, in metres
ANGLE_UNITS = {"deg": math.pi / 180, "rad": 1.0}
EXAMPLES = (
    "qropt tolerance --limit time_ratio=0.01 --limit stroke=1mm --monte-carlo 10000",
    "qropt tolerance slider-crank --r2 100 --r3 350 --e 60 --units mm --limit stroke=0.5mm",
)
PAPER_UNIT = "m"  # the paper's mechanism (the default design) is given in metres


def limit(text: str) -> tuple[str, float, str | None]:
    """'QUANTITY=VALUE[unit]' -> (quantity, value, unit or None). time_ratio is dimensionless (no unit); gamma_min
    takes deg or rad (a plain number is rad); stroke takes um, mm, cm or m, converted in ``run`` to the design's
    length unit (a plain number is in the design's unit); peak_acceleration is a plain number (the design's
    length unit/s^2)."""
    name, sep, value = text.partition("=")
    name = name.strip()
    if not sep or name not in QUANTITIES:
        raise argparse.ArgumentTypeError(
            f"not a limit: {text!r} (use e.g. time_ratio=0.01 or stroke=0.001; quantities: {', '.join(QUANTITIES)})"
        )
    v = value.strip().lower()
    unit = next((u for u in sorted({**LENGTH_UNITS, **ANGLE_UNITS}, key=len, reverse=True) if v.endswith(u)), None)
    if unit is not None:
        v = v[: -len(unit)].strip()
        allowed = {"gamma_min": ANGLE_UNITS, "stroke": LENGTH_UNITS}.get(name, {})
        if unit not in allowed:
            why = {
                "time_ratio": "the time ratio is dimensionless",
                "gamma_min": "gamma_min is an angle (deg, rad)",
                "stroke": "the stroke is a length (um, mm, cm, m)",
                "peak_acceleration": "give the peak acceleration as a plain number in length/s^2 of the design's unit",
            }[name]
            raise argparse.ArgumentTypeError(f"unit {unit!r} does not apply in the limit {text!r}: {why}")
    try:
        number = float(v)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"not a number in the limit {text!r} (units: {', '.join([*LENGTH_UNITS, *ANGLE_UNITS])})"
        ) from None
    if unit in ANGLE_UNITS:
        number, unit = number * ANGLE_UNITS[unit], None
    return name, number, unit


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.cli import param_flags, type_argument, units_argument

    type_argument(
        parser,
        "target",
        more=" (or a JSON file with 'type' and 'params', as 'qropt synth --json' or 'qropt analyze --json' print)",
    )
    param_flags(parser, float)
    parser.add_argument(
        "--limit",
        type=limit,
        action="append",
        required=True,
        metavar="QUANTITY=VALUE",
        help="allowed deviation, once per quantity: time_ratio=0.01, stroke=0.001 (the design's "
        "length unit) or stroke=1mm (a design whose unit is stated), gamma_min=1deg",
    )
    units_argument(
        parser,
        "the design's length unit: states it for TYPE and parameters (so that a stroke limit may carry a unit "
        "suffix); a design file or the paper's mechanism (m) states its own, which --units may only repeat",
    )
    parser.add_argument("--params", help="toleranced parameters, comma-separated (default: lengths and offsets)")
    parser.add_argument("--rss", action="store_true", help="statistical stack-up ||S t|| <= E / k")
    parser.add_argument("--k", type=float, default=3.0, help="rss: limit over k (default 3)")
    parser.add_argument("--omega2", type=float, help="crank speed, rad/s, for a peak_acceleration limit")
    parser.add_argument("--monte-carlo", type=int, metavar="N", help="check the allocation on N random mechanisms")
    parser.add_argument("--seed", type=int, default=0, help="Monte Carlo seed (default 0)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def design_from(args):
    """(the mechanism, its stated length unit or None): from TYPE and --r1 ... (stated by --units), from a JSON
    file (its "units", which --units may repeat but not contradict), or the paper's mechanism (in m)."""
    from qropt.cli import PARAM_NAMES, CliError

    given = {k: getattr(args, k) for k in PARAM_NAMES if getattr(args, k) is not None}
    override = getattr(args, "units", None)
    if args.target is None:
        if given:
            raise InvalidParameter("give the mechanism TYPE before its parameters: " + ", ".join(sorted(REGISTRY)))
        from qropt.examples import paper_mechanism

        declared, m, where = PAPER_UNIT, paper_mechanism(), "the paper's mechanism"
    elif args.target.endswith(".json") or (Path(args.target).exists() and not Path(args.target).is_dir()):
        from qropt.io.export import declared_unit, read_design

        d = read_design(args.target)
        declared = declared_unit(d)
        params = {**d["params"], **given}
        m, where = mechanism_type(d["type"])(**params, units=declared or override or units_.DEFAULT), args.target
    else:
        return mechanism_type(args.target)(**given, units=override or units_.DEFAULT), override
    if declared is not None and override is not None and override != declared:
        raise CliError(f"--units {override} contradicts {where}, which is in {declared}")
    return m, declared or override


def _finite(v):
    """Strict JSON: infinite tolerances (no limited quantity depends on the parameter) become null."""
    if isinstance(v, dict):
        return {k: _finite(x) for k, x in v.items()}
    return None if isinstance(v, float) and not math.isfinite(v) else v


def limits_from(args, design_unit: str | None = None) -> dict:
    """{quantity: limit} in the design's units: each quantity once, a suffixed length converted to the design's
    length unit (``design_unit``: the one its file or --units states, metres for the default design) or refused
    where that unit is not stated."""
    from qropt.cli import CliError

    out = {}
    for name, value, unit in args.limit:
        if name in out:
            raise CliError(f"--limit {name} is given more than once; give each quantity one limit")
        if unit is not None:
            if design_unit is None:
                raise CliError(
                    f"--limit {name}={value:g}{unit}: this design's length unit is not declared (qropt "
                    "lengths are in the design's own unit); give --units, or the limit as a plain number "
                    "in the design's unit"
                )
            value *= units_.to_metres(unit) / units_.to_metres(design_unit)
        out[name] = value
    return out


def run(args) -> int:
    m, design_unit = design_from(args)
    limits = limits_from(args, design_unit)
    params = None if args.params is None else [p.strip() for p in args.params.split(",") if p.strip()]
    al = allocate(m, limits, params=params, method="rss" if args.rss else "worst-case", k=args.k, omega2=args.omega2)
    mc = None
    if al.status == "optimal" and args.monte_carlo is not None:
        mc = al.monte_carlo(args.monte_carlo, seed=args.seed)
    if args.json:
        out = {
            "type": type_reference(type(m)),
            "params": dict(m.params),
            "units": m.units,
            "status": al.status,
            "message": al.message,
            "method": al.method,
            "k": al.k,
            "limits": al.limits,
            "tolerances": al.tolerances,
            "sensitivities": al.sensitivities,
            "usage": al.usage,
        }
        if mc is not None:
            out["monte_carlo"] = {
                "n": mc.n,
                "within": mc.within,
                "worst": mc.worst,
                "all_within": mc.all_within,
                "linearisation": mc.linearisation,
                "failed": mc.failed,
            }
        json.dump(_finite(out), sys.stdout, indent=2)
        sys.stdout.write("\n")
        return 0 if al.status == "optimal" else 1
    stated = m.units if design_unit else "not stated"
    print(f"{type_reference(type(m))} (lengths: {stated}): " + ", ".join(f"{k}={v:g}" for k, v in m.params.items()))
    rule = "sum |S| t <= E" if al.method == "worst-case" else f"||S t|| <= E / {al.k:g}"
    print(f"  {al.method} ({rule}); status {al.status}: {al.message}")
    if al.status != "optimal":
        return 1
    qs = list(al.limits)
    print(f"  {'param':8s} {'nominal':>12s} {'tolerance':>12s} " + " ".join(f"{'d' + q + '/dp':>20s}" for q in qs))
    for p, t in al.tolerances.items():
        sens = " ".join(f"{al.sensitivities[q][p]:20.6g}" for q in qs)
        print(f"  {p:8s} {m.params[p]:12.6g} {'+/- ' + format(t, '.4g'):>12s} {sens}")
    for q in qs:
        print(f"  {q}: limit {al.limits[q]:.6g}, stack-up uses {100 * al.usage[q]:.4g}% of it")
    if mc is not None:
        print(f"  Monte Carlo, {mc.n} mechanisms (exact re-analysis), {mc.failed} not analysable:")
        for q in qs:
            print(
                f"    {q}: {100 * mc.within[q]:.2f}% within, worst |deviation| {mc.worst[q]:.6g}, "
                f"linearisation error <= {mc.linearisation[q]:.3g}"
            )
        print(f"    every limit met: {100 * mc.all_within:.2f}%")
    return 0
