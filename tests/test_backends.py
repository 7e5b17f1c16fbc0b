"""The IPOPT backend's reading of how a run ended: a run stopped short of IPOPT's tolerance (its search direction
too small, or the iteration limit) counts as acceptable only at a KKT point relative to its own scale."""

from __future__ import annotations

from types import SimpleNamespace

import casadi
import numpy as np

from qropt.synthesis.backends import Ipopt

BOX = ([0.0, -10.0], [1.0, 10.0])


def _form(scale):
    """min scale ((x - p)^2 + y^2) subject to x + y >= 1, x in [0, 1]: at p = 2 the optimum is x = 1 on its bound
    (multiplier 2 scale there), y = 0 with the constraint inactive."""
    w, p = casadi.SX.sym("w", 2), casadi.SX.sym("p")
    f = scale * ((w[0] - p) ** 2 + w[1] ** 2)
    return SimpleNamespace(w_sym=w, p_sym=p, f_sym=f, g_sym=w[0] + w[1], lbg=np.array([1.0]), ubg=np.array([np.inf]))


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
