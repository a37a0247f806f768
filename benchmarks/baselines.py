"""The kiln-drive equations written again, as a competent user would without kilnctl.

Two independent implementations of the plant of :mod:`kilnctl.model`, written
from the paper's equations and kilnctl's documented modelling choices (not by
calling kilnctl), to time kilnctl against and to cross-check it:

(a) :class:`ScipyHybrid` -- scipy ``solve_ivp`` with a plain-Python
    right-hand side per mode, terminal events on the guards and a restart at
    every mode switch.  Same mode logic as kilnctl: ramp end, burden
    breakaway / re-stick (``friction_law`` 'torque' or 'paper', with the
    Filippov ``held`` mode when a switch would cascade without time passing),
    mesh contact / separation / back contact, voltage and current limits with
    anti-windup, and the momentum-conserving projection of speeds when rigid
    links close.  Same tolerances (atol on states scaled as kilnctl scales
    them), output on the same grid (multiples of dt, plus the event points).

(b) :class:`ControlSmooth` -- python-control ``nlsys`` +
    ``input_output_response`` of the same equations in one smooth system,
    since python-control cannot reset states or switch equations at events:
    stick-slip as a Stribeck curve times tanh(v/v_eps), backlash as a
    softplus dead zone, the limits as softplus clamps.  It differs from the
    hybrid model by its smoothing.

Both return a :class:`BaselineRun` with the same outputs as a kilnctl
Response (``i_a``, ``sigma`` ...) and :func:`summarize` computes the figures
users read in one way for every implementation.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["BaselineRun", "ScipyHybrid", "ControlSmooth", "EffectPlant", "PLANT_EFFECTS", "summarize", "summary_errors",
           "MODELS"]

#: state names and scales (the integrator's nominal magnitudes), as kilnctl declares them
MODELS = {
    "macro": (("z", "x_a", "omega_motor", "omega_kiln", "omega_burden", "psi"),
              (1e2, 1e3, 50.0, 0.05, 0.05, 1.0)),
    "micro": (("z", "x_a", "omega_motor", "phi_c", "omega_pinion", "ds", "omega_kiln", "omega_burden", "psi"),
              (1e2, 1e3, 50.0, 0.05, 0.3, 1e-3, 0.05, 0.05, 1.0)),
}
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
BEARING_OMEGA_EPS = 1e-4   # tanh regularisation of the bearing friction [rad/s] (kilnctl's choice)
V_REL_SCALE = 1e-2         # re-stick guard scale [rad/s]
DS_SCALE = 1e-4            # mesh guard scale [m]
EVENT_OFFSET = 1e-12       # an event fires when a guard falls below -1e-12 (not at exactly zero)


class _NP:
    """numpy in place of :mod:`math` (for the outputs, evaluated on arrays of samples)."""

    sin, cos, tanh, fmax, fmin = np.sin, np.cos, np.tanh, np.fmax, np.fmin


NP = _NP()


class _M:
    """:mod:`math` with fmax/fmin (scalar right-hand sides)."""

    sin, cos, tanh = math.sin, math.cos, math.tanh
    fmax, fmin = staticmethod(max), staticmethod(min)


M = _M()


# ----------------------------------------------------------------------------------------------
# results and the figures users read
# ----------------------------------------------------------------------------------------------
@dataclass
class BaselineRun:
    """Result of a baseline simulation.

    Attributes
    ----------
    t : ndarray
        Sample times [s] (an event time appears twice, before and after the switch).
    outputs : dict of str to ndarray
        ``i_a`` [A], ``speed_rpm`` [rpm], ``sigma`` [Pa], ``W_t`` [N], ``psi`` [rad], ``v_rel`` [rad/s].
    events : list of tuple
        (t [s], kind, component, from_mode, to_mode) in time order.
    wall_s : float
        Wall time of the run [s].
    info : dict
        Solver, step and call counts.
    """

    t: np.ndarray
    outputs: dict
    events: list = field(default_factory=list)
    wall_s: float = 0.0
    info: dict = field(default_factory=dict)


def summarize(t, outputs, events=(), window: float = 5.0) -> dict:
    """Figures users read, computed the same way for kilnctl and every baseline.

    Parameters
    ----------
    t : ndarray
        Sample times [s].
    outputs : mapping
        Needs ``i_a`` [A] and ``sigma`` [Pa].
    events : sequence
        Events as objects with ``t``, ``kind`` or as tuples (t, kind, ...).
    window : float, default 5.0
        Final-current averaging window [s] (as ``Response.summary``).

    Returns
    -------
    dict
        ``peak_current_A`` (max |i_a|), ``final_current_A`` (time-weighted mean of
        i_a over the last ``window`` seconds), ``peak_stress_Pa`` (max |sigma|),
        ``event_times`` {kind: [t, ...]} of the physical switches (Filippov
        ``sliding_mode`` entries included).
    """
    t = np.asarray(t, float)
    i_a, sig = np.asarray(outputs["i_a"], float), np.asarray(outputs["sigma"], float)
    # mean over exactly [t_end - window, t_end], the left edge interpolated, so that the figure does not
    # depend on where the samples fall
    t0 = t[-1] - window
    m = t > t0
    k = int(np.argmax(m))
    if k > 0 and m.sum() >= 1:
        i0 = i_a[k - 1] + (i_a[k] - i_a[k - 1]) * (t0 - t[k - 1]) / (t[k] - t[k - 1]) if t[k] > t[k - 1] else i_a[k]
        tw, iw = np.concatenate([[t0], t[m]]), np.concatenate([[i0], i_a[m]])
        final = float(np.trapezoid(iw, tw) / window)
    else:
        final = float(np.trapezoid(i_a, t) / (t[-1] - t[0])) if len(t) > 1 else float(i_a[-1])
    ev: dict[str, list] = {}
    for e in events:
        te, kind = (e.t, e.kind) if hasattr(e, "t") else (e[0], e[1])
        ev.setdefault(kind, []).append(float(te))
    return {"peak_current_A": float(np.max(np.abs(i_a))), "final_current_A": final,
            "peak_stress_Pa": float(np.max(np.abs(sig))), "event_times": ev}


def summary_errors(s: dict, ref: dict, t_floor: float = 1.0) -> dict:
    """Relative errors of a summary against a reference summary.

    Parameters
    ----------
    s, ref : dict
        From :func:`summarize`.
    t_floor : float, default 1.0
        An event-time error is relative to the event's own time, but never to
        less than ``t_floor`` seconds (an event near t = 0).

    Returns
    -------
    dict
        ``peak_current``, ``final_current``, ``peak_stress`` (|a-b|/|b|),
        ``event_times`` (max over matched events of |t-t_ref|/max(t_ref, t_floor);
        inf when the lists differ in kinds or counts; None when either has no
        event list), and ``max`` of them all.
    """
    err = {}
    for key, name in (("peak_current_A", "peak_current"), ("final_current_A", "final_current"),
                      ("peak_stress_Pa", "peak_stress")):
        err[name] = abs(s[key] - ref[key]) / max(abs(ref[key]), 1e-300)
    a, b = s.get("event_times"), ref.get("event_times")
    if a is None or b is None:
        err["event_times"] = None
    elif set(a) != set(b) or any(len(a[k]) != len(b[k]) for k in b):
        err["event_times"] = math.inf
    else:
        err["event_times"] = max((abs(x - y) / max(abs(y), t_floor) for k in b for x, y in zip(a[k], b[k])),
                                 default=0.0)
    err["max"] = max(v for v in err.values() if v is not None)
    return err


def _p(params):
    """Plain floats (and option strings) of a kilnctl Parameters, plus the derived values."""
    v = dict(params.as_dict()) if hasattr(params, "as_dict") else dict(params)
    v["n_p"] = v["R_o"] / v["R_p"]
    v["n_r"] = v["n"] / v["n_p"]
    v["k_e"] = v["k_o"] * v["k_pi"] / (v["k_o"] + v["k_pi"])
    v["J_kiln"] = v["J_o"] if v["J_e_mode"] == "sum" else v["J_e"] - v["J_v"]
    v["T_brg"] = v["mu_brg"] * v["P"] * math.cos(math.radians(30.0)) * (v["l_brg"] + v["k_brg"]) / 2.0
    return v


def _output_grid(t0, t_end, dt):
    """Sample times in (t0, t_end]: the multiples of dt, and t_end."""
    k0 = math.floor(t0 / dt + 1e-9) + 1
    t = np.arange(k0, math.floor(t_end / dt + 1e-9) + 1) * dt
    t = t[(t > t0) & (t < t_end - 1e-12)]
    return np.append(t, t_end) if t_end > t0 else t


# ----------------------------------------------------------------------------------------------
# (a) scipy solve_ivp, hybrid: one right-hand side per mode, events, restarts
# ----------------------------------------------------------------------------------------------
class ScipyHybrid:
    """The hybrid kiln-drive plant in plain Python for scipy ``solve_ivp``.

    Parameters
    ----------
    params : kilnctl.Parameters or mapping
        Numeric values with the gains resolved (k_p, k_I, k_D used as given).
    model : {'macro', 'micro'}
        Rigid reducer (eqs. 1-21) or coupling + pinion + mesh with backlash (eqs. 26-34).

    Notes
    -----
    Modes are tuples (ramp, voltage_limit, current_limit, [mesh,] burden) like
    kilnctl's.  States are physical; the absolute tolerance is ``atol`` times
    each state's nominal scale, i.e. the same as kilnctl's atol on scaled states.
    """

    def __init__(self, params, model: str = "macro"):
        if model not in MODELS:
            raise ValueError(f"model must be 'macro' or 'micro', not {model!r}")
        self.p = _p(params)
        self.model = model
        self.micro = model == "micro"
        self.state_names, scales = MODELS[model]
        self.scales = np.array(scales)
        self.nx = len(self.state_names)
        self.components = ("ramp", "voltage_limit", "current_limit") + (("mesh",) if self.micro else ()) + ("burden",)
        self.n_rhs = 0

    # --- initial state and mode ----------------------------------------------------------
    def initial(self):
        """Physical initial state and initial mode tuple."""
        p = self.p
        x = np.zeros(self.nx)
        x[self.state_names.index("psi")] = p["psi_0"]
        mode = ["rising", "free", "free"]
        if self.micro:
            x[self.state_names.index("ds")] = p["delta_x"] * (1.0 - p["gap_0"])
            mode.append("contact" if p["delta_x"] == 0 or p["gap_0"] == 0 else "gap")
        mode.append("stick")
        return x, tuple(mode)

    # --- the equations of one mode -------------------------------------------------------
    def _eval(self, t, x, mode, full=False, lib=M):
        """Derivatives (and, with ``full``, guards and outputs) at (t, x) in ``mode``.

        ``lib`` is :data:`M` (math) for one point, or :data:`NP` for arrays of points
        (x with one row per state), as used for the outputs.

        Returns
        -------
        dx : list of float
        extra : dict or None
            With ``full``: ``g`` (guard values), ``targets``, ``kinds``, outputs.
        """
        p = self.p
        micro = self.micro
        if micro:
            z, x_a, om, phi, om_p, ds, om_k, om_b, psi = x
            ramp, volt, cur, mesh, burden = mode
        else:
            z, x_a, om, om_k, om_b, psi = x
            ramp, volt, cur, burden = mode
        # ramp (reference) and PID, eq. 21
        if ramp == "rising":
            e_v, ev_dot = p["ramp_rate"] * t, p["ramp_rate"]
        else:
            e_v, ev_dot = p["omega_ref"], 0.0
        e_f = e_v - p["K_fb"] * om
        e_pi = p["k_p"] * e_f + p["k_I"] * z
        integ = 1.0
        if volt == "free":
            e_a = e_pi
        else:
            e_a, integ = (p["V_max"] if volt == "upper" else -p["V_max"]), 0.0
        i_free = x_a + p["k_D"] / p["L_a"] * e_f
        limited = cur != "free"
        if limited:
            i_a, integ = (p["I_max"] if cur == "upper" else -p["I_max"]), 0.0
        else:
            i_a = i_free
        T_m = p["k_i"] * i_a - p["B_m"] * om
        # kiln, bearing (eq. 17) and burden loads
        T_k = -p["T_brg"] * lib.tanh(om_k / BEARING_OMEGA_EPS)
        s_psi, c_psi = lib.sin(psi), lib.cos(psi)
        T_b = -p["m_v"] * p["g"] * p["L"] * s_psi
        N = p["m_v"] * p["g"] * lib.fmax(c_psi, 0.0)
        stuck = burden in ("stick", "held")
        if not stuck:
            T_kin = (1.0 if burden == "slip_pos" else -1.0) * p["mu_c"] * N * p["R"]
            T_b += T_kin
            T_k -= T_kin
        J_k, J_v = p["J_kiln"], p["J_v"]
        if micro:
            rate_c = om - p["n_r"] * om_p
            spring = p["k_c"] * phi
            if p["coupling_law"] == "progressive":
                spring *= 1.0 + (phi / p["phi_c_ref"]) ** 2
            T_c = spring + p["c_c"] * rate_c
            rate_s = p["R_p"] * om_p - p["R_o"] * om_k
            if mesh == "contact":
                W = lib.fmax(p["k_e"] * (ds - p["delta_x"]) + p["C_e"] * rate_s, 0.0)
            elif mesh == "back":
                W = lib.fmin(p["k_e"] * ds + p["C_e"] * rate_s, 0.0)
            else:
                W = 0.0 * ds
            T_m -= T_c
            T_p = p["n_r"] * T_c - W * p["R_p"]
            T_k += W * p["R_o"]
            acc_m = T_m / p["J_m"]
            acc_p = T_p / p["J_p"]
            if stuck:
                acc_k = acc_b = (T_k + T_b) / (J_k + J_v)
            else:
                acc_k, acc_b = T_k / J_k, T_b / J_v
            W_t = W
        else:  # rigid reducer: motor and kiln one body through n
            n = p["n"]
            if stuck:
                acc_m = (T_m + (T_k + T_b) / n) / (p["J_m"] + (J_k + J_v) / n ** 2)
                acc_k = acc_b = acc_m / n
            else:
                acc_m = (T_m + T_k / n) / (p["J_m"] + J_k / n ** 2)
                acc_k, acc_b = acc_m / n, T_b / J_v
            # tangential force at the girth gear: the torque the reducer delivers to the kiln side
            # (kiln shell, and the burden too while the wall holds it) over R_o
            W_t = (J_k * acc_k - T_k + ((J_v * acc_b - T_b) if stuck else 0.0)) / p["R_o"]
        ef_dot = ev_dot - p["K_fb"] * acc_m
        if limited:
            dx_a = -p["k_D"] / p["L_a"] * ef_dot
        else:
            dx_a = (e_a - p["R_a"] * i_a - p["k_b"] * om) / p["L_a"]
        if micro:
            dx = [integ * e_f, dx_a, acc_m, rate_c, acc_p, rate_s, acc_k, acc_b, om_b]
        else:
            dx = [integ * e_f, dx_a, acc_m, acc_k, acc_b, om_b]
        if not full:
            return dx, None
        # guards: the mode holds while g > 0 (same order and scaling as kilnctl)
        g, tg, kinds, comps = [], [], [], []

        def guard(val, target, kind, comp):
            g.append(val), tg.append(target), kinds.append(kind), comps.append(comp)

        if ramp == "rising":
            t_r = p["omega_ref"] / p["ramp_rate"]
            guard((t_r - t) / t_r, "hold", "ramp_end", "ramp")
        V = p["V_max"]
        if volt == "free":
            guard((V - e_pi) / V, "upper", "voltage_limit", "voltage_limit")
            guard((V + e_pi) / V, "lower", "voltage_limit", "voltage_limit")
        elif volt == "upper":
            guard((e_pi - V) / V, "free", "voltage_limit_release", "voltage_limit")
        else:
            guard((-V - e_pi) / V, "free", "voltage_limit_release", "voltage_limit")
        I = p["I_max"]
        if cur == "free":
            guard((I - i_a) / I, "upper", "current_limit", "current_limit")
            guard((I + i_a) / I, "lower", "current_limit", "current_limit")
        else:
            v_free = e_a + p["k_D"] * ef_dot - p["R_a"] * i_a - p["k_b"] * om
            guard((1.0 if cur == "upper" else -1.0) * v_free / V, "free", "current_limit_release", "current_limit")
        if micro:
            dxb = p["delta_x"]
            if mesh == "contact":
                guard((ds - dxb) / DS_SCALE, "gap", "separation", "mesh")
            elif mesh == "gap":
                guard((dxb - ds) / DS_SCALE, "contact", "contact", "mesh")
                guard(ds / DS_SCALE, "back", "back_contact", "mesh")
            else:
                guard(-ds / DS_SCALE, "gap", "back_separation", "mesh")
        v_rel = om_k - om_b
        scale = p["m_v"] * p["g"] * p["R"]
        if stuck:
            T_need = J_v * acc_b - T_b          # wall torque that holds the burden on the kiln
            T_f = T_need
            if burden == "held" or p["friction_law"] == "torque":
                cap = (p["mu_c"] if burden == "held" else p["mu_s"]) * N * p["R"]
                guard((cap - T_need) / scale, "slip_pos", "breakaway", "burden")
                guard((cap + T_need) / scale, "slip_neg", "breakaway", "burden")
            else:  # printed law: F_t against F_bf (eqs. 1-3)
                guard(p["mu_s"] * c_psi - s_psi, "slip_pos", "breakaway", "burden")
                guard(p["mu_s"] * c_psi + s_psi, "slip_neg", "breakaway", "burden")
        else:
            T_f = T_kin
            guard((v_rel if burden == "slip_pos" else -v_rel) / V_REL_SCALE, "stick", "restick", "burden")
        Kv = 1.0 if p["dynamic_factor"] == "none" else (6.1 + p["R_o"] * abs(om_k)) / 6.1
        out = {"i_a": i_a, "speed_rpm": om * RPM_PER_RAD_S, "sigma": W_t * Kv / (p["face_width"] * p["module"] * p["Y_lewis"]),
               "W_t": W_t, "psi": psi, "v_rel": v_rel, "T_f": T_f, "e_a": e_a}
        return dx, {"g": g, "targets": tg, "kinds": kinds, "comps": comps, "out": out}

    def rhs(self, mode):
        """Right-hand side f(t, x) of one mode, for ``solve_ivp``."""
        ev = self._eval

        def f(t, x):
            self.n_rhs += 1
            return ev(t, x, mode)[0]
        return f

    def guards(self, t, x, mode):
        """Guard values, targets, kinds and components of ``mode`` at (t, x)."""
        return self._eval(t, x, mode, full=True)[1]

    def guard_rates(self, t, x, mode, h=1e-7):
        """dg/dt along the flow of ``mode`` (central difference along the right-hand side)."""
        f = np.asarray(self._eval(t, x, mode)[0])
        gp = np.array(self.guards(t + h, x + h * f, mode)["g"])
        gm = np.array(self.guards(t - h, x - h * f, mode)["g"])
        return (gp - gm) / (2 * h)

    # --- mode switches ----------------------------------------------------------------------
    def project(self, x, mode):
        """Node speeds made consistent with the rigid links of ``mode``, conserving momentum."""
        p = self.p
        x = np.array(x, float)
        sn = self.state_names
        i_k, i_b = sn.index("omega_kiln"), sn.index("omega_burden")
        stuck = mode[-1] in ("stick", "held")
        if self.micro:
            if stuck:
                J = p["J_kiln"] + p["J_v"]
                w = (p["J_kiln"] * x[i_k] + p["J_v"] * x[i_b]) / J
                x[i_k] = x[i_b] = w
        else:
            i_m, n = sn.index("omega_motor"), p["n"]
            Jk = p["J_kiln"] / n ** 2
            Jb = p["J_v"] / n ** 2 if stuck else 0.0
            H = p["J_m"] * x[i_m] + Jk * n * x[i_k] + Jb * n * x[i_b]
            w = H / (p["J_m"] + Jk + Jb)
            x[i_m], x[i_k] = w, w / n
            if stuck:
                x[i_b] = w / n
        return x

    def violated(self, t, x, mode, tol=1e-10):
        """Index of the first guard ``mode`` is already outside of, or None."""
        g = self.guards(t, x, mode)["g"]
        gd = None
        for j, gj in enumerate(g):
            if gj < -1e-7:
                return j
            if gj <= tol:
                gd = self.guard_rates(t, x, mode) if gd is None else gd
                if gd[j] < -tol:
                    return j
        return None

    def settle(self, mode, x, t, first=None):
        """Switch modes at time t until no guard is violated; returns mode, x, switches."""
        switched, visited, tried = [], [mode], set()
        j = first if first is not None else self.violated(t, x, mode)
        for _ in range(32):
            if j is None:
                return mode, x, switched
            gi = self.guards(t, x, mode)
            comp, kind = gi["comps"][j], gi["kinds"][j]
            i = self.components.index(comp)
            new = mode[:i] + (gi["targets"][j],) + mode[i + 1:]
            if new in visited:
                cycle = {m[i] for m in visited[visited.index(new):]} | {new[i]}
                ok = comp == "burden" and ({"stick", "held"} & cycle) and ({"slip_pos", "slip_neg"} & cycle)
                if not ok or (i, "held") in tried:
                    raise RuntimeError(f"{comp} switches {sorted(cycle)} without time passing at t = {t}")
                tried.add((i, "held"))
                new, kind = mode[:i] + ("held",) + mode[i + 1:], "sliding_mode"
            switched.append((t, kind, comp, mode[i], new[i]))
            visited.append(new)
            mode = new
            x = self.project(x, mode)
            j = self.violated(t, x, mode)
        raise RuntimeError(f"more than 32 mode switches at t = {t}")

    # --- the run ------------------------------------------------------------------------------
    def simulate(self, t_end: float = 40.0, dt: float | None = None, rtol: float = 1e-8, atol: float = 1e-9,
                 method: str = "LSODA", max_events: int = 5000, **ivp_kwargs) -> BaselineRun:
        """Run a start-up from rest.

        Parameters
        ----------
        t_end : float
            Horizon [s].
        dt : float, optional
            Output step [s] (default 5 ms macro, 1 ms micro, as kilnctl).
        rtol, atol : float
            ``solve_ivp`` tolerances; atol applies to states divided by their scales.
        method : str, default 'LSODA'
            ``solve_ivp`` method.
        max_events : int
            Mode switches allowed.
        **ivp_kwargs
            Passed to ``solve_ivp`` (``max_step`` ...).

        Returns
        -------
        BaselineRun
        """
        dt = (5e-3 if self.model == "macro" else 1e-3) if dt is None else dt
        wall0 = time.perf_counter()
        self.n_rhs = 0
        atol_v = atol * self.scales
        x, mode = self.initial()
        t = 0.0
        mode, x, sw = self.settle(mode, x, t)
        events = list(sw)
        seg_t, seg_x, seg_m = [np.array([t])], [x[:, None]], [mode]
        n_ivp = 0
        while t < t_end * (1 - 1e-12):
            gi = self.guards(t, x, mode)
            evfuns = []
            for j in range(len(gi["g"])):
                def ev(tt, xx, j=j, mode=mode, memo=[None, None, None]):
                    # all guards of the mode at once; solve_ivp asks for each at the same point
                    if memo[0] != tt or memo[1] is None or not np.array_equal(memo[1], xx):
                        memo[0], memo[1], memo[2] = tt, np.array(xx), self.guards(tt, xx, mode)["g"]
                    # a guard that is exactly zero where the segment starts (the pinion resting on
                    # the back flank, a burden just released) must not fire on its first step
                    return memo[2][j] + EVENT_OFFSET
                ev.terminal, ev.direction = True, -1
                evfuns.append(ev)
            te_grid = _output_grid(t, t_end, dt)
            sol = solve_ivp(self.rhs(mode), (t, t_end), x, method=method, t_eval=te_grid, events=evfuns or None,
                            rtol=rtol, atol=atol_v, **ivp_kwargs)
            n_ivp += 1
            if not sol.success:
                raise RuntimeError(f"solve_ivp failed at t = {t}: {sol.message}")
            if len(sol.t):
                seg_t.append(np.asarray(sol.t)), seg_x.append(np.asarray(sol.y)), seg_m.append(mode)
            if sol.status != 1:
                break
            hits = [(te[0], j) for j, te in enumerate(sol.t_events) if len(te)]
            te, j = min(hits)
            xe = sol.y_events[j][0]
            seg_t.append(np.array([te])), seg_x.append(xe[:, None]), seg_m.append(mode)
            mode, x, sw = self.settle(mode, xe, te, first=j)
            events.extend(sw)
            if len(events) > max_events:
                raise RuntimeError(f"more than {max_events} mode switches by t = {te}")
            t = te
            seg_t.append(np.array([t])), seg_x.append(x[:, None]), seg_m.append(mode)
        # outputs at the samples, one vectorised evaluation per segment (part of the timed run)
        outs: dict[str, list] = {}
        for ts, X, m in zip(seg_t, seg_x, seg_m):
            o = self._eval(ts, X, m, full=True, lib=NP)[1]["out"]
            for key, v in o.items():
                outs.setdefault(key, []).append(np.broadcast_to(v, ts.shape))
        outs = {k: np.concatenate(v) for k, v in outs.items()}
        wall = time.perf_counter() - wall0
        return BaselineRun(np.concatenate(seg_t), outs, events, wall,
                           {"method": method, "rtol": rtol, "atol": atol, "n_rhs": self.n_rhs, "n_solve_ivp": n_ivp,
                            "n_events": len(events)})


# ----------------------------------------------------------------------------------------------
# (b) python-control nlsys: one smooth system (no resets, no events)
# ----------------------------------------------------------------------------------------------
def _softplus(x, eps):
    """eps*log(1 + exp(x/eps)), overflow-safe: a smooth max(x, 0) with corner width eps."""
    u = x / eps
    return eps * (u + math.log1p(math.exp(-u))) if u > 0 else eps * math.log1p(math.exp(u))


def _sigmoid(x, eps):
    u = x / eps
    if u >= 0:
        return 1.0 / (1.0 + math.exp(-u))
    e = math.exp(u)
    return e / (1.0 + e)


class ControlSmooth:
    """The kiln-drive plant as one smooth python-control ``nlsys``.

    Parameters
    ----------
    params : kilnctl.Parameters or mapping
        Numeric values, gains resolved.  Stick-slip follows the torque law
        (the smooth Stribeck curve has a static level mu_s*N*R and a kinetic
        level mu_c*N*R); the printed law has no smooth counterpart.
    model : {'macro', 'micro'}
    v_eps : float, default 1e-5
        tanh velocity scale of the wall friction [rad/s].
    v_stribeck : float, default 1e-3
        Velocity over which static friction falls to kinetic [rad/s].
    x_eps : float, default 1e-6
        Softplus width of the backlash dead zone [m].
    w_eps : float, default 1e3
        Softplus width of the clip that keeps the mesh force from pulling [N].
    v_clip_eps : float, default 0.5
        Softplus width of the voltage clamp [V] (and of the current-limit release [V]).
    i_clip_eps : float, default 1.0
        Softplus width of the current clamp [A].
    """

    def __init__(self, params, model: str = "macro", v_eps: float = 1e-5, v_stribeck: float = 1e-3,
                 x_eps: float = 1e-6, w_eps: float = 1e3, v_clip_eps: float = 0.5, i_clip_eps: float = 1.0):
        self.p = _p(params)
        self.model = model
        self.micro = model == "micro"
        self.state_names, scales = MODELS[model]
        self.scales = np.array(scales)
        self.eps = dict(v=v_eps, vs=v_stribeck, x=x_eps, w=w_eps, V=v_clip_eps, I=i_clip_eps)
        self.sys = None

    def _eval(self, t, x, full=False):
        p, eps, micro = self.p, self.eps, self.micro
        if micro:
            z, x_a, om, phi, om_p, ds, om_k, om_b, psi = x
        else:
            z, x_a, om, om_k, om_b, psi = x
        t_r = p["omega_ref"] / p["ramp_rate"]
        e_v, ev_dot = (p["ramp_rate"] * t, p["ramp_rate"]) if t < t_r else (p["omega_ref"], 0.0)
        e_f = e_v - p["K_fb"] * om
        e_pi = p["k_p"] * e_f + p["k_I"] * z
        V, I = p["V_max"], p["I_max"]
        # smooth clamp of the PI voltage, integrator gated while clamped
        e_a = e_pi - _softplus(e_pi - V, eps["V"]) + _softplus(-V - e_pi, eps["V"])
        gate_v = _sigmoid(V - e_pi, eps["V"]) * _sigmoid(V + e_pi, eps["V"])
        i_free = x_a + p["k_D"] / p["L_a"] * e_f
        i_a = i_free - _softplus(i_free - I, eps["I"]) + _softplus(-I - i_free, eps["I"])
        s_up, s_lo = _sigmoid(i_free - I, eps["I"]), _sigmoid(-I - i_free, eps["I"])
        integ = gate_v * (1.0 - s_up) * (1.0 - s_lo)
        T_m = p["k_i"] * i_a - p["B_m"] * om
        T_k = -p["T_brg"] * math.tanh(om_k / BEARING_OMEGA_EPS)
        s_psi, c_psi = math.sin(psi), math.cos(psi)
        T_b = -p["m_v"] * p["g"] * p["L"] * s_psi
        N = p["m_v"] * p["g"] * max(c_psi, 0.0)
        v_rel = om_k - om_b
        mu = p["mu_c"] + (p["mu_s"] - p["mu_c"]) * math.exp(-(v_rel / eps["vs"]) ** 2)
        T_f = mu * N * p["R"] * math.tanh(v_rel / eps["v"])
        T_b += T_f
        T_k -= T_f
        if micro:
            rate_c = om - p["n_r"] * om_p
            spring = p["k_c"] * phi
            if p["coupling_law"] == "progressive":
                spring *= 1.0 + (phi / p["phi_c_ref"]) ** 2
            T_c = spring + p["c_c"] * rate_c
            rate_s = p["R_p"] * om_p - p["R_o"] * om_k
            dxb, ke, Ce = p["delta_x"], p["k_e"], p["C_e"]
            w_f = ke * _softplus(ds - dxb, eps["x"]) + Ce * rate_s * _sigmoid(ds - dxb, eps["x"])
            w_b = -ke * _softplus(-ds, eps["x"]) + Ce * rate_s * _sigmoid(-ds, eps["x"])
            W = _softplus(w_f, eps["w"]) - _softplus(-w_b, eps["w"])
            T_m -= T_c
            T_p = p["n_r"] * T_c - W * p["R_p"]
            T_k += W * p["R_o"]
            acc_m, acc_p = T_m / p["J_m"], T_p / p["J_p"]
            acc_k, acc_b = T_k / p["J_kiln"], T_b / p["J_v"]
            W_t = W
        else:
            n = p["n"]
            acc_m = (T_m + T_k / n) / (p["J_m"] + p["J_kiln"] / n ** 2)
            acc_k, acc_b = acc_m / n, T_b / p["J_v"]
            W_t = (p["J_kiln"] * acc_k - T_k) / p["R_o"]
        ef_dot = ev_dot - p["K_fb"] * acc_m
        v_free = e_a + p["k_D"] * ef_dot - p["R_a"] * i_a - p["k_b"] * om
        # at a current limit the current may only fall back (the drive holds it there)
        dx_a = (v_free - s_up * _softplus(v_free, eps["V"]) + s_lo * _softplus(-v_free, eps["V"])) / p["L_a"] \
            - p["k_D"] / p["L_a"] * ef_dot
        if micro:
            dx = [integ * e_f, dx_a, acc_m, rate_c, acc_p, rate_s, acc_k, acc_b, om_b]
        else:
            dx = [integ * e_f, dx_a, acc_m, acc_k, acc_b, om_b]
        if not full:
            return dx
        Kv = 1.0 if p["dynamic_factor"] == "none" else (6.1 + p["R_o"] * abs(om_k)) / 6.1
        return [i_a, om * RPM_PER_RAD_S, W_t * Kv / (p["face_width"] * p["module"] * p["Y_lewis"]), W_t, psi, v_rel]

    OUTPUTS = ("i_a", "speed_rpm", "sigma", "W_t", "psi", "v_rel")

    def system(self):
        """The python-control ``nlsys`` (built once)."""
        import control as ct

        if self.sys is None:
            self.sys = ct.nlsys(lambda t, x, u, params: self._eval(t, x),
                                lambda t, x, u, params: self._eval(t, x, full=True),
                                states=list(self.state_names), inputs=0, outputs=list(self.OUTPUTS),
                                name=f"kiln_{self.model}_smooth")
        return self.sys

    def initial(self):
        x = np.zeros(len(self.state_names))
        x[self.state_names.index("psi")] = self.p["psi_0"]
        if self.micro:
            x[self.state_names.index("ds")] = self.p["delta_x"] * (1.0 - self.p["gap_0"])
        return x

    def simulate(self, t_end: float = 40.0, dt: float | None = None, rtol: float = 1e-8, atol: float = 1e-9,
                 method: str = "LSODA", **ivp_kwargs) -> BaselineRun:
        """Run a start-up with ``input_output_response`` (one solve_ivp over the horizon).

        Parameters
        ----------
        t_end, dt, rtol, atol, method
            As :meth:`ScipyHybrid.simulate` (output on t = 0, dt, 2 dt, ...).

        Returns
        -------
        BaselineRun
        """
        import control as ct

        dt = (5e-3 if self.model == "macro" else 1e-3) if dt is None else dt
        sys = self.system()
        T = np.linspace(0.0, t_end, int(round(t_end / dt)) + 1)
        wall0 = time.perf_counter()
        kw = {"rtol": rtol, "atol": atol * self.scales}
        kw.update(ivp_kwargs)
        r = ct.input_output_response(sys, T, 0.0, self.initial(), solve_ivp_method=method, solve_ivp_kwargs=kw)
        wall = time.perf_counter() - wall0
        y = np.atleast_2d(r.outputs)
        return BaselineRun(np.asarray(r.time), dict(zip(self.OUTPUTS, y)), [], wall,
                           {"method": method, "rtol": rtol, "atol": atol, "eps": dict(self.eps)})


# ----------------------------------------------------------------------------------------------
# (c) the plant with physical effects in forms of its own, for the diagnosis benchmark
# ----------------------------------------------------------------------------------------------
#: effect settings of :class:`EffectPlant` and their neutral values (the plant without the effect)
PLANT_EFFECTS = {
    "current_bw": 2000.0,  # bandwidth of the inner current loop [rad/s] (it limits the current to I_max)
    "J_m2": 0.0,           # second motor rotor on the motor shaft [kg m^2]
    "k_tw": 0.0,           # torsional stiffness of the drive train at the kiln axis [N m/rad]; 0: rigid
    "beta_tw": 0.0,        # stiffness-proportional damping of the drive train [s]: c = beta_tw * k
    "gap": 0.0,            # backlash at the kiln axis [rad] (girth-gear play / R_o); 0: none
    "k_gap": 0.0,          # contact stiffness behind the backlash [N m/rad] (0: the mesh's k_e R_o^2)
    "c_gap": 0.0,          # contact damping behind the backlash [N m s/rad] (0: the mesh's C_e R_o^2)
    "tau_sensor": 0.0,     # first-order lag of the speed sensor [s] (controller AND logged speed)
    "B_kiln": 0.0,         # viscous drag on the kiln shell [N m s/rad]
    "B_motor": 0.0,        # viscous drag (windage, seals) on the motor shaft [N m s/rad]
    "m_ecc": 0.0,          # eccentric mass on the kiln (coating ring) [kg]
    "r_ecc": 0.0,          # its distance from the kiln axis [m]
    "phi_ecc": 0.0,        # its angle from the bottom dead centre at t = 0 [rad]
    "T_load": 0.0,         # a resisting torque switched onto the kiln at t_load [N m] (outside the catalogue)
    "t_load": math.inf,    # when [s]
}
EFFECT_STATES = ("z", "i_a", "omega_motor", "twist", "omega_kiln", "omega_burden", "psi", "omega_sensor",
                 "theta_kiln")
EFFECT_SCALES = (1e2, 1e3, 50.0, 1e-3, 0.05, 0.05, 1.0, 50.0, 1.0)


class EffectPlant(ScipyHybrid):
    """The macro plant with effects written in forms of its own, for records the diagnosis has not seen.

    Written from the physics, not from :mod:`kilnctl.model`: the armature
    current is a physical state driven by the armature voltage, and the
    current limit is an inner current loop of finite bandwidth (not an ideal
    clamp); the speed sensor's lag is in the logged speed as well as in the
    controller's; the drive train is a two-mass system (motor side and kiln
    side) with stiffness-proportional damping; backlash is a dead zone in that
    link; viscous drag acts on the motor shaft and on the kiln; the kiln
    unbalance is the gravity torque of an eccentric mass; and a load torque
    can be switched on at a set time (an effect outside kilnctl's catalogue).
    The burden's stick-slip is :class:`ScipyHybrid`'s state machine.

    Parameters
    ----------
    params : kilnctl.Parameters or mapping
        Base values (gains resolved, ``friction_law`` as wanted).
    **effects : float
        Settings of :data:`PLANT_EFFECTS` [units given there]; unknown names
        raise ``ValueError``.

    Notes
    -----
    Modes are (ramp, voltage_limit, current_loop, link, burden, load):
    current_loop 'free' / 'upper' / 'lower' (while limiting, the loop holds
    dI/dt = current_bw (I_max - i) and the speed integrator is frozen); link
    'rigid', 'spring' (compliance, no play), 'gap', 'contact', 'back'.
    """

    def __init__(self, params, **effects):
        unknown = sorted(set(effects) - set(PLANT_EFFECTS))
        if unknown:
            raise ValueError(f"unknown plant effect(s) {unknown}; known: {sorted(PLANT_EFFECTS)}")
        super().__init__(params, "macro")
        self.fx = dict(PLANT_EFFECTS)
        self.fx.update({k: float(v) for k, v in effects.items()})
        f, p = self.fx, self.p
        if f["gap"] > 0:
            k_m = f["k_gap"] or p["k_e"] * p["R_o"] ** 2
            c_m = f["c_gap"] or p["C_e"] * p["R_o"] ** 2
            # a compliant drive train in series with the stiff mesh behind the play
            self.k_link = k_m if f["k_tw"] <= 0 else 1.0 / (1.0 / k_m + 1.0 / f["k_tw"])
            self.c_link = c_m if f["k_tw"] <= 0 else f["beta_tw"] * self.k_link
        else:
            self.k_link, self.c_link = f["k_tw"], f["beta_tw"] * f["k_tw"]
        self.model = "effects"
        self.state_names, self.scales = EFFECT_STATES, np.array(EFFECT_SCALES)
        self.nx = len(EFFECT_STATES)
        self.components = ("ramp", "voltage_limit", "current_loop", "link", "burden", "load")

    @property
    def J_motor_side(self) -> float:
        """Inertia of the motor side (motor and second motor) [kg m^2]."""
        return self.p["J_m"] + self.fx["J_m2"]

    @property
    def J_kiln_side(self) -> float:
        """Inertia of the kiln shell with the eccentric mass [kg m^2]."""
        return self.p["J_kiln"] + self.fx["m_ecc"] * self.fx["r_ecc"] ** 2

    def initial(self):
        """Physical initial state and initial mode tuple (at rest, the play open in front)."""
        x = np.zeros(self.nx)
        x[EFFECT_STATES.index("psi")] = self.p["psi_0"]
        link = "rigid" if self.k_link <= 0 else ("spring" if self.fx["gap"] <= 0 else "back")
        return x, ("rising", "free", "free", link, "stick", "off" if self.fx["t_load"] > 0 else "on")

    def _eval(self, t, x, mode, full=False, lib=M):
        p, f = self.p, self.fx
        z, i_a, om, tw, om_k, om_b, psi, om_s, th_k = x
        ramp, volt, cur, link, burden, load = mode
        if ramp == "rising":
            e_v, ev_dot = p["ramp_rate"] * t, p["ramp_rate"]
        else:
            e_v, ev_dot = p["omega_ref"], 0.0
        lag = f["tau_sensor"] > 0
        e_f = e_v - p["K_fb"] * (om_s if lag else om)
        e_pi = p["k_p"] * e_f + p["k_I"] * z
        integ = 1.0
        if volt == "free":
            e_a = e_pi
        else:
            e_a, integ = (p["V_max"] if volt == "upper" else -p["V_max"]), 0.0
        # loads: bearing (eq. 17), drags, eccentric mass, the switched load, burden friction
        T_m = p["k_i"] * i_a - (p["B_m"] + f["B_motor"]) * om
        T_k = (-p["T_brg"] * lib.tanh(om_k / BEARING_OMEGA_EPS) - f["B_kiln"] * om_k
               - f["m_ecc"] * p["g"] * f["r_ecc"] * lib.sin(th_k + f["phi_ecc"]))
        if load == "on":
            T_k = T_k - f["T_load"]
        s_psi, c_psi = lib.sin(psi), lib.cos(psi)
        T_b = -p["m_v"] * p["g"] * p["L"] * s_psi
        N = p["m_v"] * p["g"] * lib.fmax(c_psi, 0.0)
        stuck = burden in ("stick", "held")
        if not stuck:
            T_kin = (1.0 if burden == "slip_pos" else -1.0) * p["mu_c"] * N * p["R"]
            T_b = T_b + T_kin
            T_k = T_k - T_kin
        n, J_ms, J_k, J_v = p["n"], self.J_motor_side, self.J_kiln_side, p["J_v"]
        if link == "rigid":
            rate_tw = 0.0 * tw
            if stuck:
                acc_m = (T_m + (T_k + T_b) / n) / (J_ms + (J_k + J_v) / n ** 2)
                acc_k = acc_b = acc_m / n
            else:
                acc_m = (T_m + T_k / n) / (J_ms + J_k / n ** 2)
                acc_k, acc_b = acc_m / n, T_b / J_v
            T_link = n * (T_m - J_ms * acc_m)
        else:
            rate_tw = om / n - om_k
            k, c, gap = self.k_link, self.c_link, f["gap"]
            if link == "spring":
                T_link = k * tw + c * rate_tw
            elif link == "contact":
                T_link = lib.fmax(k * (tw - gap) + c * rate_tw, 0.0)
            elif link == "back":
                T_link = lib.fmin(k * tw + c * rate_tw, 0.0)
            else:
                T_link = 0.0 * tw
            acc_m = (T_m - T_link / n) / J_ms
            T_k = T_k + T_link
            if stuck:
                acc_k = acc_b = (T_k + T_b) / (J_k + J_v)
            else:
                acc_k, acc_b = T_k / J_k, T_b / J_v
        acc_s = (om - om_s) / f["tau_sensor"] if lag else acc_m
        ef_dot = ev_dot - p["K_fb"] * acc_s
        v_pid = e_a + p["k_D"] * ef_dot   # the armature voltage the speed controller asks for
        bw, I = f["current_bw"], p["I_max"]
        v_hi = p["R_a"] * i_a + p["k_b"] * om + p["L_a"] * bw * (I - i_a)    # what the current loop allows
        v_lo = p["R_a"] * i_a + p["k_b"] * om + p["L_a"] * bw * (-I - i_a)
        if cur == "free":
            v = v_pid
        else:
            v, integ = (v_hi if cur == "upper" else v_lo), 0.0
        di = (v - p["R_a"] * i_a - p["k_b"] * om) / p["L_a"]
        dx = [integ * e_f, di, acc_m, rate_tw, acc_k, acc_b, om_b, acc_s, om_k]
        if not full:
            return dx, None
        g, tg, kinds, comps = [], [], [], []

        def guard(val, target, kind, comp):
            g.append(val), tg.append(target), kinds.append(kind), comps.append(comp)

        if ramp == "rising":
            t_r = p["omega_ref"] / p["ramp_rate"]
            guard((t_r - t) / t_r, "hold", "ramp_end", "ramp")
        V = p["V_max"]
        if volt == "free":
            guard((V - e_pi) / V, "upper", "voltage_limit", "voltage_limit")
            guard((V + e_pi) / V, "lower", "voltage_limit", "voltage_limit")
        elif volt == "upper":
            guard((e_pi - V) / V, "free", "voltage_limit_release", "voltage_limit")
        else:
            guard((-V - e_pi) / V, "free", "voltage_limit_release", "voltage_limit")
        if cur == "free":
            guard((v_hi - v_pid) / V, "upper", "current_limit", "current_loop")
            guard((v_pid - v_lo) / V, "lower", "current_limit", "current_loop")
        elif cur == "upper":
            guard((v_pid - v_hi) / V, "free", "current_limit_release", "current_loop")
        else:
            guard((v_lo - v_pid) / V, "free", "current_limit_release", "current_loop")
        gap = f["gap"]
        if link == "contact":
            guard((tw - gap) / DS_SCALE * p["R_o"], "gap", "separation", "link")
        elif link == "gap":
            guard((gap - tw) / DS_SCALE * p["R_o"], "contact", "contact", "link")
            guard(tw / DS_SCALE * p["R_o"], "back", "back_contact", "link")
        elif link == "back":
            guard(-tw / DS_SCALE * p["R_o"], "gap", "back_separation", "link")
        if load == "off" and math.isfinite(f["t_load"]):
            guard((f["t_load"] - t) / max(f["t_load"], 1.0), "on", "load_step", "load")
        v_rel = om_k - om_b
        scale = p["m_v"] * p["g"] * p["R"]
        if stuck:
            T_need = J_v * acc_b - T_b
            if burden == "held" or p["friction_law"] == "torque":
                cap = (p["mu_c"] if burden == "held" else p["mu_s"]) * N * p["R"]
                guard((cap - T_need) / scale, "slip_pos", "breakaway", "burden")
                guard((cap + T_need) / scale, "slip_neg", "breakaway", "burden")
            else:
                guard(p["mu_s"] * c_psi - s_psi, "slip_pos", "breakaway", "burden")
                guard(p["mu_s"] * c_psi + s_psi, "slip_neg", "breakaway", "burden")
        else:
            guard((v_rel if burden == "slip_pos" else -v_rel) / V_REL_SCALE, "stick", "restick", "burden")
        out = {"i_a": i_a, "speed_rpm": (om_s if lag else om) * RPM_PER_RAD_S,
               "speed_motor_rpm": om * RPM_PER_RAD_S, "speed_ref_rpm": e_v + 0.0 * om,
               "T_link": T_link, "twist": tw, "omega_kiln": om_k, "psi": psi, "v_rel": v_rel, "theta_kiln": th_k}
        return dx, {"g": g, "targets": tg, "kinds": kinds, "comps": comps, "out": out}

    def project(self, x, mode):
        """Speeds made consistent with the rigid links of ``mode``, conserving momentum."""
        p = self.p
        x = np.array(x, float)
        i_m, i_k, i_b = 2, 4, 5
        stuck = mode[4] in ("stick", "held")
        J_k, J_v, n = self.J_kiln_side, p["J_v"], p["n"]
        if mode[3] == "rigid":
            Jb = J_v / n ** 2 if stuck else 0.0
            H = self.J_motor_side * x[i_m] + J_k / n * x[i_k] + Jb * n * x[i_b]
            w = H / (self.J_motor_side + J_k / n ** 2 + Jb)
            x[i_m], x[i_k] = w, w / n
            if stuck:
                x[i_b] = w / n
        elif stuck:
            w = (J_k * x[i_k] + J_v * x[i_b]) / (J_k + J_v)
            x[i_k] = x[i_b] = w
        return x
