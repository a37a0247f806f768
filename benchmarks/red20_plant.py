"""Red team 20's independent plant of the rotary-kiln drive (van Dyk & Pretorius 1994), kiln K-20.

Who and from what
-----------------
Written by a red-team helper (red team 20) from the paper's equations (eqs. 1-21) and the reading
notes ``NOTES.md``, apart from kilnctl: this module imports the standard library and numpy only, and
nothing of kilnctl's model, simulator or synthetic generator.  It is kept here as the helper wrote it
(originally ``/work/runs/red20/plant.py``): the equations, numbers, integration and their order are
unchanged, so records written with it are the red team's byte for byte
(:mod:`benchmarks.red20_records`, which holds the record definitions, logger, noise and truth).  Only
this docstring head, :func:`default_params` (a copy of :data:`BASE`), the docstrings of :data:`BASE`,
:meth:`Plant.run` and :func:`simulate` and a blank line after ``import math`` were added.

The kiln K-20 (:data:`BASE`)
---------------------------
n 820, set speed 750 rpm (ramp 60 rpm/s from 1 s), J_m 16 kg m^2, k_i = k_b 5.0, V_max 520 V, I_max 900 A;
J_o 3.4e6, J_v 4.0e5 kg m^2, m_v 2.6e5 kg, L 1.15 m, R 1.9 m, mu_c 0.38, mu_s 0.45; about 380 A running, a
kiln turn every 66 s.  Its regime: **mu_c R / L = 0.38 x 1.9 / 1.15 = 0.628 > mu_s 0.45**, so under the
paper's (printed) friction law the burden sticks to tan psi = mu_s, is then held with the shell (the
Filippov held mode: the holding torque within mu_c N R) and slides smoothly from about 13 s on: one burden
mode switch in the whole run, no stick-slip cycles.  Under the torque law the same kiln cycles (19 switches,
a cycle of about 3 s), which record E8 builds on.

How it was checked against kilnctl (the red team's, with no effect)
--------------------------------------------------------------------
Noise-free, effect-free records at :data:`BASE` through ``kilnctl compare`` (the red team's
``base_check.md``): current rms difference 0.0032 A (against about 382 A running) and speed 3.3e-5 rpm
under the paper law, 0.030 A and 1.2e-3 rpm under the torque law; a torque-law record against the
paper-law setup differs by 20.3 A (the law matters).

The helper's own description
----------------------------
K-20 rotary-kiln start-up plant (red team 20), written from van Dyk & Pretorius (1994)
eqs. 1-21 and /work/shared/paper/NOTES.md.  Independent of kilnctl's code.

Base conventions (chosen to be the paper's macro model as NOTES reads it):
  * speed loop in rpm: e_f = r - K w_fb (K = 60/2pi); e_pi = k_p e_f + k_I z, clamped at
    +-V_max with the integrator frozen while clamped; k_D e_f' in the armature voltage is
    integrated by L_a into a direct current term: i_a = x + (k_D/L_a) e_f,
    L_a x' = e_a - R_a i_a - k_b w_m.
  * rigid reduction w_m = n w_o unless a drive-train element is on.
  * burden angle psi from bottom dead centre (absolute), psi_0 = 0.
    modes: 'att' (burden moves with the shell) and 'sl+'/'sl-' (sliding, v = w_o - w_b > 0/<0,
    wall torque +-mu_c N R on the burden).  'att' is valid while the paper's force test
    (|sin psi| <= mu_s cos psi) holds OR the holding torque it needs is within the kinetic
    bound mu_c N R (the Filippov sliding/held mode of the printed law).  Torque law: valid
    while the holding torque is within mu_s N R.
  * bearing torque eq. 17 with sign tanh(w_o/1e-4).
Integration: fixed-step RK4, located (bisection) mode switches.
"""
import math

import numpy as np

G = 9.81
KFB = 60.0 / (2.0 * math.pi)

BASE = dict(
    R_a=0.015, L_a=0.9e-3, k_i=5.0, k_b=5.0, J_m=16.0, B_m=0.01,
    k_p=0.5, k_I=4.0, k_D=0.012,
    omega_ref=750.0, ramp_rate=60.0, V_max=520.0, I_max=900.0,
    J_o=3.4e6, J_v=4.0e5, m_v=2.6e5, L=1.15, R=1.9, mu_c=0.38, mu_s=0.45,
    mu_brg=0.0012, P=8.2e6, l_brg=0.60, k_brg=0.45, n=820.0,
    t_ramp=1.0,
)
"""The base kiln K-20's parameters (SI; speeds of the drive in rpm) and the ramp's start ``t_ramp`` [s]."""


