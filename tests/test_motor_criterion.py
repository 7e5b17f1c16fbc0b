"""The drive's criterion, the RMS torque at the motor (``min_rms_motor_torque``): the NLP's quadrature of the motor's
torque (the crank torque over i eta where the motor drives, times eta over i where it brakes) is its exact value at
random designs of every type, and within 3e-5 of the drive check's (split where the motor turns to braking); through
a lossless gearbox its optimum is the crank's RMS optimum over i; with losses and a load that drives part of the
turn it is the best of a refined dense scan of a closed-form family."""

from __future__ import annotations

import math

import casadi
import numpy as np
import pytest

import qropt
from qropt import Drive, Force, Loads, Motor
from qropt.errors import ProblemError
from qropt.studies._design import type_problem
from qropt.synthesis import analytic, criteria
from tests.test_dynamic_criteria import KINDS, MASSES, _at_random_design

DRIVE = Drive(15.0, 0.8)
DRIVING = Loads(800.0, gravity=(-9.81, 0.0))  # gravity along the stroke: it drives the ram down part of the turn


@pytest.mark.parametrize("kind", [*KINDS, "slot-ram-shaper"])
def test_the_nlps_motor_rms_is_the_exact_one(kind):
    p, m, f, w, pv, *_ = _at_random_design(kind, "min_rms_motor_torque", 3, DRIVING, drive=DRIVE)
    c = criteria.of("min_rms_motor_torque")
    value = float(casadi.Function("f", [f.w_sym, f.p_sym], [f.f_sym])(w, pv))
    assert c.from_nlp(value, 7.0) == pytest.approx(c.value(p, m), rel=1e-9)
    check = m.drive_check(DRIVE, 7.0, masses=MASSES, loads=DRIVING)  # its rule is split where the torque is zero
    assert check.rms_torque == pytest.approx(c.value(p, m), rel=3e-5)
    d = m.dynamics(np.linspace(0, 2 * np.pi, 721), 7.0, masses=MASSES, loads=DRIVING).torque
    assert d.min() < 0 < d.max()  # the motor drives and brakes: both of its rules count


def _problem(objective, drive, loads=DRIVING):
    return type_problem(
        "crank-shaper", 1.5, 0.3, objective=objective, masses=MASSES, loads=loads, omega2=10.0, drive=drive
    )


def test_through_a_lossless_gearbox_it_is_the_cranks_rms_over_the_ratio():
    motor = qropt.solve(_problem("min_rms_motor_torque", Drive(15.0)))
    crank = qropt.solve(_problem("min_rms_torque", None))
    assert motor.status == crank.status == "optimal"
    assert motor.objective == pytest.approx(crank.objective / 15.0, rel=1e-9)


def test_with_losses_the_optimum_is_the_best_of_a_dense_scan_and_the_drive_checks_rms():
    p = _problem("min_rms_motor_torque", DRIVE)
    r = qropt.solve(p)
    assert r.status in ("optimal", "acceptable"), r.message
    c = criteria.of("min_rms_motor_torque")
    k = analytic.crank_shaper_ratio(1.5)

    def value(r1):
        return c.value(p, qropt.CrankShaper(r1=r1, r2=k * r1, r4=0.3 / (2 * k)))

    r1 = np.geomspace(max(p.free["r1"][0], p.free["r2"][0] / k), min(p.free["r1"][1], p.free["r2"][1] / k), 400)
    best = math.inf
    for _ in range(4):  # a scan, then three refinements about its best
        values = [value(v) for v in r1]
        i = int(np.argmin(values))
        best = min(best, values[i])
        r1 = np.linspace(r1[max(i - 1, 0)], r1[min(i + 1, r1.size - 1)], 100)
    assert r.objective <= best * (1 + 1e-9)
    assert r.objective == pytest.approx(best, rel=1e-6)
    check = r.mechanism.drive_check(DRIVE, 10.0, masses=MASSES, loads=DRIVING)
    assert check.rms_torque == pytest.approx(r.objective, rel=3e-5)
    crank = qropt.solve(_problem("min_rms_torque", None))
    assert r.objective < c.value(p, crank.mechanism)  # the losses move the optimum


def test_the_problem_carries_its_drive_and_says_when_it_needs_one():
    drive = Drive(12.0, 0.9, 0.01, motor=Motor.constant(5.0, rated_torque=4.0))
    p = _problem("min_rms_motor_torque", drive, Loads(forces=[Force("C", 500.0, "against", "working")]))
    for back in (qropt.Problem.from_dict(p.to_dict()), qropt.Problem.from_toml(p.to_toml())):
        assert back.drive == drive
    assert Drive.from_dict(Drive(3.0, motor=Motor.line(2.0, 100.0)).to_dict()).motor.free_speed == 100.0
    with pytest.raises(ProblemError, match="needs the drive"):
        _problem("min_rms_motor_torque", None)
    with pytest.raises(ProblemError, match="drive"):
        qropt.Problem.from_dict({**p.to_dict(), "drive": {"ratio": -2.0}})


def test_the_command_line_designs_by_the_motor(capsys):
    from qropt import cli

    argv = ["design", "--tr", "1.5", "--stroke", "0.3", "--objective", "min_rms_motor_torque", "--density", "3.14"]
    argv += ["--ram-mass", "20", "--force", "1000", "--omega2", "10", "--types", "crank-shaper"]
    assert cli.main([*argv, "--drive", "15", "0.9"]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if "RMS motor torque" in x)
    masses, loads = qropt.Masses.bars(3.14, 20.0), Loads(1000.0)
    r = qropt.design(
        1.5,
        0.3,
        objective="min_rms_motor_torque",
        masses=masses,
        loads=loads,
        omega2=10.0,
        drive=Drive(15.0, 0.9),
        types=["crank-shaper"],
    )
    assert float(line.split()[-1]) == pytest.approx(r.rows[0].result.objective, rel=1e-3)
    for bad, words in ((["--drive", "15", "1.5"], "efficiency"), ([], "needs the drive")):
        assert cli.main([*argv, *bad]) != 0
        err = capsys.readouterr().err
        assert words in err and len(err.strip().splitlines()) == 1
