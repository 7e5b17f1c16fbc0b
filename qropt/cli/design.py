"""``qropt design``: one task (time ratio, stroke) solved for every quick-return type and compared."""

from __future__ import annotations

import argparse
import math

COMMAND = "design"
HELP = "type synthesis: the task solved for every quick-return type, compared criterion by criterion"
EXAMPLES = (
    "qropt design --tr 1.5 --stroke 0.3 --objective min_size --gamma-min 40deg --types whitworth slider-crank",
    "qropt design --tr 1.5 --stroke 300 --units mm --types slider-crank whitworth",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from qropt.cli import TIME_LIMIT_HELP, loads_arguments, objective_help, real, units_argument
    from qropt.studies._design import TYPES
    from qropt.synthesis import criteria
    from qropt.units import DEFAULT

    parser.add_argument("--tr", type=real, required=True, help="time ratio (slow/fast, >= 1)")
    parser.add_argument("--stroke", type=real, required=True, help="slider stroke [in --units]")
    units_argument(parser, "the length unit of the stroke, the bounds and the answer", default=DEFAULT)
    parser.add_argument(
        "--objective",
        default="max_gamma_min",
        choices=[o for o in criteria.objectives() if o],
        help=objective_help(more=" (default max_gamma_min)"),
    )
    parser.add_argument(
        "--size",
        default="footprint",
        choices=["sum", "longest", "footprint"],
        help="size measure of min_size (default footprint)",
    )
    parser.add_argument(
        "--types",
        nargs="+",
        metavar="TYPE",
        help="types (default all): " + ", ".join(TYPES) + ", or any slider type's KIND or module:Class",
    )
    bound_flags(parser)
    parser.add_argument("--omega2", type=real, default=1.0, help="crank speed [rad/s] (default 1)")
    parser.add_argument("--density", type=real, help="links as uniform bars of this many kg per metre (dynamics)")
    parser.add_argument("--ram-mass", dest="ram_mass", type=real, help="the ram's mass, kg (dynamics)")
    loads_arguments(parser, instead=" (dynamics: every type's solve)")
    parser.add_argument(
        "--drive",
        nargs="+",
        type=real,
        metavar=("RATIO", "EFFICIENCY"),
        help="the gearbox: ratio (motor speed / crank speed) and efficiency (default 1), for min_rms_motor_torque",
    )
    parser.add_argument(
        "--balance",
        nargs=2,
        type=real,
        metavar=("RADIUS", "MAX_MASS"),
        help="a crank counterweight each solve chooses: at RADIUS m, up to MAX_MASS kg (dynamics)",
    )
    parser.add_argument("--pareto", nargs=2, metavar=("A", "B"), help="also each type's front between two objectives")
    parser.add_argument("--n", type=int, default=12, help="front points per type with --pareto (default 12)")
    parser.add_argument("--workers", type=int, help="solve the types in this many worker processes")
    parser.add_argument("--time-limit", dest="time_limit", type=real, help=TIME_LIMIT_HELP)
    parser.add_argument("--csv", metavar="FILE", help="write the comparison table as CSV")
    parser.add_argument("--json", action="store_true", help="print the comparison as JSON")
    parser.add_argument("--plot", metavar="FILE", help="draw the designs side by side (.png, .pdf, .svg)")


def bound_flags(parser) -> None:
    """A flag per bound condition, from the criteria: --gamma-min (an angle), --max-footprint, --max-sum, ..."""
    from qropt.cli import angle, real
    from qropt.synthesis import criteria

    for key, c in criteria.bounds().items():
        side = "lower" if c.maximise else "upper"
        unit = "e.g. 40deg" if c.unit == "rad" else c.unit.replace("length", "the length unit")
        parser.add_argument(
            c.flag, dest=key, type=angle if c.unit == "rad" else real, help=f"{side} bound on {c.name} [{unit}]"
        )


def conditions_of(args) -> dict:
    """The bound conditions given on the command line."""
    from qropt.synthesis import criteria

    return {k: getattr(args, k) for k in criteria.bounds() if getattr(args, k, None) is not None}


def dynamics_of(args) -> tuple:
    """(masses, loads) from the dynamics flags (the loads as ``qropt.cli.loads_of`` reads them), each None where
    none of its flags is given."""
    from qropt.cli import loads_of, point_masses
    from qropt.dynamics.model import Counterweight, Masses

    masses = None
    balance = getattr(args, "balance", None)
    points = point_masses(args)
    if args.density is not None or args.ram_mass is not None or balance or points:
        cw = Counterweight.balancing(*balance) if balance else None
        masses = Masses.bars(args.density or 0.0, args.ram_mass or 0.0, counterweight=cw, points=points)
    return masses, loads_of(args)


def run(args) -> int:
    from qropt.cli import cli_type, picture_path, progress_bar
    from qropt.studies._design import TYPES, design

    plot = picture_path(args.plot) if args.plot else None
    types = None if args.types is None else [cli_type(t) if ":" in t else t for t in args.types]
    n_types = len(args.types or TYPES)
    masses, loads = dynamics_of(args)
    drive = None
    if args.drive is not None:
        from qropt.dynamics.drive import Drive
        from qropt.errors import InvalidParameter

        if len(args.drive) > 2:
            raise InvalidParameter(f"--drive takes RATIO [EFFICIENCY], got {len(args.drive)} numbers")
        drive = Drive(*args.drive)
    with progress_bar("types", total=n_types, unit="type") as bar:
        cmp = design(
            args.tr,
            args.stroke,
            objective=args.objective,
            types=types,
            size=args.size,
            conditions=conditions_of(args),
            omega2=args.omega2,
            pareto=tuple(args.pareto) if args.pareto else None,
            n=args.n,
            progress=bar.update,
            units=args.units,
            masses=masses,
            loads=loads,
            drive=drive,
            workers=args.workers,
            time_limit=args.time_limit,
        )
    if args.csv:
        cmp.to_csv(args.csv)
    if plot:
        cmp.plot(plot)
    code = 0 if any(r.success for r in cmp.rows) else 1
    if args.json:
        print(cmp.to_json())
        return code
    u = cmp.units
    print(f"TR {args.tr:g}, stroke {args.stroke:g} {u}, omega2 {args.omega2:g} rad/s: best by {args.objective} first")
    print(
        f"  {'type':20s} {'gamma_min':>10s} {'footprint':>11s} {'sum':>8s} {'peak accel':>11s} "
        f"{'peak v':>9s} {'T/F':>8s}"
    )
    print(
        f"  {'':20s} {'[deg]':>10s} {f'[{u}^2]':>11s} {f'[{u}]':>8s} {f'[{u}/s^2]':>11s} {f'[{u}/s]':>9s} "
        f"{f'[{u}]':>8s}"
    )
    for r in cmp.rows:
        if not r.success:
            print(f"  {r.type:20s} no design: {r.reason}")
            continue
        c = r.criteria
        print(
            f"  {r.type:20s} {math.degrees(c['gamma_min']):10.3f} {c['footprint']:11.4g} {c['sum']:8.4g} "
            f"{c['peak_accel']:11.4g} {c['peak_velocity']:9.4g} {c['torque_per_newton']:8.4g}"
        )
    dynamic = [r for r in cmp.rows if r.success and r.criteria.get("peak_torque") is not None]
    if dynamic:
        print("  dynamics at omega2 (N m; N):")
        for r in dynamic:
            c = r.criteria
            motor = c.get("rms_motor_torque")
            print(
                f"  {r.type:20s} peak torque {c['peak_torque']:10.4g}  RMS torque {c['rms_torque']:10.4g}  "
                f"peak shaking force {c['shaking_force']:10.4g}"
                + ("" if motor is None else f"  RMS motor torque {motor:10.4g}")
            )
    for r in cmp.rows:
        cw = r.result.counterweight if r.success else None
        if cw is not None:
            at = math.degrees(cw.angle)
            print(f"  {r.type:20s} counterweight {cw.mass:.4g} kg at {cw.radius:g} m, {at:.1f} deg from the crank pin")
    print(f"  (T/F: peak crank torque per newton of cutting force, N {u} per N)")
    if args.csv:
        print(f"table written to {args.csv}")
    if plot:
        print(f"picture written to {plot}")
    return code
