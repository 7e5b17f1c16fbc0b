"""The IPOPT backend's reading of how a run ended: a run stopped short of IPOPT's tolerance (its search direction
too small, or the iteration limit) counts as acceptable only at a KKT point relative to its own scale; and a run
that once never ended."""

from __future__ import annotations

from types import SimpleNamespace

import casadi
import numpy as np
import pytest

from qropt.synthesis import backends
from qropt.synthesis.backends import Ipopt
from tests.child import run_child

BOX = ([0.0, -10.0], [1.0, 10.0])


class _Form(SimpleNamespace):
    """A Formulation's parts (a backend keeps its solvers by weak reference, by identity)."""

    __hash__ = object.__hash__


def _form(scale):
    """min scale ((x - p)^2 + y^2) subject to x + y >= 1, x in [0, 1]: at p = 2 the optimum is x = 1 on its bound
    (multiplier 2 scale there), y = 0 with the constraint inactive."""
    w, p = casadi.SX.sym("w", 2), casadi.SX.sym("p")
    f = scale * ((w[0] - p) ** 2 + w[1] ** 2)
    return _Form(w_sym=w, p_sym=p, f_sym=f, g_sym=w[0] + w[1], lbg=np.array([1.0]), ubg=np.array([np.inf]))


def test_a_stalled_run_is_acceptable_only_where_the_lagrangian_is_stationary():
    for scale in (1.0, 1e6):  # N^2-sized rows: the test is relative to the gradients
        form = _form(scale)
        nlp = {"x": form.w_sym, "p": form.p_sym, "f": form.f_sym, "g": form.g_sym}
        args = dict(p=2.0, lbx=BOX[0], ubx=BOX[1], lbg=1, ubg=casadi.inf)
        quiet = {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "ipopt.tol": 1e-12}
        done = casadi.nlpsol("s", "ipopt", nlp, quiet)(x0=[0.5, 0.5], **args)
        assert abs(float(done["x"][0]) - 1.0) < 1e-7
        assert Ipopt()._stationary(form, done, 2.0, *BOX)
        early = casadi.nlpsol("s", "ipopt", nlp, {**quiet, "ipopt.max_iter": 1})(x0=[0.5, 0.5], **args)
        assert not Ipopt()._stationary(form, early, 2.0, *BOX)


def test_the_solvers_of_a_formulation_share_its_derivatives():
    """A re-solve of a dynamic objective runs with its objective scaled to order one at its start (one solver per
    scale), and from a small barrier (another backend): every solver of the formulation is given the derivatives
    its first one built (a solver that built its own held 70-80 MB; a long run held gigabytes of them), and each
    gives the value and multipliers of an unscaled solve."""
    backend = Ipopt()
    for scale in (1e3, 1e6):
        form = _form(scale)
        form.objective = SimpleNamespace(needs_masses=True)
        form.nlp = {"x": form.w_sym, "p": form.p_sym, "f": form.f_sym, "g": form.g_sym}
        form.objective_function = casadi.Function("f", [form.w_sym, form.p_sym], [form.f_sym])
        w0 = np.array([0.5, 0.5])
        assert backends.objective_scale(form, w0, 2.0) == {1e3: 1e-4, 1e6: 1e-7}[scale]
        plain = casadi.nlpsol("s", "ipopt", form.nlp, backends.IPOPT)  # the same options, unscaled
        ref = plain(x0=w0, p=2.0, lbx=BOX[0], ubx=BOX[1], lbg=form.lbg, ubg=form.ubg)
        for b, warm in ((backend, False), (backend, True), (backend.near(), True)):
            run = b.run(form, w0, 2.0, *BOX, warm=warm)
            assert run.f == pytest.approx(scale, rel=1e-9)  # x = 1 on its bound, y = 0
            assert run.f == pytest.approx(float(ref["f"]), rel=1e-9)
            assert run.lam_x[0] == pytest.approx(float(ref["lam_x"][0]), rel=1e-4)
            assert run.lam_x[0] == pytest.approx(2.0 * scale, rel=1e-4)
        solvers = [x for b in (backend, backend.near()) for x in b._solvers[form].values()]
        assert len(solvers) == 3
        first = backends._DERIVATIVES[form]
        for x in solvers:
            for option, name in backends.DERIVATIVES.items():
                assert x.get_function(f"nlp_{name}").__hash__() == first[option].__hash__()  # the same function


