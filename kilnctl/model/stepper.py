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
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from ..errors import SimulationError
from .compiled import compile_sources, generate_c

__all__ = ["Stepper", "build_stepper", "STATUS", "GUARD_EPS", "FIRST_STEP", "RUNAWAY", "NMAX"]

#: meaning of kiln_run's return codes
STATUS = {0: "reached t_end", 1: "event", 2: "output buffer full", -1: "singular iteration matrix",
          -2: "model function error or non-finite state", -3: "step size underflow", -4: "too many steps",
          -5: "too many states or guards for the compiled stepper", -6: "a state ran away",
          -7: "bad arguments to the compiled stepper", -8: "out of memory in the compiled stepper"}

#: a guard has crossed when it is below -GUARD_EPS (guards are scaled to order one), so a guard that
#: starts on its boundary does not fire on round-off or on integration error below the default
#: absolute tolerance; the one definition, used by both engines and passed to the C stepper
GUARD_EPS = 1e-7
#: first step [s] of the compiled stepper at a start and after every mode switch (then capped at the
#: largest step); the one definition, passed to the C stepper like GUARD_EPS
FIRST_STEP = 1e-4
#: a scaled state beyond this is a runaway (the loop is unstable), reported as an error; passed to the C stepper
RUNAWAY = 1e6
#: interface version of rosenbrock.c's entry points (KILN_ABI there); a library that reports another is not used
ABI = 4
#: most states and most guards the C stepper handles (its fixed arrays, ``NMAX``/``GMAX`` in rosenbrock.c)
NMAX = 64

# double arrays are passed as addresses (``ndarray.ctypes.data``, the caller holding the array): about 3 us less
# per array than ``data_as(POINTER(c_double))``, which adds up over the ~10^5 calls of a diagnosis
_D = ctypes.c_void_p
_I = ctypes.POINTER(ctypes.c_int)
_d, _i = ctypes.c_double, ctypes.c_int
_SIGNATURES = {
    "kiln_run": [_i, _i, _D, _d, _d, _D, _d, _d, _d, _d, _d, _d, _i, _D, _D, _I, _D, _D, _I, _i, _I, _D, _d, _d],
    "kiln_check": [],
    "kiln_abi": [],
    "kiln_outputs": [_i, _i, _D, _i, _D, _D, _D],
    "kiln_guard": [_D, _D, _d, _D, _D, _D],
    "kiln_project": [_D, _D, _d, _D],
}


