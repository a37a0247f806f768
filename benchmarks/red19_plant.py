"""Red team 19's independent plant of the rotary-kiln drive (van Dyk & Pretorius 1994), kiln K-19.

Who and from what
-----------------
Written by a red-team helper (red team 19) from the paper's equations (eqs. 1-21) and the reading
notes ``NOTES.md``, apart from kilnctl: this module imports the standard library and numpy only, and
nothing of kilnctl's model, simulator or synthetic generator.  It is kept here as the helper wrote it
(originally ``/work/runs/red19/plant.py``): the equations, numbers, integration and their order are
unchanged, so records written with it are the red team's byte for byte
(:mod:`benchmarks.red19_records`, which holds the record definitions, logger, noise and truth).  Only
this docstring head and the public functions' docstrings were added, and one unused local name was
dropped (``p`` in :meth:`Plant.run`).

How it was checked against kilnctl (the red team's, with no effect)
--------------------------------------------------------------------
Noise-free, effect-free records at the base kiln's own values (:func:`default_params`) through
``kilnctl compare``: current rms difference 0.0099 A (against about 360 A running) and speed
0.00045 rpm under the paper law, 0.019 A and 0.00087 rpm under the torque law; a torque-law record
against the paper-law setup differs by 67.8 A (the law matters).

The helper's own description
----------------------------
Independent rotary-kiln start-up plant (red team 19).

Written from van Dyk & Pretorius (1994), eqs. 1-21, and /work/shared/paper/NOTES.md.
Conventions (own):
  * burden angle psi from bottom dead centre in the sense of rotation (paper's Phi = pi - psi),
    so F_t = m g sin(psi), F_bf = mu_s m g cos(psi).
  * speed loop in rpm: e_f = e_v - K*omega_fb, K = 60/(2 pi); e_pi = k_p e_f + k_I z, clamped
    to +-V_max (integrator frozen while clamped); the derivative k_D*de_f/dt acts in the
    armature voltage and is integrated by L_a into a direct current term (eq. 21 line 2):
    i_a = x_a + (k_D/L_a) e_f,  L_a dx_a/dt = e_a - R_a i_a - k_b omega_m.
  * rigid gear omega_m = n omega_o (eq. 9) unless a compliance/backlash effect is on.
  * burden: stick (moves with the shell, eq. 11/18) or slip (eqs. 15/16/19) with the kinetic
    torque mu_c N R opposing the relative velocity.  Breakaway 'paper' (force comparison,
    eq. 3) or 'torque' (holding torque > mu_s N R).  Re-stick when v_rel crosses zero and the
    stick condition holds there.
  * bearing torque eq. 17, T = mu_brg P cos30 (l+k)/2, sign regularised with tanh(w/1e-4).
Integration: fixed-step RK4 (default 0.25 ms) with bisection-located mode switches.
"""
import math

G = 9.81
KFB = 60.0 / (2.0 * math.pi)


def default_params():
    """The base kiln K-19's parameters (SI; speeds of the drive in rpm), friction law and ramp start.

    Returns
    -------
    dict
        Motor (``R_a``, ``L_a``, ``k_i``, ``k_b``, ``J_m``, ``B_m``), controller (``k_p``, ``k_I``,
        ``k_D``), drive (``omega_ref``, ``ramp_rate`` [rpm, rpm/s], ``V_max``, ``I_max``), kiln (``J_o``,
        ``J_v``, ``m_v``, ``L``, ``R``, ``mu_c``, ``mu_s``, ``mu_brg``, ``P``, ``l_brg``, ``k_brg``), gear
        ``n``, ``friction_law`` ('paper') and ``t_ramp`` [s], the start of the ramp.
    """
    return dict(
        R_a=0.021, L_a=1.4e-3, k_i=3.0, k_b=3.0, J_m=12.0, B_m=0.008,
        k_p=0.6, k_I=6.0, k_D=0.02,
        omega_ref=680.0, ramp_rate=60.0, V_max=300.0, I_max=700.0,
        J_o=2.6e6, J_v=2.9e5, m_v=1.9e5, L=1.05, R=1.6, mu_c=0.35, mu_s=0.57,
        mu_brg=0.0011, P=5.4e6, l_brg=0.48, k_brg=0.38, n=850.0,
        friction_law="paper", t_ramp=1.0,
    )


