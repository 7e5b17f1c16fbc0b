"""A kernel group's refinement of extremes as one C loop around CasADi's generated Newton switch.

``Kernel.refine`` finds each requested quantity's sampled extremes (a sample at least its left neighbour and
above its right one, cyclically) and runs the batched Newton refinement from each. In numpy that takes a dozen
array operations around the compiled Newton call, which cost more than its arithmetic. Here it is one call into C
that runs the same generated function on the same numbers in the same order, so the results are those of the
numpy route to the last bit (``tests/test_native.py``). Built through ``native`` (the machine's C compiler, its
flags and cache); None where no compiler works.
"""

from __future__ import annotations

import ctypes
import threading

import casadi
import numpy as np

from qropt.kinematics import native

# the Newton switch: z = (quantity index, theta, h, the three signed samples around it, sign, p) -> (theta,
# converged, value). Hit k is column k of out (5, cap): request, grid index, theta,
# converged, value; request r's hits start at starts[r], starts[R] is their count and starts[R + 1] the number not
# converged. A negative return: more hits than cap, or a failed call.
_DRIVER = r"""
#define QROPT_WORK(f, a, r, i, w) casadi_int a, r, i, w; f##_work(&a, &r, &i, &w); \
  const casadi_real* arg_[a > 1 ? a : 1]; casadi_real* res_[r > 1 ? r : 1]; \
  casadi_int iw_[i > 0 ? i : 1]; casadi_real w_[w > 0 ? w : 1];

CASADI_SYMBOL_EXPORT long long qropt_refine(const double* q, long long n, double h, const long long* rows,
                                            const double* sgn, long long nr, const double* p, long long np,
                                            double* out, long long* starts, long long cap) {
  QROPT_WORK(qropt_newton, sa, sr, si, sw)
  double z[7 + np], res[3];
  long long k = 0, bad = 0;
  for (long long j = 0; j < np; ++j) z[7 + j] = p[j];
  for (long long r = 0; r < nr; ++r) {
    const double* v = q + rows[r] * n;
    const double s = sgn[r];
    starts[r] = k;
    for (long long i = 0; i < n; ++i) {
      const double a = s * v[i == 0 ? n - 1 : i - 1], b = s * v[i], c = s * v[i == n - 1 ? 0 : i + 1];
      if (!(b >= a && b > c)) continue;
      if (k >= cap) return -1;
      z[0] = (double)rows[r];
      z[1] = (double)i * h;
      z[2] = h;
      z[3] = a;
      z[4] = b;
      z[5] = c;
      z[6] = s;
      arg_[0] = z;
      res_[0] = res;
      if (qropt_newton(arg_, res_, iw_, w_, 0)) return -2;
      out[k] = (double)r;
      out[cap + k] = (double)i;
      out[2 * cap + k] = res[0];
      out[3 * cap + k] = res[1];
      out[4 * cap + k] = res[2];
      bad += res[1] == 0.0;
      ++k;
    }
  }
  starts[nr] = k;
  starts[nr + 1] = bad;
  return k;
}
"""

_P = ctypes.c_void_p
_I = ctypes.c_longlong


def _pointer(a: np.ndarray) -> int:
    return a.__array_interface__["data"][0]


class Driver:
    """The C loop of one kernel group's refinement (``refine``), with its buffers kept per request list and grid,
    per thread (ctypes runs the call without Python's lock), for at most KEPT of them."""

    KEPT = 64  # request lists whose buffers are kept

    def __init__(self, lib: ctypes.CDLL):
        self._refine = lib.qropt_refine
        self._refine.restype = _I
        self._refine.argtypes = [_P, _I, ctypes.c_double, _P, _P, _I, _P, _I, _P, _P, _I]
        self._lib = lib  # kept alive with its function
        self._local = threading.local()  # .calls: (rows, signs, n) -> (the call's fixed arguments, its buffers)

    def refine(self, q: np.ndarray, h: float, rows: np.ndarray, sgn: np.ndarray, p: np.ndarray):
        """Every sampled extreme in q (Q, n, C order) of the requests (rows (R,) int64, signs (R,): +1 a maximum,
        -1 a minimum), refined from the grid spacing h: (hits (5, K): request, grid index, theta, converged,
        value; the list of where each request's hits start, R + 1 entries, then the number not converged), or
        None if the call fails. The hits are a view of a buffer the next call with these requests overwrites."""
        n = q.shape[1]
        key = (id(rows), id(sgn), n)
        calls = getattr(self._local, "calls", None)
        if calls is None:
            calls = self._local.calls = {}
        call = calls.get(key)
        if call is None:
            if len(calls) >= self.KEPT:
                calls.clear()
            cap = rows.size * (n // 2 + 1)
            out, starts = np.empty((5, cap)), np.empty(rows.size + 2, np.int64)
            fixed = (_pointer(rows), _pointer(sgn), rows.size)
            call = calls[key] = (fixed, (_pointer(out), _pointer(starts), cap), out, starts, (rows, sgn))
        fixed, buffers, out, starts, _ = call
        k = self._refine(_pointer(q), n, h, *fixed, _pointer(p), p.size, *buffers)
        if k < 0:
            return None
        return out[:, :k], starts.tolist()


def build(newton: casadi.Function, name: str) -> Driver | None:
    """The driver of a group's Newton switch (``Kernel._switch``'s row function), or None where no compiler
    works."""
    if not native.enabled():
        return None
    try:
        z = newton.mx_in(0)
        lib = native.library(name, native.source(casadi.Function("qropt_newton", [z], [newton(z)])) + _DRIVER)
        return None if lib is None else Driver(ctypes.CDLL(str(lib)))
    except (OSError, RuntimeError):  # as native.compiled: the numpy route instead
        return None


__all__ = ["Driver", "build"]