def test_a_quasi_newton_backend_shares_what_it_has():
    """IPOPT's limited-memory Hessian (``Solver(ipopt_options={"ipopt.hessian_approximation": "limited-memory"})``)
    builds no Hessian of the Lagrangian: its solver shares the gradient and Jacobian, built first or given, and an
    exact-Hessian solver of the same formulation after it builds and shares the Hessian; both reach the optimum."""
    form = _form(1.0)
    form.objective = None
    form.nlp = {"x": form.w_sym, "p": form.p_sym, "f": form.f_sym, "g": form.g_sym}
    quasi = Ipopt({"ipopt.hessian_approximation": "limited-memory"})
    for b in (quasi, Ipopt(), quasi.near()):
        run = b.run(form, np.array([0.5, 0.5]), 2.0, *BOX)
        assert run.f == pytest.approx(1.0, rel=1e-9), b.options
    assert set(backends._DERIVATIVES[form]) == set(backends.DERIVATIVES)
    assert not quasi.solver(form).has_function("nlp_hess_l")
    for option, name in backends.DERIVATIVES.items():
        if option != "hess_lag":
            assert (
                quasi.solver(form).get_function(f"nlp_{name}").__hash__()
                == backends._DERIVATIVES[form][option].__hash__()
            )


def test_a_run_whose_linear_solves_once_overflowed_ends():
    """The Whitworth by peak torque under a transmission guard of 10 deg, at TR 2.848, 0.834 m, from one of its Sobol
    starts: the KKT system of iteration 32 is solved to a step of norm 1e111, and with IPOPT's default of up to 10
    steps of iterative refinement (5 as well) the refinement overflows, the multipliers and the barrier parameter
    become NaN and IPOPT loops on its inertia correction for ever (in a child process here, so that a hang is a
    failure). IPOPT's options (``formulation.IPOPT``) stop the refinement after three steps: the system is found
    singular and perturbed."""
    code = (
        "import math\n"
        "import qropt\n"
        "from qropt import Solver\n"
        "from qropt.studies._design import type_problem\n"
        "p = type_problem('whitworth', 2.848, 0.834, objective='min_peak_torque', omega2=10.0,\n"
        "    masses=qropt.Masses.steel(4e-4, ram=20.0), loads=qropt.Loads(1000.0),\n"
        "    conditions={'gamma_min': math.radians(10.0)})\n"
        "v = {'r1': 0.07600918934948539, 'r2': 0.09318662849786412, 'r5': 0.27696642689436607,\n"
        "     'r6': 2.246338840940679, 'h': 1.6508812718154184}\n"
        "c = Solver().local_solve.run(p, v, {'sigma_slider': 1.0}, dict(p.targets), orientation=1, max_rounds=30,\n"
        "    bound=4982.675999639441)\n"
        "print(c.ok, c.iterations)\n"
    )
    ok, iterations = run_child(code, 120).split()
    assert int(iterations) > 0


def test_common_subexpression_elimination_is_an_ipopt_option():
    """``Solver(ipopt_options={"oracle_options": {"cse": True}})`` builds the NLP's functions with
    common-subexpression elimination: a subexpression written twice (here sin(x y), as a formulation's rows repeat a
    kinematic term) is computed once in the Hessian of the Lagrangian, which gives the values of the default one (to
    rounding); the default builds them without it."""
    w, p = casadi.SX.sym("w", 2), casadi.SX.sym("p")
    f = casadi.sin(w[0] * w[1]) ** 2 + p * casadi.sin(w[0] * w[1]) * w[1]
    g = casadi.vertcat(casadi.sin(w[0] * w[1]) + w[0], casadi.cos(w[0] * w[1]) * w[1])
    hessians = {}
    for name, options in (("default", None), ("cse", {"oracle_options": {"cse": True}})):
        form = _Form(w_sym=w, p_sym=p, f_sym=f, g_sym=g, lbg=np.array([-1.0, -1.0]), ubg=np.array([1.0, 1.0]))
        form.objective, form.nlp = None, {"x": w, "p": p, "f": f, "g": g}
        hessians[name] = Ipopt(options).solver(form).get_function("nlp_hess_l")
    plain = casadi.nlpsol("s", "ipopt", {"x": w, "p": p, "f": f, "g": g}, backends.IPOPT).get_function("nlp_hess_l")
    assert hessians["default"].n_instructions() == plain.n_instructions()
    assert hessians["cse"].n_instructions() < plain.n_instructions()
    rng = np.random.default_rng(0)
    for _ in range(5):
        x, lam_g = rng.uniform(-2.0, 2.0, 2), rng.uniform(-1.0, 1.0, 2)
        a, b = (np.array(hessians[k](x, 0.7, 1.3, lam_g)) for k in ("default", "cse"))
        assert np.allclose(a, b, rtol=1e-13, atol=1e-13)
