"""Outputs of the smooth model and their exact gradients from one CVODES run.

CasADi can differentiate through CVODES itself, but its forward-sensitivity
integrator costs about 15 times the simulation on this stiff model (measured:
0.9 s against 0.06 s for a 25 s start-up).  Here the sensitivity equations
are written out instead, dS/dt = (df/dx) S with S = dx/dtheta (the profile
numbers theta enter only through the initial state, as constant states), and
integrated together with the states as one ordinary CVODES problem, with
error control on both: 0.2 s for the same run and gradient.  The objective's
integral smooth maximum (:func:`kilnctl.optimize.transcription.objective_quadrature`)
and its gradient are quadratures of the same run.

:class:`SensitivityRun` returns numbers; :class:`CaseCallback` wraps the
values and Jacobian of all cases as a CasADi function for IPOPT.
"""

from __future__ import annotations

import time

import casadi as ca
import numpy as np

from .model import OUTPUTS, SmoothStartup, integrate_retrying

__all__ = ["SensitivityRun", "CaseCallback", "smooth_max_np"]


def smooth_max_np(v: np.ndarray, dv: np.ndarray, beta: float) -> tuple[float, np.ndarray]:
    """Log-sum-exp smooth maximum of samples and its gradient.

    Parameters
    ----------
    v : ndarray, shape (n,)
        Samples (dimensionless).
    dv : ndarray, shape (n, m)
        Their derivatives with respect to m parameters.
    beta : float
        Sharpness (1/unit of v).

    Returns
    -------
    value : float
        max(v) <= value <= max(v) + log(n)/beta.
    grad : ndarray, shape (m,)
        Softmax-weighted derivative.
    """
    mx = float(np.max(v))
    w = np.exp(beta * (v - mx))
    sw = float(np.sum(w))
    return mx + np.log(sw) / beta, (w / sw) @ dv


class SensitivityRun:
    """One smooth-model run with forward sensitivities to the profile numbers.

    Parameters
    ----------
    model : SmoothStartup
        The smooth model.
    grid : ndarray
        Output times [s].
    quad : tuple (casadi.SX q, casadi.SX pq)
        Objective integrand and its extra parameters (see
        :func:`~kilnctl.optimize.transcription.objective_quadrature`).
    rtol, atol : float
        CVODES tolerances on states and sensitivities (scaled).
    """

    def __init__(self, model: SmoothStartup, grid, quad, rtol: float = 1e-7, atol: float = 1e-8):
        self.model = model
        self.grid = np.asarray(grid, dtype=float)
        nx = model.xs.shape[0]
        nth = len(model.theta_index)
        self.nx, self.nth = nx, nth
        q, pq = quad
        S = ca.SX.sym("S", nx, nth)
        fx = ca.jacobian(model.f_expr, model.xs)
        qx = ca.jacobian(q, model.xs)
        aug = ca.vertcat(model.f_expr, ca.vec(ca.mtimes(fx, S)))
        X = ca.vertcat(model.xs, ca.vec(S))
        self.nq = q.shape[0]
        dae = {"x": X, "t": model.t, "p": ca.vertcat(model.P, pq), "ode": aug,
               "quad": ca.vertcat(q, ca.vec(ca.mtimes(qx, S).T))}
        self._dae, self._tol = dae, (rtol, atol)
        self._F = {}
        y = model.y_expr
        dy = ca.mtimes(ca.jacobian(y, model.xs), S)
        self.Y = ca.Function("ydy", [X, model.t, model.P], [y, ca.vec(dy)]).map(len(self.grid))
        self.S0 = np.zeros((nx, nth))
        for k, i in enumerate(model.theta_index):
            self.S0[i, k] = 1.0 / model.plant.scales[i]

    def integrator(self, tighten: float = 1.0) -> ca.Function:
        """The augmented CVODES integrator (cached).

        Parameters
        ----------
        tighten : float, default 1.0
            Factor on the tolerances.

        Returns
        -------
        casadi.Function
        """
        F = self._F.get(tighten)
        if F is None:
            rtol, atol = self._tol
            # Warnings off: CVODES meets a NaN in the sensitivity equations at some trial steps (pwl:4: 4
            # messages in one solve, pwl:8: 48) and recovers by shortening the step, while CasADi printed
            # "sens:daeF failed: NaN detected" and SUNDIALS "repeated recoverable right-hand side function
            # errors" each time. A run that does not recover still fails, is retried at tighter tolerances,
            # then raises OptimizationError.
            opts = {"abstol": atol * tighten, "reltol": rtol * tighten, "max_num_steps": 1000000,
                    "quad_err_con": True, "show_eval_warnings": False, "disable_internal_warnings": True}
            F = self._F[tighten] = ca.integrator("sens", "cvodes", self._dae, 0.0, list(self.grid), opts)
        return F

    def __call__(self, params, theta, widths: dict, pq) -> dict:
        """Run and return outputs, objective integral and their derivatives with respect to theta.

        Parameters
        ----------
        params : Parameters
            Gains resolved.
        theta : ndarray
            Profile numbers [profile units].
        widths : dict
            Smoothing widths.
        pq : sequence of float
            Objective integrand parameters [beta, c, 1/scale].

        Returns
        -------
        dict
            ``Y`` (n_out x n_grid), ``dY`` (n_out x n_grid x n_theta),
            ``Q`` (n_q,: the objective integrals over the horizon [s]) and
            ``dQ`` (n_q x n_theta).

        Raises
        ------
        OptimizationError
            CVODES failed, also at ten times tighter tolerances (the message
            names the profile numbers).
        """
        P = self.model.param_vector(params)
        x0 = np.asarray(self.model.x0(params, np.asarray(theta, float), widths), dtype=float).ravel()
        X0 = np.concatenate([x0, self.S0.ravel(order="F")])
        r = integrate_retrying(self.integrator, theta, x0=X0, p=np.concatenate([P, np.asarray(pq, float)]))
        Xa = np.asarray(r["xf"])
        qf = np.asarray(r["qf"])
        y, dy = self.Y(Xa, self.grid, P)
        n = len(self.grid)
        Y = np.asarray(y)
        dY = np.asarray(dy).reshape(Y.shape[0], self.nth, n, order="F").transpose(0, 2, 1)
        nq = self.nq
        return {"Y": Y, "dY": dY, "Q": qf[:nq, -1].copy(), "dQ": qf[nq:, -1].reshape(nq, self.nth)}