def default_params():
    """The base kiln K-20's parameters: a copy of :data:`BASE`.

    Returns
    -------
    dict
        Motor (``R_a``, ``L_a``, ``k_i``, ``k_b``, ``J_m``, ``B_m``), controller (``k_p``, ``k_I``,
        ``k_D``), drive (``omega_ref``, ``ramp_rate`` [rpm, rpm/s], ``V_max``, ``I_max``), kiln (``J_o``,
        ``J_v``, ``m_v``, ``L``, ``R``, ``mu_c``, ``mu_s``, ``mu_brg``, ``P``, ``l_brg``, ``k_brg``), gear
        ``n`` and ``t_ramp`` [s], the start of the ramp.  The friction law is the plant's effect ``law``
        (paper by default), not a parameter.
    """
    return dict(BASE)

# state: z, x, wm, thm, wl, phi, psi, wb, u(limiter), zc (unused)
Z, X, WM, THM, WL, PHI, PSI, WB, U, YF = range(10)
NS = 10


class Plant:
    """fx (effects, all optional; own forms):
    second motor   : J2 [kg m2], B2 [N m s/rad] eddy drag of the coasting second rotor
    current limit  : il0 [A], il_n1 [rpm], il_n2 [rpm], il_f [-] (limit falls linearly from il0
                     at n1 to il_f*il0 at n2: commutation limit), kl [V/A/s], kpl [V/A]
    compliance     : kc1 [N m/rad motor side] soft elastomer up to |phi|<ph1, kc2 beyond
                     (metal stops), cc [N m s/rad], Jg [kg m2] load side of the coupling
    backlash       : gap [rad motor side], gap0 [-], kt [N m/rad], ct [N m s/rad], Jg
    sensor lag     : Tw [s] speed = (theta(t)-theta(t-Tw))/Tw used by loop and logger
    unbalance      : U1, ph1u, U2, ph2u [N m kiln side]: -U1 sin(th+ph1) - U2 sin(2 th+ph2)
    drag           : cd [N m (s/rad)^a], ad [-]  T = cd |w_o|^ad sign(w_o) (kiln side)
    motor friction : Tc [N m], Ts [N m], ws [rad/s]: Stribeck, motor side
    tacho filter   : tau_f [s] first-order RC filter of the tachogenerator (loop and logger)
    aging law      : law='aging', mus_inf, tau_age: torque breakaway, static coef
                     mu_c + (mus_inf-mu_c)(1-exp(-t_stuck/tau_age))
    law='torque'   : plain torque law
    pinion         : Ap [N m kiln], nr [-], php : -Ap sin(thm/nr + php) (outside catalogue)
    """

    def __init__(self, p, fx=None):
        self.p = dict(p)
        self.fx = dict(fx or {})
        f = self.fx
        self.flex = ("kc1" in f) or ("gap" in f)
        self.Tbrg = p["mu_brg"] * p["P"] * math.cos(math.pi / 6) * (p["l_brg"] + p["k_brg"]) / 2.0
        self.law = f.get("law", "paper")
        self.hist_t = None

    def ref(self, t):
        tr = t - self.p["t_ramp"]
        if tr <= 0:
            return 0.0
        return min(self.p["ramp_rate"] * tr, self.p["omega_ref"])

    def wfb(self, t, s):
        """feedback / logged speed [rad/s motor]"""
        f = self.fx
        if "Tw" in f:
            Tw = f["Tw"]
            tp = t - Tw
            if tp <= 0:
                thp = 0.0
            else:
                thp = float(np.interp(tp, self.hist_t, self.hist_th))
            return (s[THM] - thp) / Tw
        if "tau_f" in f:
            return s[YF]
        return s[WM]

    def current(self, t, s):
        p = self.p
        e_f = self.ref(t) - KFB * self.wfb(t, s)
        return s[X] + p["k_D"] / p["L_a"] * e_f, e_f

    def mus_eff(self):
        f = self.fx
        if self.law == "aging":
            ts = max(self._tnow - self.t_att, 0.0)
            return self.p["mu_c"] + (f["mus_inf"] - self.p["mu_c"]) * (1 - math.exp(-ts / f["tau_age"]))
        return self.p["mu_s"]

    def deriv(self, t, s, mode, need=False):
        p, f = self.p, self.fx
        d = [0.0] * NS
        n = p["n"]
        i_a, e_f = self.current(t, s)
        e_pi = p["k_p"] * e_f + p["k_I"] * s[Z]
        run_int = 1.0
        if e_pi > p["V_max"]:
            e_pi = p["V_max"]
            if e_f > 0:
                run_int = 0.0
        elif e_pi < -p["V_max"]:
            e_pi = -p["V_max"]
            if e_f < 0:
                run_int = 0.0
        e_a = e_pi
        wm = s[WM]
        if "il0" in f:
            rpm = KFB * wm
            x = min(max((rpm - f["il_n1"]) / (f["il_n2"] - f["il_n1"]), 0.0), 1.0)
            ilim = f["il0"] * (1.0 - (1.0 - f["il_f"]) * x)
            over = i_a - ilim
            u = s[U]
            if u > 0 or over > 0:
                d[U] = f["kl"] * over
            ut = max(u, 0.0) + f["kpl"] * max(over, 0.0)
            e_a -= ut
            if ut > 0:
                run_int = 0.0
        d[Z] = run_int * e_f
        d[X] = (e_a - p["R_a"] * i_a - p["k_b"] * wm) / p["L_a"]
        Tm = p["k_i"] * i_a - p["B_m"] * wm
        Jm = p["J_m"]
        if "J2" in f:
            Jm += f["J2"]
            Tm -= f.get("B2", 0.0) * wm
        if "Tc" in f:
            Tf = f["Tc"] + (f["Ts"] - f["Tc"]) * math.exp(-(wm / f["ws"]) ** 2)
            Tm -= Tf * math.tanh(wm / 0.01)
        d[THM] = wm
        wl = s[WL] if self.flex else wm
        wo = wl / n
        th = s[THM] / n if not self.flex else (s[THM] - s[PHI]) / n
        Tk = -self.Tbrg * math.tanh(wo / 1e-4)
        if "U1" in f:
            Tk -= f["U1"] * math.sin(th + f["ph1u"]) + f.get("U2", 0.0) * math.sin(2 * th + f.get("ph2u", 0.0))
        if "cd" in f:
            Tk -= f["cd"] * abs(wo) ** f["ad"] * math.tanh(wo / 1e-4)
        if "Ap" in f:
            Tk -= f["Ap"] * math.sin(s[THM] / f["nr"] + f["php"])
        psi = s[PSI]
        m_v, J_v = p["m_v"], p["J_v"]
        N = m_v * G * max(math.cos(psi), 0.0)
        Tg = m_v * G * p["L"] * math.sin(psi)
        if mode == "att":
            Jk = p["J_o"] + J_v
            Tk -= Tg
            d[PSI] = wo
        else:
            Jk = p["J_o"]
            Tw = (1.0 if mode == "sl+" else -1.0) * p["mu_c"] * N * p["R"]
            Tk -= Tw
            d[PSI] = s[WB]
            d[WB] = (Tw - Tg) / J_v
        if not self.flex:
            dwm = (Tm + Tk / n) / (Jm + Jk / n ** 2)
            d[WM] = dwm
            dwo = dwm / n
        else:
            JL = f.get("Jg", 0.0) + Jk / n ** 2
            phi = s[PHI]
            dphi = wm - s[WL]
            if "kc1" in f:
                a = abs(phi)
                if a <= f["ph1"]:
                    Tsp = f["kc1"] * phi
                else:
                    Tsp = math.copysign(f["kc1"] * f["ph1"] + f["kc2"] * (a - f["ph1"]), phi)
                Tc = Tsp + f["cc"] * dphi
            else:
                # phi: twist of the pinion relative to the girth gear; driving flank at phi>=0,
                # back flank at phi<=-gap
                gap = f["gap"]
                if phi >= 0:
                    Tc = max(f["kt"] * phi + f["ct"] * dphi, 0.0)
                elif phi <= -gap:
                    Tc = min(f["kt"] * (phi + gap) + f["ct"] * dphi, 0.0)
                else:
                    Tc = 0.0
            d[PHI] = dphi
            d[WM] = (Tm - Tc) / Jm
            d[WL] = (Tc + Tk / n) / JL
            dwo = d[WL] / n
        if mode == "att":
            d[WB] = dwo
        if "tau_f" in f:
            d[YF] = (wm - s[YF]) / f["tau_f"]
        if need:
            return J_v * dwo + Tg, N * p["R"], psi
        return d

    # guard >= 0 while mode valid
    def guard(self, t, s, mode):
        p = self.p
        if mode == "att":
            hold, NR, psi = self.deriv(t, s, "att", need=True)
            if self.law == "paper":
                g1 = p["mu_s"] * math.cos(psi) - abs(math.sin(psi))
                g2 = (p["mu_c"] * NR - abs(hold)) / (p["m_v"] * G * p["R"])
                return max(g1, g2)
            return (self.mus_eff() * NR - abs(hold)) / (p["m_v"] * G * p["R"])
        wo = (s[WL] if self.flex else s[WM]) / p["n"]
        v = wo - s[WB]
        return v if mode == "sl+" else -v

    def rk4(self, t, s, h):
        m = self.mode
        k1 = self.deriv(t, s, m)
        s2 = [a + 0.5 * h * b for a, b in zip(s, k1)]
        k2 = self.deriv(t + 0.5 * h, s2, m)
        s3 = [a + 0.5 * h * b for a, b in zip(s, k2)]
        k3 = self.deriv(t + 0.5 * h, s3, m)
        s4 = [a + h * b for a, b in zip(s, k3)]
        k4 = self.deriv(t + h, s4, m)
        return [a + h / 6.0 * (b + 2 * c + 2 * e + g) for a, b, c, e, g in zip(s, k1, k2, k3, k4)]

    def switch(self, t, s):
        p = self.p
        wo = (s[WL] if self.flex else s[WM]) / p["n"]
        if self.mode == "att":
            hold, _, _ = self.deriv(t, s, "att", need=True)
            self.mode = "sl+" if hold > 0 else "sl-"
            s[WB] = wo
        else:
            s[WB] = wo
            self.t_att = t
            if self.guard(t, s, "att") >= 0:
                self.mode = "att"
            else:
                self.mode = "sl-" if self.mode == "sl+" else "sl+"
        self.events.append((t, self.mode))

    def run(self, t_end, dt=2.5e-4, store_every=4):
        """Integrate the start-up from rest (burden attached at psi = 0, zero current).

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
            ``t`` [s], ``i`` armature current [A], ``w`` fed-back (and logged) speed [rpm], ``r`` speed
            reference [rpm], ``psi`` burden angle [rad], ``wm`` motor speed [rpm] (numpy arrays) and
            ``events``, the burden mode switches as ``(t, new mode)``.
        """
        f = self.fx
        s = [0.0] * NS
        if "gap" in f:
            s[PHI] = -f["gap"] * f["gap0"]
            s[THM] = s[PHI]  # kiln angle 0 at start
        self.mode = "att"
        self.t_att = 0.0
        self.events = []
        nsteps = int(round(t_end / dt))
        if "Tw" in f:
            self.hist_t = np.arange(nsteps + 2) * dt
            self.hist_th = np.zeros(nsteps + 2)
        t = 0.0
        self._tnow = 0.0
        out = {k: [] for k in ("t", "i", "w", "r", "psi", "wm")}
        for k in range(nsteps + 1):
            self._tnow = t
            if "Tw" in f:
                self.hist_th[k] = s[THM]
            if k % store_every == 0:
                i_a, _ = self.current(t, s)
                out["t"].append(t)
                out["i"].append(i_a)
                out["w"].append(KFB * self.wfb(t, s))
                out["r"].append(self.ref(t))
                out["psi"].append(s[PSI])
                out["wm"].append(KFB * s[WM])
            if k == nsteps:
                break
            g0 = self.guard(t, s, self.mode)
            if g0 < 0:  # mode already invalid at the step start (left by a switch): switch now
                self.switch(t, s)
                g0 = self.guard(t, s, self.mode)
            s1 = self.rk4(t, s, dt)
            g1 = self.guard(t + dt, s1, self.mode)
            if g0 >= 0 and g1 < 0:
                lo, hi = 0.0, dt
                for _ in range(30):
                    mid = 0.5 * (lo + hi)
                    if self.guard(t + mid, self.rk4(t, s, mid), self.mode) >= 0:
                        lo = mid
                    else:
                        hi = mid
                se = self.rk4(t, s, hi)
                self.switch(t + hi, se)
                rest = dt - hi
                s1 = self.rk4(t + hi, se, rest) if rest > 0 else se
            s = s1
            t = (k + 1) * dt
        o = {k: np.array(v) for k, v in out.items()}
        o["events"] = list(self.events)
        return o


def simulate(p, fx=None, t_end=41.0, dt=2.5e-4):
    """Simulate a start-up of the plant.

    Parameters
    ----------
    p : dict
        Parameters (:data:`BASE`, possibly changed).
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
    return Plant(p, fx).run(t_end, dt)
