"""Transcriptions of a :class:`~kilnctl.optimize.problem.RampProblem` into an NLP for IPOPT.

The problem is declared once; this module turns it into a nonlinear program
in one of two ways (``transcription=``):

``'single_shooting'``
    The decision variables are the (scaled) profile numbers only; one CVODES
    run per scenario over the whole horizon gives the outputs on a fine time
    grid, and CVODES forward sensitivities give their gradients.
``'multiple_shooting'``
    The horizon is cut into ``n_shooting`` intervals; the scaled states at
    the interval starts are extra variables tied together by continuity
    constraints.  The same optimum, a better-conditioned problem when the
    single-shooting map is very nonlinear, at more cost per iteration.

Direct collocation is not offered: the backlash impact excites the 290 Hz
mesh mode, which needs steps near 0.1 ms, and a uniform collocation grid over
a 25 s start-up would have about 2.5e5 intervals (CVODES adapts its step
instead; see docs/optimization.md).

Peak values enter through the smooth maximum
``smooth_max(v, beta) = m + log(sum(exp(beta*(v - m))))/beta`` (m = max v,
which cancels from the value and the gradient), taken over the outputs on the
grid: it lies between max(v) and max(v) + log(len(v))/beta.  The objective
uses it on |sigma|/sigma_scale; the current and voltage constraints use it on
|i_a|/I_max and |e_a|/V_max, so that they are conservative (never below the
sampled maximum).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from ..errors import ParameterError
from .model import OUTPUTS, SmoothStartup
from .sensitivity import CaseCallback, SensitivityRun

__all__ = ["smooth_max", "TimeGrid", "NLP", "build_nlp", "TRANSCRIPTIONS", "CONSTRAINT_BETA"]

TRANSCRIPTIONS = ("single_shooting", "multiple_shooting")
#: sharpness of the smooth maximum in the current and voltage constraints [1/limit]:
#: conservative by at most log(n_samples)/CONSTRAINT_BETA of the limit (0.5 % for 5e4 samples)
CONSTRAINT_BETA = 2000.0
#: weight of the dynamic stress in the 'peak' objective [-]: it decides between ramps of equal peak
#: stress (a flat objective where the burden's running load sets the peak) and is otherwise negligible
TIE_BREAK = 0.01


def smooth_max(v, beta):
    """Log-sum-exp smooth maximum of the entries of a column vector.

    Parameters
    ----------
    v : casadi.MX
        Column vector (dimensionless).
    beta : casadi.MX or float
        Sharpness, > 0 (1/unit of v).

    Returns
    -------
    casadi.MX
        Between max(v) and max(v) + log(len(v))/beta.
    """
    m = ca.mmax(v)
    return m + ca.log(ca.sum1(ca.exp(beta * (v - m)))) / beta


@dataclass(frozen=True)
class TimeGrid:
    """Uniform output grid of the start-up, with t_max on a grid point.

    Attributes
    ----------
    dt : float
        Step [s].
    n : int
        Number of points (t = dt, 2*dt, ..., n*dt).
    k_tmax : int
        Index of t_max.
    """

    dt: float
    n: int
    k_tmax: int

    @classmethod
    def make(cls, t_max: float, horizon: float, dt: float) -> "TimeGrid":
        """Grid of step about ``dt`` [s] that hits t_max and covers the horizon [s]."""
        k = max(1, int(round(t_max / dt)))
        step = t_max / k
        n = int(np.ceil(horizon / step - 1e-9))
        return cls(step, n, k - 1)

    @property
    def t(self) -> np.ndarray:
        """Output times [s]."""
        return self.dt * np.arange(1, self.n + 1)


@dataclass
class NLP:
    """An NLP ready for IPOPT, with what is needed to read its solution.

    Attributes
    ----------
    solver : casadi.Function
        ``nlpsol`` instance; parameters p = [beta, c_s, c_d, smoothing widths].
    w0 : ndarray
        Initial guess of all variables.
    lbw, ubw, lbg, ubg : ndarray
        Bounds.
    n_theta : int
        The first ``n_theta`` variables are the scaled profile numbers.
    theta_scale : ndarray
        theta = w[:n_theta] * theta_scale.
    g_names : list of str
        Name of each constraint row (``'<case>: speed at t_max'`` ...).
    width_names : tuple of str
        Order of the smoothing widths in p after beta.
    transcription : str
    """

    solver: ca.Function
    w0: np.ndarray
    lbw: np.ndarray
    ubw: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    n_theta: int
    theta_scale: np.ndarray
    g_names: list
    width_names: tuple
    transcription: str
    g_function: ca.Function = field(repr=False, default=None)
    callback: object = field(repr=False, default=None)
    inv_scale: float = 1.0

    def parameters(self, beta: float, c_s: float, c_d: float, widths: dict) -> np.ndarray:
        """Set a continuation stage and return the NLP parameter vector.

        Parameters
        ----------
        beta : float
            Smooth-maximum sharpness [1/stress scale].
        c_s, c_d : float
            Shifts of the peak and dynamic stress integrands [stress scales].
        widths : dict
            Smoothing widths by state name.

        Returns
        -------
        ndarray
            [beta, c_s, c_d, widths...].
        """
        if self.callback is not None:
            self.callback.set_stage(beta, c_s, c_d, widths, self.inv_scale)
        return np.array([beta, c_s, c_d] + [widths[n] for n in self.width_names], dtype=float)


#: time normalisation of the integral smooth maximum [s]: a peak of this width counts at its full height
TAU = 1e-3


#: exponent above which the smooth maximum's exponential continues as its tangent line: exp(beta*x)
#: overflowed (inf, then NaN gradients: CasADi's "NaN detected") when a trial ramp's stress exceeded the
#: stage's shift c by more than 709/beta; with the tangent the integrand stays finite and keeps growing
EXP_CAP = 200.0


def exp_capped(x):
    """exp(x) up to :data:`EXP_CAP`, then its tangent line there (continuous with its slope, finite).

    Parameters
    ----------
    x : casadi.SX or casadi.MX
        Exponent (dimensionless).

    Returns
    -------
    casadi.SX or casadi.MX
        ``exp(x)`` for x <= EXP_CAP, ``exp(EXP_CAP) (1 + x - EXP_CAP)`` above.
    """
    # fmin keeps the unused branch finite (if_else evaluates both; inf * 0 would give NaN)
    return ca.if_else(x <= EXP_CAP, ca.exp(ca.fmin(x, EXP_CAP + 1)), np.exp(EXP_CAP) * (1 + x - EXP_CAP))


def objective_quadrature(model: SmoothStartup):
    """Integrands of the time-continuous smooth maxima of |sigma(t)| and |sigma_dyn(t)|.

    Parameters
    ----------
    model : SmoothStartup

    Returns
    -------
    q : casadi.SX, shape (2, 1)
        exp(beta*(s/scale - c_s)) + exp(beta*(-s/scale - c_s)) for s = sigma,
        then the same for sigma_dyn with shift c_d.
    pq : casadi.SX
        Their parameters [beta, c_s, c_d, 1/scale].
    """
    pq = ca.SX.sym("pq", 4)
    q = []
    for k, key in enumerate(("sigma", "sigma_dyn")):
        s_ = model.y_expr[OUTPUTS.index(key)] * pq[3]
        q.append(exp_capped(pq[0] * (s_ - pq[1 + k])) + exp_capped(pq[0] * (-s_ - pq[1 + k])))
    return ca.vertcat(*q), pq


def integral_smooth_max(Q, beta, c):
    """c + log(Q/TAU)/beta: the smooth maximum from the integral Q of the objective quadrature.

    Parameters
    ----------
    Q : casadi.MX
        Integral over the horizon of :func:`objective_quadrature` [s].
    beta, c : casadi.MX
        Sharpness and shift (scaled units).

    Returns
    -------
    casadi.MX
        About max |s|/scale + log(w/TAU)/beta for a single peak of effective
        width w; equal to the discrete smooth maximum on a TAU grid.
    """
    return c + ca.log(Q / TAU) / beta


def build_nlp(problem, model: SmoothStartup, cases, grid: TimeGrid, sigma_scale: float,
              theta_scale: np.ndarray, theta0: np.ndarray, transcription: str = "single_shooting",
              n_shooting: int = 10, ipopt_options: dict | None = None, guess_widths: dict | None = None) -> NLP:
    """Transcribe the problem into an IPOPT NLP.

    Each case contributes the integral smooth maxima J_s of |sigma| and J_d of
    |sigma_dyn| (:func:`objective_quadrature`, integrated by CVODES with
    error control, so no output grid limits their resolution), the motor
    speed at t_max, and the discrete smooth maxima of |i_a|/I_max and
    |e_a|/V_max over ``grid``.  The objective is J_s + TIE_BREAK*J_d
    (``'peak'``: least peak stress, and among ramps of equal peak the least
    dynamic stress) or J_d (``'dynamic'``); with several cases, the worst of
    these per-case objectives (one epigraph variable).

    Parameters
    ----------
    problem : RampProblem
        The declared problem (objective, t_max, speed fraction, profile).
    model : SmoothStartup
        Smooth model of the profile family.
    cases : list of (str, Parameters)
        Cases (scenarios) with gains resolved.
    grid : TimeGrid
        Sampling grid of the current and voltage constraints (t_max on it).
    sigma_scale : float
        Stress scale [Pa] (objectives are in its units).
    theta_scale : ndarray
        Scale of each profile number (physical = scaled * scale).
    theta0 : ndarray
        Initial guess of the profile numbers (physical units).
    transcription : {'single_shooting', 'multiple_shooting'}
    n_shooting : int, default 10
        Intervals of multiple shooting.
    ipopt_options : dict, optional
        Options passed to IPOPT (``ipopt.`` prefix added unless present).
    guess_widths : dict, optional
        Smoothing widths for simulating the multiple-shooting initial guess.

    Returns
    -------
    NLP
        Its parameters are [beta, c_s, c_d, widths...] (:meth:`NLP.parameters`).
    """
    if transcription not in TRANSCRIPTIONS:
        raise ParameterError(f"transcription {transcription!r} is unknown: choose one of {TRANSCRIPTIONS}")
    prof = problem.profile
    n_th = len(prof.names)
    z = ca.MX.sym("z", n_th)
    widths_names = model.width_names
    pp = ca.MX.sym("p", 3 + len(widths_names))
    beta, c_s, c_d = pp[0], pp[1], pp[2]
    widths = {n: pp[3 + i] for i, n in enumerate(widths_names)}
    theta = z * ca.DM(theta_scale)
    robust = len(cases) > 1
    peak = problem.objective == "peak"
    qexpr = objective_quadrature(model)
    i_i, i_e, i_w = OUTPUTS.index("i_a"), OUTPUTS.index("e_a"), OUTPUTS.index("speed_rpm")
    extra_w, extra_w0, g, lbg, ubg, names = [], [], [], [], [], []
    Js, Jd = [], []
    callback = None
    if transcription == "single_shooting":
        run = SensitivityRun(model, grid.t, qexpr, rtol=model.rtol, atol=model.atol)
        callback = CaseCallback(run, cases, theta_scale, grid.k_tmax, CONSTRAINT_BETA, TAU)
        out = callback(z)
    for ic, (cname, cp) in enumerate(cases):
        if callback is not None:
            j_s, j_d, speed, ks_i, ks_e = (out[CaseCallback.ROWS * ic + k] for k in range(CaseCallback.ROWS))
        else:
            P = ca.DM(model.param_vector(cp))
            pfull = ca.vertcat(P, beta, c_s, c_d, 1.0 / sigma_scale)
            x0 = model.x0(cp, theta, widths)
            X, Q, nodes, cont, guess = _multiple_shooting(model, cp, x0, pfull, grid, n_shooting, theta0,
                                                          guess_widths, qexpr)
            extra_w += nodes
            extra_w0 += guess
            for k, cr in enumerate(cont):
                g.append(cr)
                lbg += [0.0] * cr.shape[0]
                ubg += [0.0] * cr.shape[0]
                names += [f"{cname}: continuity at shooting node {k + 1}"] * cr.shape[0]
            Y = model.output_map(grid.n)(X, grid.t, P)
            j_s = integral_smooth_max(Q[0], beta, c_s)
            j_d = integral_smooth_max(Q[1], beta, c_d)
            ia = Y[i_i, :].T / cp.I_max
            ea = Y[i_e, :].T / cp.V_max
            speed = Y[i_w, grid.k_tmax] / cp.omega_ref
            ks_i = smooth_max(ca.vertcat(ia, -ia), CONSTRAINT_BETA)
            ks_e = smooth_max(ca.vertcat(ea, -ea), CONSTRAINT_BETA)
        Js.append(j_s)
        Jd.append(j_d)
        g += [problem.speed_fraction - speed, ks_i - 1.0, ks_e - 1.0]
        lbg += [-np.inf] * 3
        ubg += [0.0] * 3
        names += [f"{cname}: speed at t_max = {problem.t_max:g} s reaches {problem.speed_fraction:g} of omega_ref",
                  f"{cname}: armature current within I_max = {cp.I_max:g} A",
                  f"{cname}: armature voltage within V_max = {cp.V_max:g} V"]
    # per case: 'peak' -> J_s + TIE_BREAK*J_d, 'dynamic' -> J_d; several cases: their worst (epigraph)
    objs = [js + TIE_BREAK * jd for js, jd in zip(Js, Jd)] if peak else Jd
    eps = []
    if robust:
        s_w = ca.MX.sym("s_w")
        eps.append(s_w)
        f = s_w
        g += [j - s_w for j in objs]
        lbg += [-np.inf] * len(objs)
        ubg += [0.0] * len(objs)
        names += [f"{cname}: objective below the worst case" for cname, _ in cases]
    else:
        f = objs[0]
    w = [z] + eps + extra_w
    gg = ca.vertcat(*g)
    nlp = {"x": ca.vertcat(*w), "p": pp, "f": f, "g": gg}
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
            "ipopt.hessian_approximation": "limited-memory", "ipopt.max_iter": 150, "ipopt.tol": 1e-6,
            "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 3, "ipopt.mu_strategy": "adaptive",
            # forward-mode derivatives through the integrators (few parameters; CVODES adjoints
            # of the multiple-shooting intervals failed on the stiff mesh in tests)
            "oracle_options": {"ad_weight": 0.0}}
    for k, v in (ipopt_options or {}).items():
        opts[k if "." in k or k == "oracle_options" else f"ipopt.{k}"] = v
    solver = ca.nlpsol("ramp_nlp", "ipopt", nlp, opts)
    z0 = np.asarray(theta0, dtype=float) / theta_scale
    n_eps = len(eps)
    # epigraph variables start above every case (the solver lowers them)
    parts = [z0, np.full(n_eps, 10.0)] + [np.ravel(x) for x in extra_w0]
    w0 = np.concatenate(parts)
    n_extra = int(sum(x.shape[0] for x in extra_w))
    lbw = np.concatenate([lb / theta_scale for lb in [problem.bounds()[0]]] + [np.full(n_eps, -np.inf),
                                                                             np.full(n_extra, -np.inf)])
    ubw = np.concatenate([problem.bounds()[1] / theta_scale, np.full(n_eps, np.inf), np.full(n_extra, np.inf)])
    g_fun = ca.Function("g_eval", [nlp["x"], pp], [gg, f, ca.vertcat(*Js), ca.vertcat(*Jd)])
    return NLP(solver, w0, lbw, ubw, np.array(lbg, float), np.array(ubg, float), n_th, np.asarray(theta_scale),
               names, widths_names, transcription, g_fun, callback, 1.0 / sigma_scale)


def _multiple_shooting(model: SmoothStartup, cp, x0, pfull, grid: TimeGrid, n_shooting, theta0, guess_widths, quad):
    """States on the grid and the objective integral from ``n_shooting`` intervals with node variables."""
    if isinstance(n_shooting, bool) or not isinstance(n_shooting, int) or not 2 <= n_shooting <= grid.n:
        raise ParameterError(f"n_shooting = {n_shooting!r} must be an integer in 2..{grid.n}")
    t = grid.t
    cuts = np.linspace(0, grid.n, n_shooting + 1).round().astype(int)
    nx = model.plant.scales.size
    # initial guess of the nodes: the smooth model run at theta0 with the guess widths
    P = model.param_vector(cp)
    Xg = np.asarray(model.integrator(0.0, t)(x0=model.x0(cp, np.asarray(theta0, float), guess_widths), p=P)["xf"])
    pieces, nodes, cont, guess = [], [], [], []
    Q = 0
    xk = x0
    for k in range(n_shooting):
        a, b = cuts[k], cuts[k + 1]
        t0 = 0.0 if a == 0 else t[a - 1]
        r = model.integrator(t0, t[a:b], ("objective", *quad))(x0=xk, p=pfull)
        pieces.append(r["xf"])
        Q = Q + r["qf"][:, -1]
        if k < n_shooting - 1:
            node = ca.MX.sym(f"S{k + 1}", nx)
            nodes.append(node)
            guess.append(Xg[:, b - 1])
            cont.append(node - r["xf"][:, -1])
            xk = node
    return ca.horzcat(*pieces), Q, nodes, cont, guess