#: seconds between progress lines during a solve
PROGRESS_EVERY = 10.0


class CaseCallback(ca.Callback):
    """Values and Jacobian of every case's objective and constraints, for IPOPT.

    Output per case (:attr:`ROWS` = 5 rows): the integral smooth maxima J_s
    of |sigma| and J_d of |sigma_dyn|, the motor speed at t_max over
    omega_ref, and the smooth maxima of |i_a|/I_max and |e_a|/V_max over the
    grid.  Input: the scaled profile
    numbers z (theta = z * theta_scale).  One sensitivity run per case serves
    value and Jacobian (cached on z).

    Parameters
    ----------
    run : SensitivityRun
    cases : list of (str, Parameters)
    theta_scale : ndarray
    k_tmax : int
        Grid index of t_max.
    constraint_beta : float
        Sharpness of the current and voltage smooth maxima.
    tau : float
        Time normalisation of the integral smooth maximum [s].
    """

    ROWS = 5

    def __init__(self, run: SensitivityRun, cases, theta_scale, k_tmax: int, constraint_beta: float, tau: float):
        ca.Callback.__init__(self)
        self.run, self.cases = run, list(cases)
        self.theta_scale = np.asarray(theta_scale, float)
        self.k_tmax, self.cbeta, self.tau = int(k_tmax), float(constraint_beta), float(tau)
        self.n_out = self.ROWS * len(self.cases)
        self.stage = None
        self._key = None
        self._val = self._jac = None
        self.n_runs = 0
        self._jac_cb = None
        #: callable(str) or None: a line every PROGRESS_EVERY seconds while IPOPT evaluates
        self.progress = None
        self._last_report = time.perf_counter()
        #: set when Ctrl-C arrived inside an evaluation: CasADi turns the KeyboardInterrupt raised there into
        #: a failed evaluation, so the solver's caller checks this flag and raises it again
        self.interrupted = False
        self.construct("cases", {"enable_fd": False})

    def set_stage(self, beta: float, c_s: float, c_d: float, widths: dict, inv_scale: float) -> None:
        """Set the smoothing of the current continuation stage (clears the cache).

        Parameters
        ----------
        beta : float
            Smooth-maximum sharpness [1/stress scale].
        c_s, c_d : float
            Shifts of the peak and dynamic stress integrands [stress scales].
        widths : dict
            Smoothing widths.
        inv_scale : float
            1/stress scale [1/Pa].
        """
        self.stage = (float(beta), float(c_s), float(c_d), dict(widths), float(inv_scale))
        self._key = None

    def get_n_in(self):
        return 1

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        return ca.Sparsity.dense(len(self.theta_scale), 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(self.n_out, 1)

    def evaluate(self, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Values and Jacobian at scaled profile numbers (one sensitivity run per case, cached).

        Parameters
        ----------
        z : ndarray
            Scaled profile numbers.

        Returns
        -------
        values : ndarray, shape (n_out,)
        jacobian : ndarray, shape (n_out, n_z)
        """
        if self.interrupted:  # stop the solver quickly: every evaluation fails from now on
            raise KeyboardInterrupt
        try:
            return self._evaluate(z)
        except KeyboardInterrupt:
            self.interrupted = True
            raise

    def _evaluate(self, z):
        z = np.asarray(z, float).ravel()
        key = z.tobytes()
        if key == self._key:
            return self._val, self._jac
        beta, c_s, c_d, widths, inv = self.stage
        theta = z * self.theta_scale
        iw, ii, ie = OUTPUTS.index("speed_rpm"), OUTPUTS.index("i_a"), OUTPUTS.index("e_a")
        val, jac = [], []
        for _, cp in self.cases:
            r = self.run(cp, theta, widths, [beta, c_s, c_d, inv])
            self.n_runs += 1
            for k, c in enumerate((c_s, c_d)):
                Q = max(r["Q"][k], 1e-300)
                val.append(c + np.log(Q / self.tau) / beta)
                jac.append(r["dQ"][k] / (beta * Q))
            val.append(r["Y"][iw, self.k_tmax] / cp.omega_ref)
            jac.append(r["dY"][iw, self.k_tmax] / cp.omega_ref)
            for row, lim in ((ii, cp.I_max), (ie, cp.V_max)):
                v = r["Y"][row] / lim
                dv = r["dY"][row] / lim
                ks, dks = smooth_max_np(np.concatenate([v, -v]), np.concatenate([dv, -dv]), self.cbeta)
                val.append(ks)
                jac.append(dks)
        J = np.array(jac) * self.theta_scale[None, :]
        self._key, self._val, self._jac = key, np.array(val), J
        now = time.perf_counter()
        if self.progress is not None and now - self._last_report >= PROGRESS_EVERY:
            self._last_report = now
            self.progress(f"    {self.n_runs} sensitivity runs so far; peak-stress objective {val[0]:.4g} "
                          f"(stress scales), speed at t_max {val[2]:.3f} of omega_ref")
        return self._val, self._jac

    def eval(self, arg):
        return [self.evaluate(np.asarray(arg[0]))[0]]

    def has_jacobian(self):
        return True

    def get_jacobian(self, name, inames, onames, opts):
        self._jac_cb = _JacobianCallback(name, self, opts)
        return self._jac_cb


class _JacobianCallback(ca.Callback):
    """Jacobian of :class:`CaseCallback` (inputs: z and the nominal output)."""

    def __init__(self, name, parent: CaseCallback, opts):
        ca.Callback.__init__(self)
        self.parent = parent
        self.construct(name, {"enable_fd": False})

    def get_n_in(self):
        return 2

    def get_n_out(self):
        return 1

    def get_sparsity_in(self, i):
        if i == 0:
            return ca.Sparsity.dense(len(self.parent.theta_scale), 1)
        return ca.Sparsity.dense(self.parent.n_out, 1)

    def get_sparsity_out(self, i):
        return ca.Sparsity.dense(self.parent.n_out, len(self.parent.theta_scale))

    def eval(self, arg):
        return [self.parent.evaluate(np.asarray(arg[0]))[1]]