# state indices
Z, XA, WM, WL, PHI, PSI, WB, TH, THM, Y1, Y2, UL = range(12)
NS = 12


class Plant:
    """p: parameter dict; fx: effect dict (keys below, all optional).

    fx keys (own forms):
      J_m2, c_fan            : second motor rigid on the shaft + fan windage c_fan*w|w|
      ilim, G_l, tau_l       : converter current limit: u_l lag voltage taken off e_a
      k_c, eta_c, J_g        : compliant pinion coupling (motor-side stiffness k_c [Nm/rad]),
                               hysteretic (rate-independent) damping with loss factor eta_c,
                               gearbox inertia J_g on the motor side of it
      gap, gap0, k_h, c_h    : backlash, total play 'gap' [motor rad], initially 'gap0' of it
                               open, Hunt-Crossley contact T = k_h d^1.5 (1 + c_h d')
      tau_s2, zeta_s         : second-order speed sensor (w_n = 1/tau_s2)
      T_unb, phi_unb, e_R    : unbalance -T_unb sin(th+phi) and friction arm R(1+e_R cos(th+phi))
      B0, B1, tau_B          : kiln drag B(t) = B1 + (B0-B1) exp(-(t-t_ramp)/tau_B)
      T_cm, T_cb, th_cb      : motor friction T_cm + (T_cb-T_cm) exp(-theta_m/th_cb)
      slump_t, slump_frac, slump_dur : burden slump (X1)
    """

    def __init__(self, p, fx=None):
        self.p = dict(p)
        self.fx = dict(fx or {})
        f = self.fx
        self.flex = ("k_c" in f) or ("gap" in f)
        self.Tbrg = p["mu_brg"] * p["P"] * math.cos(math.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2.0
        self.mode = "stick"

    # ---- helpers ----
    def ref(self, t):
        p = self.p
        tr = t - p["t_ramp"]
        if tr <= 0:
            return 0.0
        return min(p["ramp_rate"] * tr, p["omega_ref"])

    def burden_mass(self, t):
        p, f = self.p, self.fx
        m, J = p["m_v"], p["J_v"]
        if "slump_t" in f:
            x = (t - f["slump_t"]) / f["slump_dur"]
            x = min(max(x, 0.0), 1.0)
            s = 1.0 - f["slump_frac"] * (x * x * (3 - 2 * x))
            m *= s
            J *= s
        return m, J

    def omega_fb(self, s):
        if "tau_s2" in self.fx:
            return s[Y1] / KFB
        return s[WM]

    def current(self, t, s):
        p = self.p
        e_f = self.ref(t) - KFB * self.omega_fb(s)
        return s[XA] + p["k_D"] / p["L_a"] * e_f, e_f

    def meas_speed_rpm(self, s):
        if "tau_s2" in self.fx:
            return s[Y1]
        return KFB * s[WM]

    # ---- dynamics ----
    def deriv(self, t, s, mode=None, want_need=False):
        p, f = self.p, self.fx
        mode = mode or self.mode
        d = [0.0] * NS
        n = p["n"]
        m_v, J_v = self.burden_mass(t)
        # controller
        i_a, e_f = self.current(t, s)
        e_pi = p["k_p"] * e_f + p["k_I"] * s[Z]
        integ = 1.0
        if e_pi > p["V_max"]:
            e_pi = p["V_max"]
            integ = 0.0 if e_f > 0 else 1.0
        elif e_pi < -p["V_max"]:
            e_pi = -p["V_max"]
            integ = 0.0 if e_f < 0 else 1.0
        e_a = e_pi
        if "ilim" in f:
            e_a -= s[UL]
            d[UL] = (-s[UL] + f["G_l"] * max(i_a - f["ilim"], 0.0)) / f["tau_l"]
            if s[UL] > 0.5:
                integ = 0.0
        d[Z] = integ * e_f
        wm = s[WM]
        d[XA] = (e_a - p["R_a"] * i_a - p["k_b"] * wm) / p["L_a"]
        # motor torques
        Tm = p["k_i"] * i_a - p["B_m"] * wm
        Jm = p["J_m"]
        if "J_m2" in f:
            Jm += f["J_m2"]
            Tm -= f.get("c_fan", 0.0) * wm * abs(wm)
        if "T_cm" in f:
            Tc = f["T_cm"] + (f["T_cb"] - f["T_cm"]) * math.exp(-abs(s[THM]) / f["th_cb"])
            Tm -= Tc * math.tanh(wm / 0.005)
        d[THM] = wm
        # kiln side
        wL = s[WL] if self.flex else wm
        wo = wL / n
        th = s[TH]
        Tk = -self.Tbrg * math.tanh(wo / 1e-4)
        Rw = p["R"]
        if "T_unb" in f:
            Tk -= f["T_unb"] * math.sin(th + f["phi_unb"])
            Rw = p["R"] * (1.0 + f.get("e_R", 0.0) * math.cos(th + f["phi_unb"]))
        if "B0" in f:
            tt = max(t - p["t_ramp"], 0.0)
            B = f["B1"] + (f["B0"] - f["B1"]) * math.exp(-tt / f["tau_B"])
            Tk -= B * wo
        d[TH] = wo
        psi = s[PSI]
        N = m_v * G * max(math.cos(psi), 0.0)
        Tgrav = m_v * G * p["L"] * math.sin(psi)
        if mode == "stick":
            Jk = p["J_o"] + J_v
            Tk -= Tgrav
            d[PSI] = wo
        else:
            Jk = p["J_o"]
            sgn = 1.0 if mode == "slip_pos" else -1.0
            Tw = sgn * p["mu_c"] * N * Rw
            Tk -= Tw
            d[PSI] = s[WB]
            d[WB] = (Tw - Tgrav) / J_v
        # drive train
        if not self.flex:
            J = Jm + Jk / n ** 2
            dw = (Tm + Tk / n) / J
            d[WM] = dw
            dwo = dw / n
        else:
            JL = f.get("J_g", 0.0) + Jk / n ** 2
            phi = s[PHI]
            dphi = wm - s[WL]
            if "k_c" in f:
                Ts = f["k_c"] * phi
                Tc = Ts + f["eta_c"] * abs(Ts) * math.tanh(dphi / 0.02)
            else:  # backlash, phi measured from the closed driving flank: contact at phi >= 0
                gap = f["gap"]
                if phi >= 0:
                    Tc = f["k_h"] * phi ** 1.5 * (1.0 + f["c_h"] * dphi)
                    Tc = max(Tc, 0.0)
                elif phi <= -gap:
                    dd = -gap - phi
                    Tc = -f["k_h"] * dd ** 1.5 * (1.0 - f["c_h"] * dphi)
                    Tc = min(Tc, 0.0)
                else:
                    Tc = 0.0
            d[PHI] = dphi
            d[WM] = (Tm - Tc) / Jm
            d[WL] = (Tc + Tk / n) / JL
            dwo = d[WL] / n
        if mode == "stick":
            d[WB] = dwo
        # speed sensor (2nd order, rpm)
        if "tau_s2" in f:
            wn = 1.0 / f["tau_s2"]
            d[Y1] = s[Y2]
            d[Y2] = wn * wn * (KFB * wm - s[Y1]) - 2 * f["zeta_s"] * wn * s[Y2]
        if want_need:
            # wall torque needed to keep the burden with the shell
            return d, J_v * dwo + Tgrav, N * Rw, psi
        return d

    def rk4(self, t, s, h):
        k1 = self.deriv(t, s)
        s2 = [a + 0.5 * h * b for a, b in zip(s, k1)]
        k2 = self.deriv(t + 0.5 * h, s2)
        s3 = [a + 0.5 * h * b for a, b in zip(s, k2)]
        k3 = self.deriv(t + 0.5 * h, s3)
        s4 = [a + h * b for a, b in zip(s, k3)]
        k4 = self.deriv(t + h, s4)
        return [a + h / 6.0 * (b + 2 * c + 2 * e + g) for a, b, c, e, g in zip(s, k1, k2, k3, k4)]

    # guard >= 0 while the current mode is valid
    def guard(self, t, s):
        p = self.p
        if self.mode == "stick":
            if p["friction_law"] == "paper":
                psi = s[PSI]
                return p["mu_s"] * math.cos(psi) - abs(math.sin(psi))
            _, need, NR, _ = self.deriv(t, s, "stick", want_need=True)
            return p["mu_s"] * NR - abs(need)
        wo = (s[WL] if self.flex else s[WM]) / p["n"]
        v = wo - s[WB]
        return v if self.mode == "slip_pos" else -v

    def stick_ok(self, t, s):
        return self.guard_for("stick", t, s) >= 0

    def guard_for(self, mode, t, s):
        m0 = self.mode
        self.mode = mode
        g = self.guard(t, s)
        self.mode = m0
        return g

    def switch(self, t, s):
        """Called at a located guard crossing; choose the new burden mode."""
        p = self.p
        if self.mode == "stick":
            if p["friction_law"] == "paper":
                self.mode = "slip_pos" if math.sin(s[PSI]) > 0 else "slip_neg"
            else:
                _, need, _, _ = self.deriv(t, s, "stick", want_need=True)
                self.mode = "slip_pos" if need > 0 else "slip_neg"
            wo = (s[WL] if self.flex else s[WM]) / p["n"]
            s[WB] = wo
        else:
            wo = (s[WL] if self.flex else s[WM]) / p["n"]
            s[WB] = wo
            if self.guard_for("stick", t, s) >= 0:
                self.mode = "stick"
            else:
                self.mode = "slip_neg" if self.mode == "slip_pos" else "slip_pos"
        self.events.append((t, self.mode))

    def run(self, t_end, dt=2.5e-4, store_every=4):
        """Integrate the start-up from rest (burden stuck at psi = 0).

        Parameters
        ----------
        t_end : float
            End time [s].
        dt : float, default 2.5e-4
            Fixed RK4 step [s]; a burden mode switch inside a step is located by bisection.
        store_every : int, default 4
            Keep every ``store_every``-th step (1 ms with the default step).

        Returns
        -------
        dict
            ``t`` [s], ``i`` armature current [A], ``w`` measured speed [rpm], ``r`` speed reference [rpm],
            ``psi`` burden angle [rad] (numpy arrays) and ``events``, the burden mode switches as
            ``(t, new mode)``.
        """
        s = [0.0] * NS
        f = self.fx
        s[PSI] = 0.0
        if "gap" in f:
            s[PHI] = -f["gap"] * f["gap0"]
        self.mode = "stick"
        self.events = []
        t = 0.0
        out_t, out_i, out_w, out_r, out_psi = [], [], [], [], []
        nsteps = int(round(t_end / dt))
        for k in range(nsteps + 1):
            if k % store_every == 0:
                i_a, _ = self.current(t, s)
                out_t.append(t)
                out_i.append(i_a)
                out_w.append(self.meas_speed_rpm(s))
                out_r.append(self.ref(t))
                out_psi.append(s[PSI])
            if k == nsteps:
                break
            g0 = self.guard(t, s)
            s1 = self.rk4(t, s, dt)
            g1 = self.guard(t + dt, s1)
            if g0 >= 0 and g1 < 0:
                lo, hi = 0.0, dt
                for _ in range(30):
                    mid = 0.5 * (lo + hi)
                    sm = self.rk4(t, s, mid)
                    if self.guard(t + mid, sm) >= 0:
                        lo = mid
                    else:
                        hi = mid
                se = self.rk4(t, s, hi)
                self.switch(t + hi, se)
                rest = dt - hi
                s1 = self.rk4(t + hi, se, rest) if rest > 0 else se
                # a second switch inside the same step is ignored (dt is small)
            s = s1
            t = (k + 1) * dt
        import numpy as np
        return dict(t=np.array(out_t), i=np.array(out_i), w=np.array(out_w),
                    r=np.array(out_r), psi=np.array(out_psi), events=list(self.events))


def simulate(p, fx=None, t_end=41.0, dt=2.5e-4):
    """Simulate a start-up of the plant.

    Parameters
    ----------
    p : dict
        Parameters (:func:`default_params`, possibly changed).
    fx : dict, optional
        Effects (keys in :class:`Plant`); none by default.
    t_end : float, default 41.0
        End time [s].
    dt : float, default 2.5e-4
        RK4 step [s].

    Returns
    -------
    dict
        As :meth:`Plant.run`.
    """
    pl = Plant(p, fx)
    return pl.run(t_end, dt)
