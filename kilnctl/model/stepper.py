"""Compiled per-mode stepper: generated model C code driven by ``rosenbrock.c``.

For one mode of a plant, CasADi generates C for the right-hand side f, its
Jacobian df/dx, df/dt and the guards; gcc links them with the ROS3P driver of
``rosenbrock.c`` into one shared library (cached on disk by source hash).  The
simulator calls :meth:`Stepper.run` through ctypes with numpy buffers: the
whole stepping loop, dense output and guard checking after every accepted
step run in C.
"""

from __future__ import annotations

import ctypes
from dataclasses import dataclass
from importlib import resources

import casadi as ca
import numpy as np

from .compiled import compile_sources, generate_c

__all__ = ["Stepper", "build_stepper", "STATUS"]

#: meaning of kiln_run's return codes
STATUS = {0: "reached t_end", 1: "event", 2: "output buffer full", -1: "singular iteration matrix",
          -2: "model function error or non-finite state", -3: "step size underflow", -4: "too many steps",
          -5: "too many states or guards for the compiled stepper", -6: "a state ran away"}

_D = ctypes.POINTER(ctypes.c_double)
_I = ctypes.POINTER(ctypes.c_int)


@dataclass
class Stepper:
    """A loaded compiled stepper for one mode.

    Attributes
    ----------
    n : int
        Number of (scaled) states.
    ng : int
        Number of guards.
    """

    lib: ctypes.CDLL
    n: int
    ng: int
    ny: int

    def outputs(self, P, T, X) -> np.ndarray:
        """Output signals at samples T (k,) with scaled states X (n x k); returns (ny x k)."""
        T = np.ascontiguousarray(T, dtype=float)
        Xr = np.ascontiguousarray(np.asarray(X, dtype=float).T)
        P = np.ascontiguousarray(P, dtype=float)
        Y = np.empty((len(T), self.ny))
        st = self.lib.kiln_outputs(self.n, self.ny, P.ctypes.data_as(_D), len(T), T.ctypes.data_as(_D),
                                   Xr.ctypes.data_as(_D), Y.ctypes.data_as(_D))
        if st != 0:
            raise RuntimeError(f"compiled output evaluation failed ({STATUS.get(st, st)})")
        return Y.T

    def guard(self, P, x, t):
        """Guards, selectors and their time derivatives at (x, t): three arrays of length ng."""
        P, x = np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(x, dtype=float)
        m = max(self.ng, 1)
        g, sel, gd = np.empty(m), np.empty(m), np.empty(m)
        if self.lib.kiln_guard(P.ctypes.data_as(_D), x.ctypes.data_as(_D), ctypes.c_double(t), g.ctypes.data_as(_D),
                               sel.ctypes.data_as(_D), gd.ctypes.data_as(_D)):
            raise RuntimeError("compiled guard evaluation failed")
        return g[: self.ng], sel[: self.ng], gd[: self.ng]

    def project(self, P, x):
        """Scaled state with node speeds projected onto the mode's rigid links."""
        P, x = np.ascontiguousarray(P, dtype=float), np.ascontiguousarray(x, dtype=float)
        out = np.empty(self.n)
        if self.lib.kiln_project(P.ctypes.data_as(_D), x.ctypes.data_as(_D), out.ctypes.data_as(_D)):
            raise RuntimeError("compiled projection failed")
        return out

    def run(self, P, t0, t_end, x0, dt_out, rtol, atol, hmax, h0, event_tol, max_out=4096, max_steps=500000,
            runaway=1e6):
        """Integrate from (t0, x0) to t_end or the first guard crossing.

        Returns
        -------
        dict
            ``status`` (see :data:`STATUS`), ``t`` and ``x`` (samples on the grid
            t0 + k*dt_out), ``t_ev``, ``x_ev`` (end or event point), ``j_ev``
            (guard index), ``n_steps``, ``h`` (last step size).
        """
        out_t = np.empty(max_out)
        out_x = np.empty((max_out, self.n))
        x0 = np.ascontiguousarray(x0, dtype=float)
        P = np.ascontiguousarray(P, dtype=float)
        x_ev = np.empty(self.n)
        t_ev = np.zeros(1)
        n_out = ctypes.c_int(0)
        j_ev = ctypes.c_int(-1)
        n_steps = ctypes.c_int(0)
        h_last = ctypes.c_double(0.0)
        st = self.lib.kiln_run(
            self.n, self.ng, P.ctypes.data_as(_D), ctypes.c_double(t0), ctypes.c_double(t_end),
            x0.ctypes.data_as(_D), ctypes.c_double(dt_out), ctypes.c_double(rtol), ctypes.c_double(atol),
            ctypes.c_double(hmax), ctypes.c_double(h0), ctypes.c_double(event_tol), max_out,
            out_t.ctypes.data_as(_D), out_x.ctypes.data_as(_D), ctypes.byref(n_out), t_ev.ctypes.data_as(_D),
            x_ev.ctypes.data_as(_D), ctypes.byref(j_ev), max_steps, ctypes.byref(n_steps), ctypes.byref(h_last),
            ctypes.c_double(runaway))
        k = n_out.value
        # copies of the used rows, so the full buffers are freed now
        return {"status": st, "t": out_t[:k].copy(), "x": out_x[:k].T.copy(), "t_ev": float(t_ev[0]), "x_ev": x_ev,
                "j_ev": j_ev.value, "n_steps": n_steps.value, "h": h_last.value}


def build_stepper(f, xs, t, P, g, y, sel, gdot, proj) -> Stepper | None:
    """Generate, compile (cached) and load the stepper of one mode.

    Parameters
    ----------
    f : casadi.SX
        Right-hand side in scaled states.
    xs, t, P : casadi.SX
        State, time and parameter symbols.
    g : casadi.SX
        Guards (may be empty).
    y : casadi.SX
        Output signals.
    sel, gdot : casadi.SX
        Guard selectors and time derivatives of the guards.
    proj : casadi.SX
        Scaled state with speeds projected onto the rigid links (a function of xs and P).

    Returns
    -------
    Stepper or None
        None when no C compiler is available or compiling fails.
    """
    n, ng = xs.numel(), g.numel()
    if n > 64 or ng > 64:
        return None
    gg = g if ng else ca.SX.ones(1)
    funcs = [ca.Function("kf", [xs, t, P], [f]),
             ca.Function("kj", [xs, t, P], [ca.densify(ca.jacobian(f, xs))]),
             ca.Function("kt", [xs, t, P], [ca.densify(ca.jacobian(f, t))]),
             ca.Function("kg", [xs, t, P], [ca.densify(gg)]),
             ca.Function("ko", [xs, t, P], [ca.densify(y)]),
             ca.Function("kd", [xs, t, P], [ca.densify(gg), ca.densify(sel if ng else ca.SX.ones(1)),
                                            ca.densify(gdot if ng else ca.SX.zeros(1))]),
             ca.Function("kp", [xs, P], [ca.densify(proj)])]
    driver = resources.files("kilnctl.model").joinpath("rosenbrock.c").read_bytes()
    lib_path = compile_sources("mode", {"gen.c": generate_c(funcs, "gen"), "rosenbrock.c": driver})
    if lib_path is None:
        return None
    lib = ctypes.CDLL(str(lib_path))
    lib.kiln_run.restype = ctypes.c_int
    lib.kiln_check.restype = ctypes.c_int
    if lib.kiln_check() != 0:
        return None
    lib.kiln_outputs.restype = ctypes.c_int
    lib.kiln_guard.restype = ctypes.c_int
    lib.kiln_project.restype = ctypes.c_int
    return Stepper(lib, n, ng, y.numel())
