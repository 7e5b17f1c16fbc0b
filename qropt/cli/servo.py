"""``qropt servo``: the fastest crank-speed profile of a servo-driven crank within speed, acceleration,
cutting-speed and torque limits (qropt.servo)."""

from __future__ import annotations

import argparse
import csv
import json
import sys

import numpy as np

from qropt.convex.servo import OBJECTIVES, speed_profile
from qropt.mechanisms import REGISTRY, type_reference
from qropt.validate import picture_path

COMMAND = "servo"
HELP = "fastest crank-speed profile of a servo-driven crank within speed, acceleration and torque limits"
EXAMPLES = (
    "qropt servo --omega-max 13 --alpha-max 200 --force 1000 --inertia 1 --torque-max 113",
    "qropt servo slider-crank --r2 0.1 --r3 0.4 --omega-max 20 --v-cut 0.5 --a-max 40 --alpha-max 400 --v-max 2",
)
LIMITS = ("omega_max", "alpha_max", "v_max", "a_max", "v_cut", "force", "inertia", "torque_max")
UNITS = {
    "omega_max": "rad/s",
    "alpha_max": "rad/s^2",
    "v_max": "m/s",
    "a_max": "m/s^2",
    "v_cut": "m/s",
    "force": "N",
    "inertia": "kg m^2",
    "torque_max": "N m",
}
# the servo's dynamics add force x length to inertia x alpha: its designs are given in metres (SI) only


def add_mechanism_arguments(parser: argparse.ArgumentParser) -> None:
    """TYPE (default: the paper's drag-link mechanism) and its parameters --r1 ... --sigma-slider."""
    from qropt.cli import param_argument, param_flags, type_argument

    type_argument(parser)
    param_flags(parser, float)
    param_argument(parser)


def mechanism_from(args):
    """The mechanism named by args (InvalidParameter for an unknown type or bad parameters)."""
    from qropt.cli import PARAM_NAMES, cli_type, flag_params, mechanism_params

    given = {**flag_params(args, PARAM_NAMES), **dict(args.param)}
    if args.type is None and not given:
        from qropt.examples import paper_mechanism

        return paper_mechanism()
    if args.type is None:
        from qropt.errors import InvalidParameter

        raise InvalidParameter("give the mechanism TYPE before its parameters: " + ", ".join(sorted(REGISTRY)))
    cls = cli_type(args.type)
    return cls(**mechanism_params(args, cls, PARAM_NAMES))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_mechanism_arguments(parser)
    parser.add_argument("--omega-max", type=float, required=True, help="largest crank speed, rad/s")
    for k in LIMITS[1:]:
        what = {
            "force": "cutting force on the working stroke",
            "inertia": "crank-reduced moment of inertia",
            "v_cut": "constant cutting speed over the central cut fraction",
        }.get(k, "limit")
        parser.add_argument(f"--{k.replace('_', '-')}", dest=k, type=float, help=f"{what}, {UNITS[k]}")
    parser.add_argument("--cut-fraction", type=float, default=0.8, help="cut share of the working travel (0.8)")
    parser.add_argument(
        "--objective",
        choices=OBJECTIVES,
        default=OBJECTIVES[0],
        help=f"what the profile minimises: {' or '.join(OBJECTIVES)} (then the shortest cycle among the fastest "
        f"returns); default {OBJECTIVES[0]}",
    )
    parser.add_argument("--n", type=int, default=720, help="cells per turn (>= 36, default 720)")
    parser.add_argument("--plot", help="PNG file: omega2, slider v and a (and torque) against time")
    parser.add_argument("--csv", help="file for the profile, one row per node ('-': standard output)")
    parser.add_argument("--json", action="store_true", help="print JSON instead of text")


def summary(p, m) -> dict:
    """The profile's numbers as plain JSON-ready values."""
    out = {
        "type": type_reference(type(m)),
        "params": dict(m.params),
        "status": p.status,
        "message": p.message,
        "limits": {k: v for k, v in p.limits.items() if v is not None},
        "binding": list(p.binding),
        "constant_speed": p.constant_speed()._asdict(),
    }
    if p.time is not None:
        out.update(
            cycle_time=p.cycle_time,
            working_time=p.working_time,
            return_time=p.return_time,
            time_ratio=p.time_ratio,
            peak_torque=p.peak_torque,
            cells=int(p.alpha.size),
            excess=p.check(),
        )
    return out


def write_csv(p, path: str) -> None:
    s = p.motion(1)
    f = sys.stdout if path == "-" else open(path, "w", newline="")  # noqa: SIM115
    try:
        w = csv.writer(f)
        w.writerow(["t", "theta2_deg", "omega2", "alpha2", "x", "v", "a", "torque"])
        for i in range(0, s.t.size, 2):  # each cell's first sample: the node, alpha2 of the cell it starts
            w.writerow([f"{q[i]:.12g}" for q in (s.t, np.degrees(s.theta), s.omega, s.alpha, s.x, s.v, s.a, s.torque)])
    finally:
        if f is not sys.stdout:
            f.close()


def run(args) -> int:
    if args.plot is not None:
        picture_path(args.plot)  # before solving: a bad path is refused at once
    m = mechanism_from(args)
    limits = {k: getattr(args, k) for k in LIMITS}
    p = speed_profile(m, **limits, cut_fraction=args.cut_fraction, objective=args.objective, n=args.n)
    r = summary(p, m)
    if args.json:
        json.dump(r, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"{type_reference(type(m))}: " + ", ".join(f"{k}={v:g}" for k, v in m.params.items()))
        print("  limits            " + ", ".join(f"{k} {v:g} {UNITS[k]}" for k, v in r["limits"].items()))
        if p.force or p.inertia:
            print(f"  load              force {p.force:g} N on the working stroke, inertia {p.inertia:g} kg m^2")
        print(f"  status            {p.status}: {p.message}")
        if p.time is not None:
            c = p.constant_speed()
            print(
                f"  cycle time        {p.cycle_time:.6f} s ({p.working_time:.6f} s working, "
                f"{p.return_time:.6f} s return); {c.cycle_time:.6f} s at constant omega_max"
            )
            print(f"  time ratio        {p.time_ratio:.6f}; {c.time_ratio:.6f} at constant speed")
            if p.peak_torque is not None:
                ref = "" if c.peak_torque is None else f"; {c.peak_torque:.6g} at constant speed"
                print(f"  peak torque       {p.peak_torque:.6g} N m{ref}")
            print(
                "  largest excess    "
                + ", ".join(f"{k} {v:+.2e}" for k, v in r["excess"].items())
                + " (relative, exact simulation 10x finer)"
            )
    if p.time is not None and args.csv:
        write_csv(p, args.csv)
    if p.time is not None and args.plot:
        p.plot(args.plot)
        if not args.json:
            print(f"  picture written to {args.plot}")
    return 0 if p.status in ("optimal", "acceptable") else 1