def _vector(name, v, n):
    """A contiguous float64 copy of v, checked to have n finite-or-not entries (length is what C trusts)."""
    a = np.ascontiguousarray(v, dtype=float).ravel()
    if a.size != n:
        raise SimulationError(f"compiled stepper: {name} has {a.size} entries, the compiled mode expects {n}")
    return a


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
    n_p: int = -1
    #: (P, its address) of the last parameter vector that was checked as it is: a run passes the same vector at
    #: every call (one tuple, read and replaced whole, so threads sharing the stepper never mix two entries)
    _last_p: tuple = field(default=(None, 0), repr=False, compare=False)

    def _params(self, P):
        return _vector("P", P, self.n_p) if self.n_p >= 0 else np.ascontiguousarray(P, dtype=float).ravel()

    def _p_address(self, P):
        """(array to hold during the call, its address) for parameter vector P, checked once per vector."""
        last = self._last_p
        if last[0] is P:  # held in _last_p, so its id cannot have been reused by another object
            return P, last[1]
        if (type(P) is np.ndarray and P.dtype == np.float64 and P.ndim == 1 and P.flags.c_contiguous
                and (self.n_p < 0 or P.size == self.n_p)):
            address = P.ctypes.data
            self._last_p = (P, address)
            return P, address
        a = self._params(P)  # converted (or refused): a new array each call
        return a, a.ctypes.data

    def outputs(self, P, T, X) -> np.ndarray:
        """Output signals at samples T (k,) with scaled states X (n x k); returns (ny x k)."""
        T = np.ascontiguousarray(T, dtype=float).ravel()
        X = np.asarray(X, dtype=float)
        if X.ndim != 2 or X.shape != (self.n, len(T)):
            raise SimulationError(f"compiled stepper: states of shape {X.shape}, expected ({self.n}, {len(T)})")
        return self.outputs_rows(P, T, X.T).T

    def outputs_rows(self, P, T, X, out=None) -> np.ndarray:
        """Output signals at samples T (k,) with scaled states X given as rows (k x n); returns (k x ny).

        The layout the C code reads and writes: a C-contiguous X is not copied.  ``out``, a C-contiguous
        (k x ny) float array, receives the outputs (and is returned) instead of a new array.
        """
        T = np.ascontiguousarray(T, dtype=float).ravel()
        X = np.ascontiguousarray(X, dtype=float)
        if X.ndim != 2 or X.shape != (len(T), self.n):
            raise SimulationError(f"compiled stepper: state rows of shape {X.shape}, expected ({len(T)}, {self.n})")
        P, p_address = self._p_address(P)
        if out is None:
            Y = np.empty((len(T), self.ny))
        elif (isinstance(out, np.ndarray) and out.dtype == np.float64 and out.shape == (len(T), self.ny)
              and out.flags.c_contiguous and out.flags.writeable):
            Y = out
        else:
            raise SimulationError(f"compiled stepper: out must be a writeable C-contiguous float array of shape "
                                  f"({len(T)}, {self.ny})")
        st = self.lib.kiln_outputs(self.n, self.ny, p_address, len(T), T.ctypes.data, X.ctypes.data,
                                   Y.ctypes.data)
        if st != 0:
            raise SimulationError(f"compiled output evaluation failed ({STATUS.get(st, st)})")
        return Y

    def guard(self, P, x, t):
        """Guards, selectors and their time derivatives at (x, t): three arrays of length ng."""
        P, p_address = self._p_address(P)
        x = _vector("x", x, self.n)
        m = max(self.ng, 1)
        buf = np.empty((3, m))  # g, sel, gdot: one allocation, rows of m doubles
        b = buf.ctypes.data
        if self.lib.kiln_guard(p_address, x.ctypes.data, float(t), b, b + 8 * m, b + 16 * m):
            raise SimulationError("compiled guard evaluation failed")
        return buf[0, : self.ng], buf[1, : self.ng], buf[2, : self.ng]

    def project(self, P, x, t):
        """Scaled state at time t projected onto the mode's constraints (rigid links, held current)."""
        P, p_address = self._p_address(P)
        x = _vector("x", x, self.n)
        out = np.empty(self.n)
        if self.lib.kiln_project(p_address, x.ctypes.data, float(t), out.ctypes.data):
            raise SimulationError("compiled projection failed")
        return out

    def run(self, P, t0, t_end, x0, dt_out, rtol, atol, hmax, h0, event_tol, max_out=4096, max_steps=500000,
            runaway=RUNAWAY, guard_eps=GUARD_EPS, out_t=None, out_x=None):
        """Integrate from (t0, x0) to t_end or the first guard crossing.

        Parameters
        ----------
        P : array_like
            Parameter vector of the plant.
        t0, t_end : float
            Start and end time [s].
        x0 : array_like
            Scaled state at t0 (length n).
        dt_out : float
            Output and guard-check grid [s] (samples at k*dt_out).
        rtol, atol : float
            Integration tolerances (atol on scaled states).
        hmax, h0 : float
            Largest step and first step [s], both > 0 (:data:`FIRST_STEP` at a
            start or after a switch; the stepper caps it at ``hmax``).
        event_tol : float
            Width [s] to which a guard crossing is located.
        max_out : int
            Output buffer length; when it is full, the run stops at the last
            accepted integrator point (status 2) and the caller continues from
            there, so results do not depend on max_out.
        max_steps : int
            Steps allowed in this call.
        runaway : float
            Largest magnitude of a scaled state.
        guard_eps : float
            A guard has crossed when below -guard_eps.
        out_t, out_x : ndarray, optional
            Where to write the samples: C-contiguous float arrays of shape
            (max_out,) and (max_out, n), e.g. row slices of a caller's buffer
            for the whole run.  Default: new arrays, of which the used rows are
            returned as copies.

        Returns
        -------
        dict
            ``status`` (see :data:`STATUS`), ``t`` and ``x`` (samples on the grid
            t0 + k*dt_out; ``x`` is n x k, a view of ``x_rows``, the same samples
            as k x n rows; with ``out_t``/``out_x``, views of those),
            ``t_ev``, ``x_ev`` (end, event or restart point), ``j_ev`` (guard
            index), ``n_steps``, ``h`` (next step size).
        """
        max_out = int(max_out)
        given = out_t is not None or out_x is not None
        if given:
            for name, a, shape in (("out_t", out_t, (max_out,)), ("out_x", out_x, (max_out, self.n))):
                if (not isinstance(a, np.ndarray) or a.dtype != np.float64 or a.shape != shape
                        or not a.flags.c_contiguous or not a.flags.writeable):
                    raise SimulationError(f"compiled stepper: {name} must be a writeable C-contiguous float array of "
                                          f"shape {shape}")
        else:
            out_t = np.empty(max_out)
            out_x = np.empty((max_out, self.n))
        x0 = _vector("x0", x0, self.n)
        P, p_address = self._p_address(P)
        x_ev = np.empty(self.n)
        t_ev = np.zeros(1)
        n_out = ctypes.c_int(0)
        j_ev = ctypes.c_int(-1)
        n_steps = ctypes.c_int(0)
        h_last = ctypes.c_double(0.0)
        st = self.lib.kiln_run(
            self.n, self.ng, p_address, ctypes.c_double(t0), ctypes.c_double(t_end),
            x0.ctypes.data, ctypes.c_double(dt_out), ctypes.c_double(rtol), ctypes.c_double(atol),
            ctypes.c_double(hmax), ctypes.c_double(h0), ctypes.c_double(event_tol), max_out,
            out_t.ctypes.data, out_x.ctypes.data, ctypes.byref(n_out), t_ev.ctypes.data,
            x_ev.ctypes.data, ctypes.byref(j_ev), int(max_steps), ctypes.byref(n_steps), ctypes.byref(h_last),
            ctypes.c_double(runaway), ctypes.c_double(guard_eps))
        k = n_out.value
        if given:
            t_out, x_rows = out_t[:k], out_x[:k]
        else:  # copies of the used rows, so the full buffers are freed now
            t_out, x_rows = out_t[:k].copy(), out_x[:k].copy()
        return {"status": st, "t": t_out, "x": x_rows.T, "x_rows": x_rows, "t_ev": float(t_ev[0]),
                "x_ev": x_ev, "j_ev": j_ev.value, "n_steps": n_steps.value, "h": h_last.value}


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
        Scaled state projected onto the mode's constraints (a function of xs, t and P).

    Returns
    -------
    Stepper or None
        None when no C compiler is available, compiling fails, the library
        does not load, or the mode is beyond the stepper's fixed sizes (each
        but the first with a warning: the caller falls back to CVODES).
    """
    n, ng = xs.numel(), g.numel()
    if n > NMAX or ng > NMAX:
        warnings.warn(f"kilnctl: a mode with {n} states and {ng} guards is beyond the compiled stepper's limit of "
                      f"{NMAX}; falling back to CVODES (guards checked every dt only, slower)", RuntimeWarning,
                      stacklevel=3)
        return None
    gg = g if ng else ca.SX.ones(1)
    funcs = [ca.Function("kf", [xs, t, P], [f]),
             ca.Function("kj", [xs, t, P], [ca.densify(ca.jacobian(f, xs))]),
             ca.Function("kt", [xs, t, P], [ca.densify(ca.jacobian(f, t))]),
             ca.Function("kg", [xs, t, P], [ca.densify(gg)]),
             ca.Function("ko", [xs, t, P], [ca.densify(y)]),
             ca.Function("kd", [xs, t, P], [ca.densify(gg), ca.densify(sel if ng else ca.SX.ones(1)),
                                            ca.densify(gdot if ng else ca.SX.zeros(1))]),
             ca.Function("kp", [xs, t, P], [ca.densify(proj)])]
    # the driver next to this file, so the Python side and the C side always come from one tree
    driver = Path(__file__).with_name("rosenbrock.c").read_bytes()
    lib_path = compile_sources("mode", {"gen.c": generate_c(funcs, "gen"), "rosenbrock.c": driver})
    if lib_path is None:
        return None
    try:
        lib = ctypes.CDLL(str(lib_path))
        for name, args in _SIGNATURES.items():
            fn = getattr(lib, name)
            fn.argtypes = args
            fn.restype = ctypes.c_int
    except (OSError, AttributeError) as exc:
        warnings.warn(f"kilnctl: the cached stepper library {lib_path} does not load ({exc}); falling back to "
                      "CVODES. Delete that file (or set KILNCTL_CACHE to a fresh folder) to rebuild it.",
                      RuntimeWarning, stacklevel=3)
        return None
    if lib.kiln_abi() != ABI:
        warnings.warn(f"kilnctl: the stepper library {lib_path} has interface version {lib.kiln_abi()}, this kilnctl "
                      f"needs {ABI}; falling back to CVODES. Delete that file to rebuild it.", RuntimeWarning,
                      stacklevel=3)
        return None
    if lib.kiln_check() != 0:
        warnings.warn("kilnctl: this mode's generated code needs more work memory than the compiled stepper has; "
                      "falling back to CVODES", RuntimeWarning, stacklevel=3)
        return None
    return Stepper(lib, n, ng, y.numel(), P.numel())
