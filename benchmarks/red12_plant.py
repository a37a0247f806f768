"""Red team 12: an independent rotary-kiln drive plant (numpy/scipy only, no kilnctl), written by a helper that
did not read kilnctl's code (2026-11-27, fifth session); the plant is kept as written, the record definitions
below it are the red team's (``make_records.py``), gathered into :func:`record`.  Used as the truth of
tests/test_red12_plant.py.

Macro model after van Dyk & Pretorius (1994) eqs. 1-21 as read in kilnctl's model_reference.md,
written from scratch: PID with the derivative through L_a, DC motor, rigid reducer or a
spring-damper at the kiln axis, bearing friction, burden with stick / slip (paper or torque
breakaway), plus out-of-catalogue effects.  Integrated with scipy solve_ivp (DOP853) piecewise
between mode switches, switches located as terminal events.
"""
import numpy as np
from scipy.integrate import solve_ivp

RPM = 60.0 / (2 * np.pi)   # rpm per rad/s (K of eq. 21)


def kiln_F():
    """A 3.6 m cement kiln, one 250 kW DC motor (mine)."""
    return dict(R_a=0.02, L_a=1.0e-3, k_i=4.0, k_b=4.0, J_m=9.0, B_m=0.003,
                k_p=1.2, k_I=3.0, k_D=0.006, ramp_rate=90.0, omega_ref=900.0,
                V_max=450.0, I_max=1000.0,
                J_o=2.62e6, J_v=5.97e5, m_v=3.0e5, L=1.10, R=1.80, mu_c=0.40, mu_s=0.51,
                mu_brg=0.001, P=8.83e6, l_brg=0.55, k_brg=0.42, n=1250.0, g=9.81,
                friction_law="paper")


def kiln_G():
    """A 2.5 m lime kiln, small fast motor, short kiln revolution (38 s)."""
    return dict(R_a=0.05, L_a=2.5e-3, k_i=2.2, k_b=2.2, J_m=2.5, B_m=0.001,
                k_p=0.6, k_I=2.0, k_D=0.002, ramp_rate=150.0, omega_ref=1100.0,
                V_max=300.0, I_max=500.0,
                J_o=3.5e5, J_v=8.63e4, m_v=9.0e4, L=0.78, R=1.25, mu_c=0.38, mu_s=0.50,
                mu_brg=0.001, P=2.45e6, l_brg=0.40, k_brg=0.30, n=700.0, g=9.81,
                friction_law="paper")


class Plant:
    """p: dict of parameters (kiln_F()/kiln_G() + effects).

    effects (keys, all optional, default off):
      J_m2            extra motor-side inertia (second motor)
      B_o             viscous drag on kiln [N m s/rad];  B2_o quadratic drag T = B2_o*w_o*|w_o|
      T_unb, phi_unb  once-per-kiln-rev unbalance  -T_unb sin(theta_o+phi)
      T_cm            motor Coulomb friction (tanh, 0.01 rad/s)
      k_po, C_po      drive-train spring-damper at the kiln axis
      stribeck        (a, v_s): burden slip friction mu_c*(1 + a*exp(-|v_rel|/v_s)); breakaway when
                      the holding torque exceeds mu_c*(1+a)*N*R (continuous at v_rel = 0)
      T_ecc, n_pin, phi_ecc  gear eccentricity: kiln torque -T_ecc sin(n_pin*theta_o + phi)
                      (once per PINION revolution; n_pin = girth/pinion teeth)
      T_lift, w_lift  support-roller breakaway friction  -T_lift*exp(-|w_o|/w_lift)*tanh(w_o/1e-4)
      T_vw            roller friction falling linearly with kiln speed to 0 at the set speed
      fill            (t_start, rate_per_s, t_stop): m_v (and J_v) grow by rate*m_v0 per s
    """

    def __init__(self, p):
        self.p = dict(p)
        p = self.p
        self.T_brg = 2 * p["mu_brg"] * (p["P"] / 2) * np.cos(np.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2
        self.Jm_tot = p["J_m"] + p.get("J_m2", 0.0)
        self.rigid = "k_po" not in p
        self.t0 = p.get("t0", 1.0)

    # ------------------------------------------------------------------ helpers
    def ref(self, t):
        p = self.p
        return np.clip(p["ramp_rate"] * (t - self.t0), 0.0, p["omega_ref"])

    def mass(self, t):
        p = self.p
        m0, J0 = p["m_v"], p["J_v"]
        f = p.get("fill")
        if f is None:
            return m0, J0
        ts, r, te = f
        fac = 1.0 + r * (np.clip(t, ts, te) - ts)
        return m0 * fac, J0 * fac

    def mu_slip(self, vrel):
        p = self.p
        s = p.get("stribeck")
        if s is None:
            return p["mu_c"]
        a, vs = s
        return p["mu_c"] * (1 + a * np.exp(-abs(vrel) / vs))

    def mu_break(self):
        p = self.p
        s = p.get("stribeck")
        if s is not None:
            return p["mu_c"] * (1 + s[0])
        return p["mu_s"] if p["friction_law"] == "torque" else p["mu_c"]

    def kiln_ext(self, t, wo, th):
        """External load torque on the kiln shell (positive = opposing forward rotation)."""
        p = self.p
        T = self.T_brg * np.tanh(wo / 1e-4)
        T += p.get("B_o", 0.0) * wo + p.get("B2_o", 0.0) * wo * abs(wo)
        if "T_unb" in p:
            T += p["T_unb"] * np.sin(th + p.get("phi_unb", 0.0))
        if "T_ecc" in p:
            T += p["T_ecc"] * np.sin(p["n_pin"] * th + p.get("phi_ecc", 0.0))
        if "T_vw" in p:   # velocity-weakening roller friction, linear to zero at the set speed
            w_set = p["omega_ref"] / RPM / p["n"]
            T += p["T_vw"] * max(0.0, 1 - abs(wo) / w_set) * np.tanh(wo / 1e-4)
        if "T_lift" in p:
            T += p["T_lift"] * np.exp(-abs(wo) / p["w_lift"]) * np.tanh(wo / 1e-4)
        return T

    # ------------------------------------------------------------------ dynamics
    # y = [x_a, z, w_m, phi_po, w_o, theta_o, psi, w_b]
    def electrical(self, t, y):
        p = self.p
        x_a, z, wm = y[0], y[1], y[2]
        e_f = self.ref(t) - RPM * wm
        e_pi = p["k_p"] * e_f + p["k_I"] * z
        e_a = np.clip(e_pi, -p["V_max"], p["V_max"])
        integ = 1.0 if abs(e_pi) < p["V_max"] else 0.0
        i_a = x_a + p["k_D"] / p["L_a"] * e_f
        dx = (e_a - p["R_a"] * i_a - p["k_b"] * wm) / p["L_a"]
        return i_a, dx, integ * e_f

    def accel(self, t, y, mode):
        """returns (dw_m, dw_o, dw_b, T_need) ; mode 0 = stick, +1/-1 = slip sign."""
        p = self.p
        n = p["n"]
        i_a, _, _ = self.electrical(t, y)
        wm, phi, wo, th, psi, wb = y[2], y[3], y[4], y[5], y[6], y[7]
        if self.rigid:
            wo = wm / n
        m, Jv = self.mass(t)
        g = p["g"]
        Tg = m * g * p["L"] * np.sin(psi)
        N = m * g * max(np.cos(psi), 0.0)
        Tm = p["k_i"] * i_a - p["B_m"] * wm
        if "T_cm" in p:
            Tm -= p["T_cm"] * np.tanh(wm / 0.01)
        Text = self.kiln_ext(t, wo, th)
        if mode == 0:
            Tw = None
        else:
            Tw = mode * self.mu_slip(wo - wb) * N * p["R"]   # torque on burden
        if self.rigid:
            if mode == 0:
                J = self.Jm_tot + (p["J_o"] + Jv) / n**2
                dwm = (Tm - (Text + Tg) / n) / J
                dwo = dwm / n
                dwb = dwo
                Tneed = Jv * dwo + Tg
            else:
                J = self.Jm_tot + p["J_o"] / n**2
                dwm = (Tm - (Text + Tw) / n) / J
                dwo = dwm / n
                dwb = (-Tg + Tw) / Jv
                Tneed = None
        else:
            T = p["k_po"] * phi + p["C_po"] * (wm / n - wo)
            dwm = (Tm - T / n) / self.Jm_tot
            if mode == 0:
                dwo = (T - Text - Tg) / (p["J_o"] + Jv)
                dwb = dwo
                Tneed = Jv * dwo + Tg
            else:
                dwo = (T - Text - Tw) / p["J_o"]
                dwb = (-Tg + Tw) / Jv
                Tneed = None
        return dwm, dwo, dwb, Tneed, N, i_a

    def rhs(self, t, y, mode):
        p = self.p
        i_a, dx, dz = self.electrical(t, y)
        dwm, dwo, dwb, _, _, _ = self.accel(t, y, mode)
        wm, wo, wb = y[2], y[4], y[7]
        if self.rigid:
            wo = wm / p["n"]
        dphi = 0.0 if self.rigid else wm / p["n"] - wo
        if mode == 0:
            wb = wo
        return np.array([dx, dz, dwm, dphi, dwo, wo, wb, dwb])

    def guard(self, t, y, mode):
        p = self.p
        if mode == 0:
            _, _, _, Tneed, N, _ = self.accel(t, y, 0)
            return (self.mu_break() * N * p["R"] - abs(Tneed)) / (p["m_v"] * p["g"] * p["R"])
        wo = y[2] / p["n"] if self.rigid else y[4]
        return mode * (wo - y[7]) / 0.01

    # ------------------------------------------------------------------ run
    def run(self, t_out, rtol=1e-9, atol=1e-9, max_step=0.005):
        p = self.p
        t_end = float(t_out[-1])
        y = np.zeros(8)
        mode = 0
        t = self.t0
        corners = [self.t0 + p["omega_ref"] / p["ramp_rate"], t_end]
        ts, ys, ms = [], [], []
        self.events = []
        scale = np.array([1, 1, 1, 1e-4, 1e-3, 1e-3, 1e-3, 1e-3])
        while t < t_end - 1e-12:
            tb = min(c for c in corners if c > t + 1e-12)
            ev = lambda tt, yy, m=mode: self.guard(tt, yy, m)
            ev.terminal = True
            ev.direction = -1
            sol = solve_ivp(lambda tt, yy, m=mode: self.rhs(tt, yy, m), (t, tb), y, method="DOP853",
                            rtol=rtol, atol=atol * scale, max_step=max_step, events=ev, dense_output=True)
            if sol.status < 0:
                raise RuntimeError(sol.message)
            te = sol.t[-1]
            sel = (t_out >= t) & (t_out <= te)
            if sel.any():
                ts.append(t_out[sel]); ys.append(sol.sol(t_out[sel])); ms.append(np.full(sel.sum(), mode))
            y = sol.y[:, -1].copy()
            t = te
            if sol.status == 1:   # event
                if mode == 0:
                    # breakaway: slip in the sense of the holding torque
                    _, _, _, Tneed, _, _ = self.accel(t, y, 0)
                    mode = 1 if Tneed > 0 else -1
                    if self.rigid:
                        y[4] = y[2] / p["n"]
                    y[7] = y[4] if not self.rigid else y[2] / p["n"]
                    self.events.append((t, "breakaway"))
                else:
                    mode = 0
                    wo = y[2] / p["n"] if self.rigid else y[4]
                    y[7] = wo
                    # if sticking cannot hold, slip on (other sense)
                    if self.guard(t, y, 0) < 0:
                        _, _, _, Tneed, _, _ = self.accel(t, y, 0)
                        mode = 1 if Tneed > 0 else -1
                        self.events.append((t, "restick-rejected"))
                    else:
                        self.events.append((t, "restick"))
                # nudge past the event
                if len(self.events) > 20000:
                    raise RuntimeError("event storm")
        T = np.concatenate(ts); Y = np.concatenate(ys, axis=1); M = np.concatenate(ms)
        # unique samples (boundaries appear twice)
        _, idx = np.unique(T, return_index=True)
        T, Y, M = T[idx], Y[:, idx], M[idx]
        i_a = np.array([self.electrical(tt, Y[:, k])[0] for k, tt in enumerate(T)])
        wm = Y[2]
        # samples before t0
        I = np.zeros(len(t_out)); W = np.zeros(len(t_out))
        pos = np.searchsorted(t_out, T)
        I[pos] = i_a; W[pos] = wm * RPM
        e_pi = None
        return dict(t=t_out, current=I, speed=W, ref=self.ref(t_out), mode=np.r_[np.zeros(len(t_out) - len(T)), M],
                    psi=np.r_[np.zeros(len(t_out) - len(T)), Y[6]])


def ar1(n, dt, sigma, tau, rng):
    a = np.exp(-dt / tau)
    e = rng.standard_normal(n) * sigma * np.sqrt(1 - a * a)
    x = np.empty(n); x[0] = rng.standard_normal() * sigma
    for k in range(1, n):
        x[k] = a * x[k - 1] + e[k]
    return x


# ---- the red team's records (make_records.py), as a function -------------------------------------------------

#: the nuisance of every record: the plant's values over the setup's
NUISANCE = dict(m_v=1.03, mu_c=0.98, mu_s=1.04, J_v=0.96)

#: name: (kiln, effects, T [s], fs [Hz], noise (I white, I AR sigma, I AR tau, w white, w AR sigma, w AR tau), seed)
RECORDS = {
    "R15": ("G", {"T_vw": 1.5e4}, 40.0, 50.0, (1.5, 2.5, 0.4, 0.15, 0.2, 0.25), 1213),
    "R16": ("G", {}, 60.0, 50.0, (1.0, 4.0, 3.0, 0.2, 0.25, 3.0), 1214),
    "R17": ("F", {"T_vw": 1.4e5}, 40.0, 50.0, (1.5, 2.5, 0.4, 0.15, 0.2, 0.25), 1215),
}


def record(name):
    """The red team's record ``name``: (t, current [A], speed [rpm], speed_ref [rpm], setup dict, plant dict).

    The setup is the kiln's nominal values (what kilnctl is told); the plant runs them with
    :data:`NUISANCE` and the record's effects, and the noise is white plus AR(1) as the red team drew it.
    """
    kiln, effects, T, fs, (iw, ia, it, ww, wa, wt), seed = RECORDS[name]
    base = {"F": kiln_F, "G": kiln_G}[kiln]()
    true = dict(base)
    for k, f in NUISANCE.items():
        true[k] = base[k] * f
    true.update(effects)
    t = np.arange(0, T + 1e-9, 1 / fs)
    clean = Plant(true).run(t)
    rng = np.random.default_rng(seed)
    n, dt = len(t), 1 / fs
    current = clean["current"] + iw * rng.standard_normal(n) + ar1(n, dt, ia, it, rng)
    speed = clean["speed"] + ww * rng.standard_normal(n) + ar1(n, dt, wa, wt, rng)
    return t, current, speed, clean["ref"], base, true
