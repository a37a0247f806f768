"""Red team 21's independent plant of the rotary-kiln drive (van Dyk & Pretorius 1994), kiln K-21.

Who and from what
-----------------
Written by a red-team helper (red team 21) from the paper's equations (eqs. 1-21) and the reading notes
``NOTES.md``, with the conventions docs/model_reference.md states (its text, not kilnctl's code), apart from
kilnctl: this module imports the standard library, numpy and scipy (``solve_ivp``) only, and nothing of
kilnctl's model, simulator or synthetic generator.  It is kept here as the helper wrote it (originally
``/work/runs/red21/plant.py``, with the nominal values of ``kiln21.py``): the equations, numbers, integration
and their order are unchanged, so records written with it are the red team's byte for byte
(:mod:`benchmarks.red21_records`, which holds the record definitions, nuisance, logger, noise and truth).
Only this docstring head, :data:`K21` (``kiln21.py``'s values, folded in), :func:`default_params` (a copy of
it), the docstrings of :class:`Plant`, :meth:`Plant.simulate` and :meth:`Plant.sample` and blank lines
between the imports were added.

The kiln K-21 (:data:`K21`)
---------------------------
n 1450, set speed 900 rpm (ramp 110 rpm/s from 1 s), J_m 30 kg m^2, k_i = k_b 7.2, V_max 820 V, I_max 1250 A;
J_o 1.05e7, J_v 2.9e6 kg m^2, m_v 7.6e5 kg, L 1.62 m, R 2.55 m, mu_c 0.36, mu_s 0.46; about 572 A running
(peak 581 A).  Its regime: **mu_c R / L = 0.36 x 2.55 / 1.62 = 0.567 > mu_s 0.46**, so under the paper's
(printed) friction law the burden breaks away at tan psi = mu_s (24.7 deg, 11.85 s), is held with the shell by
kinetic friction (the Filippov held mode) until tan psi = mu_c R / L (29.5 deg, 13.15 s) and then slides
steadily: three burden events in the whole run, no stick-slip at the set speed.  Under the torque law
(breakaway at tan psi = mu_s R / L, 35.9 deg) the same kiln cycles: breakaway at 14.86 s, then a stick-slip
cycle every 5.10 s (11 events in 41 s), which record P1 builds on (with a Stribeck kinetic law).

How it was checked against kilnctl (the red team's, with no effect)
-------------------------------------------------------------------
Noise-free, effect-free, nuisance-free records of :data:`K21` (1 s at rest, 40 s after the ramp start)
through ``kilnctl compare`` (the red team's ``base_check.md``): under the paper law current rms residual
0.0031 A (bias -0.00011 A, against about 572 A running) and speed 3.0e-5 rpm, at 50 Hz and 100 Hz alike;
under the torque law 0.040 A and 6.9e-4 rpm at 50 Hz, 0.048 A and 1.0e-3 rpm at 100 Hz (one-sample spikes of
up to 1 A at the stick-slip falls, where the two integrators place a breakaway about a millisecond apart).
Peak current 581.4 A (paper) and 680.0 A (torque).

The helper's own description
----------------------------
Independent rotary-kiln start-up plant for red team 21 (kiln "K-21").

Written from van Dyk & Pretorius (1994), eqs. 1-21, and the reading notes
(NOTES.md); the conventions that the comparison with kilnctl fixes are those
stated in kilnctl's docs/model_reference.md (not its code):

* speed loop in rpm:  e_f = e_v - K*omega_fb,  K = 60/(2 pi)
  e_pi = k_p e_f + k_I z,  dz/dt = e_f
* armature (eq. 21, derivative through L_a):
  i_a = x_a + (k_D/L_a) e_f,   L_a dx_a/dt = e_a - R_a i_a - k_b Phi omega_m
* motor (eq. 4): J_m domega_m/dt = k_i Phi i_a - B_m omega_m - T_l
* burden angle psi from bottom dead centre (paper's Phi = pi - psi),
  J_v domega_b/dt = -m g L sin psi + T_w, wall torque T_w, -T_w on the kiln,
  kinetic T_w = +-mu N R against the relative velocity v_rel = omega_o - omega_b,
  N = m g max(cos psi, 0)
* breakaway: 'paper' (forces, tan psi > mu_s, eq. 3 as printed), 'torque'
  (holding torque > mu_s N R) or 'stribeck' (torque breakaway, kinetic friction
  falling from mu_st to mu_c with the sliding speed);
  a zero-time stick/slip cycle is resolved into the Filippov mode 'held'
  (burden with the wall, held by kinetic friction, slips when the holding
  torque exceeds mu_c N R)
* bearing friction eq. 17, 2 mu_brg (P/2) cos30 (l+k)/2, regularised with
  tanh(omega_o / 1e-4 rad/s)

The integrator is scipy's DOP853 with events (every mode switch located by root
finding); the stick-slip state machine, the drive-train variants and the effects
are this file's own.  Effects (all optional, dict `fx`):

  second_rotor_clutch  {'J2','T_slip'}: a second motor behind a torque-limiting
                       friction (slip) coupling on the motor shaft
  three_mass           {'k1','c1','J_g','k2','c2'}: motor - elastic coupling -
                       gearbox inertia (motor speed) - compliant pinion shaft and
                       mesh (kiln axis) - kiln
  dual_pinion          {'J_m2','kA','cA','kB','cB'}: the second (idle) motor on
                       its own pinion; each pinion train a spring-damper at the
                       kiln axis
  backlash_impact      {'dx','e','v_lock'}: girth-gear backlash with rigid teeth,
                       Newton restitution e at each impact, rigid mesh once the
                       rebound is below v_lock
  lag3                 {'tau'}: three equal first-order lags in the speed feedback
                       (tacho RC, drive input filter, A/D anti-alias), logged too
  thermal_bow          {'T0','phi','theta_r'}: once-per-turn torque of a hot
                       shell's bow that relaxes as the kiln turns
                       T0 exp(-theta_o/theta_r) sin(theta_o + phi)
  maxwell_drag         {'B','tau'}: drag dT/dt = (B omega_o - T)/tau (viscoelastic
                       seal / grease film), on the kiln
  dahl_motor_friction  {'Tc','sigma'}: Dahl friction on the motor shaft
  i2t_limit            {'I_hi','I_lo','I_n','E1','E2','k_l'}: overload current
                       limit folding back from I_hi to I_lo as the I^2t budget is
                       spent; proportional limiter of k_l V/A, speed integrator
                       frozen while limiting
  field_buildup        {'a','tau'}: flux Phi(t) = 1 - a exp(-(t-t0)/tau)
                       (field economy at standstill, restored at the start)
  supply_sag           {'t_on','t_off','V_sag','T_aw'}: converter ceiling V_max
                       drops to V_sag; back-calculation anti-windup T_aw
"""
from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

KFB = 60.0 / (2.0 * math.pi)
W_BRG = 1e-4          # rad/s, tanh regularisation of the bearing friction
V_REL = 0.01          # rad/s, guard scale of the relative velocity

K21 = dict(
    # [motor]
    R_a=0.028, L_a=1.1e-3, k_i=7.2, k_b=7.2, J_m=30.0, B_m=0.02,
    # [controller]
    k_p=2.0, k_I=6.0, k_D=0.04,
    # [drive]
    omega_ref=900.0, ramp_rate=110.0, V_max=820.0, I_max=1250.0,
    # [kiln]
    J_o=1.05e7, J_v=2.9e6, m_v=760e3, L=1.62, R=2.55, mu_c=0.36, mu_s=0.46,
    mu_brg=0.001, P=2.3e7, l_brg=0.82, k_brg=0.61, psi_0=0.0, g=9.81,
    # [gear]
    n=1450.0, R_o=4.6, R_p=0.6,
)
"""Kiln K-21: nominal values (the setup TOML states these; the helper's ``kiln21.py``).  SI; the drive's
speeds in rpm."""


def default_params():
    """The kiln K-21's nominal parameters: a copy of :data:`K21`.

    Returns
    -------
    dict
        Motor (``R_a``, ``L_a``, ``k_i``, ``k_b``, ``J_m``, ``B_m``), controller (``k_p``, ``k_I``, ``k_D``),
        drive (``omega_ref``, ``ramp_rate`` [rpm, rpm/s], ``V_max``, ``I_max``), kiln (``J_o``, ``J_v``,
        ``m_v``, ``L``, ``R``, ``mu_c``, ``mu_s``, ``mu_brg``, ``P``, ``l_brg``, ``k_brg``, ``psi_0``, ``g``)
        and gear (``n``, ``R_o``, ``R_p``).  The friction law is :class:`Plant`'s ``law`` (paper by
        default), not a parameter; the ramp's start is its ``t0``.
    """
    return dict(K21)


def bearing_torque(p):
    """eq. 17: T = 2 mu_brg (P/2) cos30 (l + k)/2."""
    return 2.0 * p["mu_brg"] * (p["P"] / 2.0) * math.cos(math.radians(30.0)) * (p["l_brg"] + p["k_brg"]) / 2.0


class SimulationError(RuntimeError):
    pass


class Plant:
    """The plant: motor, speed loop, drive train, kiln and burden, with the effects ``fx``.

    Parameters
    ----------
    p : dict
        Parameters (:data:`K21`, possibly changed; ``mu_st`` and ``v_s`` too for the ``stribeck`` law).
    law : {'paper', 'torque', 'stribeck'}, default 'paper'
        The burden's breakaway law (see the module docstring).
    fx : dict, optional
        Effects by name (the module docstring's list), each a dict of its values; none by default.
    t0 : float, default 1.0
        Start of the ramp [s]; the plant is at rest before it.
    reference : callable, optional
        Speed reference [rpm] of time, instead of the ramp to ``omega_ref``.
    """

    def __init__(self, p: dict, law: str = "paper", fx: dict | None = None,
                 t0: float = 1.0, reference=None):
        self.p = dict(p)
        self.law = law
        self.fx = dict(fx or {})
        self.t0 = t0
        self.T_brg = bearing_torque(self.p)
        self.reference = reference            # None: ramp_rate/omega_ref ramp
        self.drivetrain = "rigid"
        for k in ("three_mass", "dual_pinion", "backlash_impact"):
            if k in self.fx:
                self.drivetrain = k
        names = ["z", "xa", "wm", "wo", "tho", "wb", "psi"]
        if "lag3" in self.fx:
            names += ["y1", "y2", "y3"]
        if "second_rotor_clutch" in self.fx:
            names += ["w2"]
        if self.drivetrain == "three_mass":
            names += ["ph1", "wg", "ph2"]
        if self.drivetrain == "dual_pinion":
            names += ["phA", "wm2", "phB"]
        if self.drivetrain == "backlash_impact":
            names += ["s"]
        if "maxwell_drag" in self.fx:
            names += ["Td"]
        if "dahl_motor_friction" in self.fx:
            names += ["Fd"]
        if "i2t_limit" in self.fx:
            names += ["E"]
        self.names = names
        self.ix = {n: i for i, n in enumerate(names)}
        scale = {"z": 10.0, "xa": 100.0, "wm": 10.0, "wo": 0.01, "tho": 0.1, "wb": 0.01,
                 "psi": 0.1, "y1": 10.0, "y2": 10.0, "y3": 10.0, "w2": 10.0, "ph1": 1e-3,
                 "wg": 10.0, "ph2": 1e-5, "phA": 1e-5, "wm2": 10.0, "phB": 1e-5, "s": 0.1,
                 "Td": 1e4, "Fd": 10.0, "E": 0.1}
        self.atol = np.array([scale[n] for n in names]) * 1e-9
        self.events_log = []

    # ------------------------------------------------------------------ inputs
    def ref_rpm(self, t):
        if self.reference is not None:
            return float(self.reference(t))
        p = self.p
        if t <= self.t0:
            return 0.0
        return min(p["ramp_rate"] * (t - self.t0), p["omega_ref"])

    def breakpoints(self):
        p = self.p
        bps = [self.t0 + p["omega_ref"] / p["ramp_rate"]] if self.reference is None else list(getattr(self.reference, "knots", []))
        if "supply_sag" in self.fx:
            bps += [self.fx["supply_sag"]["t_on"], self.fx["supply_sag"]["t_off"]]
        return sorted(b for b in bps if b > self.t0)

    def flux(self, t):
        f = self.fx.get("field_buildup")
        if f is None:
            return 1.0
        return 1.0 - f["a"] * math.exp(-max(t - self.t0, 0.0) / f["tau"])

    def v_ceiling(self, t):
        s = self.fx.get("supply_sag")
        if s is not None and s["t_on"] <= t < s["t_off"]:
            return s["V_sag"]
        return self.p["V_max"]

    def i_limit(self, E):
        c = self.fx["i2t_limit"]
        x = min(max((E - c["E1"]) / (c["E2"] - c["E1"]), 0.0), 1.0)
        x = x * x * (3.0 - 2.0 * x)
        return c["I_hi"] - (c["I_hi"] - c["I_lo"]) * x

    # ------------------------------------------------------------- dynamics
    def kinetic_mu(self, vrel):
        p = self.p
        if self.law == "stribeck":
            return p["mu_c"] + (p["mu_st"] - p["mu_c"]) * math.exp(-(vrel / p["v_s"]) ** 2)
        return p["mu_c"]

    def derived(self, t, y, m):
        """Every algebraic quantity of the plant in modes m at (t, y)."""
        p, ix, fx = self.p, self.ix, self.fx
        d = {}
        wm, wo = y[ix["wm"]], y[ix["wo"]]
        wb, psi, tho = y[ix["wb"]], y[ix["psi"]], y[ix["tho"]]
        w_fb = y[ix["y3"]] if "lag3" in fx else wm
        ev = self.ref_rpm(t)
        ef = ev - KFB * w_fb
        ia = y[ix["xa"]] + p["k_D"] / p["L_a"] * ef
        epi = p["k_p"] * ef + p["k_I"] * y[ix["z"]]
        Vc = self.v_ceiling(t)
        dz = ef
        if m["volt"] == "upper":
            ea = Vc
        else:
            ea = epi
        if "supply_sag" in fx:
            # back-calculation anti-windup of the plant's own converter
            dz = ef - (epi - ea) / (p["k_I"] * fx["supply_sag"]["T_aw"])
        elif m["volt"] == "upper":
            dz = 0.0
        if "i2t_limit" in fx:
            Ilim = self.i_limit(y[ix["E"]])
            d["Ilim"] = Ilim
            if m["ilim"] == "limit":
                ea = ea - fx["i2t_limit"]["k_l"] * (ia - Ilim)
                dz = 0.0
        phi = self.flux(t)
        d.update(ev=ev, ef=ef, ia=ia, epi=epi, ea=ea, dz=dz, phi=phi, w_fb=w_fb, Vc=Vc)
        # motor-side torque
        Tm = p["k_i"] * phi * ia - p["B_m"] * wm
        if "dahl_motor_friction" in fx:
            Tm -= y[ix["Fd"]]
        Jms = p["J_m"]
        if "second_rotor_clutch" in fx:
            c = fx["second_rotor_clutch"]
            if m["clutch"] == "locked":
                Jms += c["J2"]
            else:
                sgn = 1.0 if wm - y[ix["w2"]] >= 0 else -1.0
                Tm -= c["T_slip"] * sgn
                d["a2"] = c["T_slip"] * sgn / c["J2"]
        # kiln loads
        TK = self.T_brg * math.tanh(wo / W_BRG)
        if "thermal_bow" in fx:
            b = fx["thermal_bow"]
            TK += b["T0"] * math.exp(-tho / b["theta_r"]) * math.sin(tho + b["phi"])
        if "maxwell_drag" in fx:
            TK += y[ix["Td"]]
        mg = p["m_v"] * p["g"]
        N = mg * max(math.cos(psi), 0.0)
        grav = mg * p["L"] * math.sin(psi)
        linked = m["burden"] in ("stick", "held")
        if linked:
            Jk = p["J_o"] + p["J_v"]
            Tb = grav
        else:
            vrel = wo - wb
            mu = self.kinetic_mu(vrel)
            Tw = mu * N * p["R"] * (1.0 if m["burden"] == "slip_pos" else -1.0)
            Jk = p["J_o"]
            Tb = Tw
            d["Tw"] = Tw
        n = p["n"]
        dt_ = self.drivetrain
        if dt_ == "rigid" or (dt_ == "backlash_impact" and m["gap"] == "contact"):
            am = (Tm - (TK + Tb) / n) / (Jms + Jk / n ** 2)
            ao = am / n
            if dt_ == "backlash_impact":
                # tooth force (as torque at the kiln) transmitted through the mesh
                d["Tlink"] = Jk * ao + TK + Tb
        elif dt_ == "backlash_impact":
            am = Tm / Jms
            ao = -(TK + Tb) / Jk
        elif dt_ == "three_mass":
            c = fx["three_mass"]
            T1 = c["k1"] * y[ix["ph1"]] + c["c1"] * (wm - y[ix["wg"]])
            T2 = c["k2"] * y[ix["ph2"]] + c["c2"] * (y[ix["wg"]] / n - wo)
            am = (Tm - T1) / Jms
            d["ag"] = (T1 - T2 / n) / c["J_g"]
            ao = (T2 - TK - Tb) / Jk
            d["T1"], d["T2"] = T1, T2
        elif dt_ == "dual_pinion":
            c = fx["dual_pinion"]
            TA = c["kA"] * y[ix["phA"]] + c["cA"] * (wm / n - wo)
            TB = c["kB"] * y[ix["phB"]] + c["cB"] * (y[ix["wm2"]] / n - wo)
            am = (Tm - TA / n) / Jms
            d["am2"] = (-p["B_m"] * y[ix["wm2"]] - TB / n) / c["J_m2"]
            ao = (TA + TB - TK - Tb) / Jk
            d["TA"], d["TB"] = TA, TB
        else:
            raise ValueError(dt_)
        d.update(Tm=Tm, TK=TK, am=am, ao=ao, N=N, grav=grav, Jms=Jms)
        if linked:
            d["Tneed"] = p["J_v"] * ao + grav
            d["ab"] = ao
        else:
            d["ab"] = (-grav + d["Tw"]) / p["J_v"]
        if "second_rotor_clutch" in fx and m["clutch"] == "locked":
            d["a2"] = am
            d["Tclutch"] = fx["second_rotor_clutch"]["J2"] * am
        return d

    def rhs(self, t, y, m):
        ix, fx = self.ix, self.fx
        d = self.derived(t, y, m)
        p = self.p
        f = np.zeros_like(y)
        f[ix["z"]] = d["dz"]
        f[ix["xa"]] = (d["ea"] - p["R_a"] * d["ia"] - p["k_b"] * d["phi"] * y[ix["wm"]]) / p["L_a"]
        f[ix["wm"]] = d["am"]
        f[ix["wo"]] = d["ao"]
        f[ix["tho"]] = y[ix["wo"]]
        f[ix["wb"]] = d["ab"]
        f[ix["psi"]] = y[ix["wo"]] if m["burden"] in ("stick", "held") else y[ix["wb"]]
        if "lag3" in fx:
            tau = fx["lag3"]["tau"]
            f[ix["y1"]] = (y[ix["wm"]] - y[ix["y1"]]) / tau
            f[ix["y2"]] = (y[ix["y1"]] - y[ix["y2"]]) / tau
            f[ix["y3"]] = (y[ix["y2"]] - y[ix["y3"]]) / tau
        if "second_rotor_clutch" in fx:
            f[ix["w2"]] = d["a2"]
        if self.drivetrain == "three_mass":
            f[ix["ph1"]] = y[ix["wm"]] - y[ix["wg"]]
            f[ix["wg"]] = d["ag"]
            f[ix["ph2"]] = y[ix["wg"]] / p["n"] - y[ix["wo"]]
        if self.drivetrain == "dual_pinion":
            f[ix["phA"]] = y[ix["wm"]] / p["n"] - y[ix["wo"]]
            f[ix["wm2"]] = d["am2"]
            f[ix["phB"]] = y[ix["wm2"]] / p["n"] - y[ix["wo"]]
        if self.drivetrain == "backlash_impact":
            f[ix["s"]] = 0.0 if m["gap"] == "contact" else y[ix["wm"]] - p["n"] * y[ix["wo"]]
        if "maxwell_drag" in fx:
            c = fx["maxwell_drag"]
            f[ix["Td"]] = (c["B"] * y[ix["wo"]] - y[ix["Td"]]) / c["tau"]
        if "dahl_motor_friction" in fx:
            c = fx["dahl_motor_friction"]
            w = y[ix["wm"]]
            f[ix["Fd"]] = c["sigma"] * (w - abs(w) * y[ix["Fd"]] / c["Tc"])
        if "i2t_limit" in fx:
            c = fx["i2t_limit"]
            f[ix["E"]] = max(d["ia"] ** 2 - c["I_n"] ** 2, 0.0) / c["I_n"] ** 2
        return f

    # ------------------------------------------------------------- guards
    def guards(self, m):
        """List of (name, function(t, y) -> value, direction) for modes m."""
        p, ix, fx = self.p, self.ix, self.fx
        g = []
        b = m["burden"]
        mgR = p["m_v"] * p["g"] * p["R"]
        if b == "stick":
            if self.law == "paper":
                g.append(("breakaway_pos", lambda t, y: p["mu_s"] * math.cos(y[ix["psi"]]) - math.sin(y[ix["psi"]]), -1))
                g.append(("breakaway_neg", lambda t, y: p["mu_s"] * math.cos(y[ix["psi"]]) + math.sin(y[ix["psi"]]), -1))
            else:
                def gp(t, y):
                    d = self.derived(t, y, m)
                    return (p["mu_s"] * d["N"] * p["R"] - d["Tneed"]) / mgR
                def gn(t, y):
                    d = self.derived(t, y, m)
                    return (p["mu_s"] * d["N"] * p["R"] + d["Tneed"]) / mgR
                g.append(("breakaway_pos", gp, -1))
                g.append(("breakaway_neg", gn, -1))
        elif b == "held":
            def gh(t, y):
                d = self.derived(t, y, m)
                return (self.kinetic_mu(0.0) * d["N"] * p["R"] - d["Tneed"]) / mgR
            g.append(("held_slip", gh, -1))
        elif b == "slip_pos":
            g.append(("restick", lambda t, y: (y[ix["wo"]] - y[ix["wb"]]) / V_REL, -1))
        elif b == "slip_neg":
            g.append(("restick", lambda t, y: (y[ix["wb"]] - y[ix["wo"]]) / V_REL, -1))
        if "second_rotor_clutch" in fx:
            c = fx["second_rotor_clutch"]
            if m["clutch"] == "locked":
                g.append(("clutch_slip", lambda t, y: (c["T_slip"] - abs(self.derived(t, y, m)["Tclutch"])) / c["T_slip"], -1))
            else:
                sgn0 = m["clutch_sign"]
                g.append(("clutch_lock", lambda t, y: sgn0 * (y[ix["wm"]] - y[ix["w2"]]) / V_REL, -1))
        if self.drivetrain == "backlash_impact":
            G = m["G"]
            if m["gap"] == "free":
                g.append(("impact", lambda t, y: (G - y[ix["s"]]) / G, -1))
                g.append(("back_impact", lambda t, y: y[ix["s"]] / G, -1))
            else:
                g.append(("separation", lambda t, y: self.derived(t, y, m)["Tlink"] / (mgR * p["L"] / p["R"]), -1))
        if "i2t_limit" in fx:
            if m["ilim"] == "free":
                g.append(("ilim_on", lambda t, y: (self.derived(t, y, m)["Ilim"] - self.derived(t, y, m)["ia"]) / 100.0, -1))
            else:
                g.append(("ilim_off", lambda t, y: (self.derived(t, y, m)["ia"] - self.derived(t, y, m)["Ilim"]) / 100.0, -1))
        if m["volt"] == "free":
            g.append(("volt_on", lambda t, y: (self.v_ceiling(t) - self.derived(t, y, m)["epi"]) / 100.0, -1))
        else:
            g.append(("volt_off", lambda t, y: (self.derived(t, y, m)["epi"] - self.v_ceiling(t)) / 100.0, -1))
        return g

    # ------------------------------------------------------------- switching
    def _resolve_burden(self, t, y, m):
        """Give the burden a consistent mode at (t, y) (cascade within one instant)."""
        p = self.p
        for _ in range(6):
            b = m["burden"]
            if b == "stick":
                d = self.derived(t, y, m)
                if self.law == "paper":
                    vp = p["mu_s"] * math.cos(y[self.ix["psi"]]) - math.sin(y[self.ix["psi"]])
                    vn = p["mu_s"] * math.cos(y[self.ix["psi"]]) + math.sin(y[self.ix["psi"]])
                    ok_p, ok_n = vp > -1e-12, vn > -1e-12
                else:
                    cap = p["mu_s"] * d["N"] * p["R"]
                    ok_p = d["Tneed"] <= cap * (1 + 1e-12)
                    ok_n = -d["Tneed"] <= cap * (1 + 1e-12)
                if ok_p and ok_n:
                    return m
                kin = self.kinetic_mu(0.0) * d["N"] * p["R"]
                if not ok_p:
                    if d["Tneed"] > kin:
                        m["burden"] = "slip_pos"
                    else:
                        m["burden"] = "held"       # zero-time stick/slip cycle: Filippov
                        self._log(t, "sliding_mode")
                        return m
                else:
                    if -d["Tneed"] > kin:
                        m["burden"] = "slip_neg"
                    else:
                        m["burden"] = "held"
                        self._log(t, "sliding_mode")
                        return m
                y[self.ix["wb"]] = y[self.ix["wo"]]
                return m
            if b == "held":
                d = self.derived(t, y, m)
                kin = self.kinetic_mu(0.0) * d["N"] * p["R"]
                if d["Tneed"] > kin * (1 + 1e-12):
                    m["burden"] = "slip_pos"
                    y[self.ix["wb"]] = y[self.ix["wo"]]
                return m
            return m
        return m

    def _log(self, t, kind):
        self.events_log.append((float(t), kind))

    def _switch(self, name, t, y, m):
        ix, p = self.ix, self.p
        self._log(t, name)
        if name in ("breakaway_pos", "breakaway_neg", "held_slip"):
            d = self.derived(t, y, m)
            kin = self.kinetic_mu(0.0) * d["N"] * p["R"]
            if name == "breakaway_neg":
                m["burden"] = "slip_neg" if -d["Tneed"] > kin else "held"
            elif name == "held_slip":
                m["burden"] = "slip_pos"
            else:
                m["burden"] = "slip_pos" if d["Tneed"] > kin else "held"
                if m["burden"] == "held":
                    self._log(t, "sliding_mode")
            y[ix["wb"]] = y[ix["wo"]]
        elif name == "restick":
            # plastic catch: momentum of kiln group and burden conserved (v_rel = 0 here)
            J1 = p["J_o"] + (p["n"] ** 2 * p["J_m"] if self.drivetrain == "rigid" else 0.0)
            w = (J1 * y[ix["wo"]] + p["J_v"] * y[ix["wb"]]) / (J1 + p["J_v"])
            if self.drivetrain == "rigid":
                y[ix["wm"]] = w * p["n"]
            y[ix["wo"]] = w
            y[ix["wb"]] = w
            m["burden"] = "stick"
            m = self._resolve_burden(t, y, m)
        elif name == "clutch_slip":
            d = self.derived(t, y, m)
            m["clutch"] = "slip"
            m["clutch_sign"] = 1.0 if d["Tclutch"] > 0 else -1.0
            y[ix["w2"]] = y[ix["wm"]]
        elif name == "clutch_lock":
            c = self.fx["second_rotor_clutch"]
            w = (p["J_m"] * y[ix["wm"]] + c["J2"] * y[ix["w2"]]) / (p["J_m"] + c["J2"])
            y[ix["wm"]] = w
            y[ix["w2"]] = w
            m["clutch"] = "locked"
            d = self.derived(t, y, m)
            if abs(d["Tclutch"]) > c["T_slip"]:
                m["clutch"] = "slip"
                m["clutch_sign"] = 1.0 if d["Tclutch"] > 0 else -1.0
        elif name in ("impact", "back_impact"):
            c = self.fx["backlash_impact"]
            J1 = p["J_m"]
            # impulsive: the burden's friction transmits no impulse, the shell takes it
            J2 = p["J_o"] / p["n"] ** 2
            v1, v2 = y[ix["wm"]], p["n"] * y[ix["wo"]]
            dv = v1 - v2
            e = c["e"] if abs(dv) > c["v_lock"] else 0.0
            v1n = v1 - (1 + e) * J2 * dv / (J1 + J2)
            v2n = v2 + (1 + e) * J1 * dv / (J1 + J2)
            y[ix["wm"]] = v1n
            y[ix["wo"]] = v2n / p["n"]
            m["impacts"] = m.get("impacts", 0) + 1
            if name == "impact" and e == 0.0:
                m["gap"] = "contact"
                y[ix["s"]] = m["G"]
            if m["burden"] in ("stick", "held") and abs(y[ix["wo"]] - y[ix["wb"]]) > 0:
                m["burden"] = "slip_pos" if y[ix["wo"]] > y[ix["wb"]] else "slip_neg"
        elif name == "separation":
            m["gap"] = "free"
        elif name == "ilim_on":
            m["ilim"] = "limit"
        elif name == "ilim_off":
            m["ilim"] = "free"
        elif name == "volt_on":
            m["volt"] = "upper"
        elif name == "volt_off":
            m["volt"] = "free"
        else:
            raise ValueError(name)
        return m

    # ------------------------------------------------------------- run
    def initial(self):
        y = np.zeros(len(self.names))
        m = {"burden": "stick", "volt": "free"}
        if "second_rotor_clutch" in self.fx:
            m["clutch"] = "locked"
        if self.drivetrain == "backlash_impact":
            c = self.fx["backlash_impact"]
            m["G"] = self.p["n"] * c["dx"] / self.p["R_o"]      # motor-side free travel [rad]
            m["gap"] = "free"
        if "i2t_limit" in self.fx:
            m["ilim"] = "free"
        return y, m

    def simulate(self, t_end, rtol=1e-10, max_events=20000, max_step=0.05):
        """Integrate the start-up from ``t0`` (at rest, burden sticking at psi = 0) to ``t_end``.

        Parameters
        ----------
        t_end : float
            End time [s].
        rtol : float, default 1e-10
            DOP853's relative tolerance (absolute tolerances per state, ``atol``).
        max_events : int, default 20000
            Most mode switches before :class:`SimulationError`.
        max_step : float, default 0.05
            Largest step [s].

        Returns
        -------
        Plant
            Itself, with the solution's segments (``segs``) and the mode switches (``events_log``: ``(t,
            name)``) for :meth:`sample`.
        """
        y, m = self.initial()
        t = self.t0
        segs = []            # (t_a, t_b, sol, modes)
        bps = [b for b in self.breakpoints() if b < t_end] + [t_end]
        nev = 0
        zero_time = 0
        while t < t_end - 1e-12:
            t_next = min(b for b in bps if b > t + 1e-12)
            guards = self.guards(m)
            evs = []
            for name, fn, direc in guards:
                def ev(tt, yy, fn=fn, ts=t, direc=direc):
                    v = fn(tt, yy)
                    if tt <= ts or (tt - ts < 1e-9 and abs(v) < 1e-10):
                        # at the segment's start the guard has just been switched on: a
                        # zero-length first step must not read as a crossing
                        return -direc * (abs(v) + 1e-300)
                    return v
                ev.terminal = True
                ev.direction = direc
                evs.append(ev)
            mm = dict(m)
            sol = solve_ivp(lambda tt, yy: self.rhs(tt, yy, mm), (t, t_next), y, method="DOP853",
                            rtol=rtol, atol=self.atol, events=evs, dense_output=True,
                            max_step=max_step)
            if sol.status == -1:
                raise SimulationError(sol.message)
            t_hit = sol.t[-1]
            segs.append((t, t_hit, sol.sol, dict(m)))
            y = sol.y[:, -1].copy()
            if sol.status == 1:
                k = next(i for i, te in enumerate(sol.t_events) if len(te))
                name = guards[k][0]
                y = sol.y_events[k][0].copy()
                t_hit = sol.t_events[k][0]
                zero_time = zero_time + 1 if t_hit - t < 1e-9 else 0
                if zero_time > 20:
                    raise SimulationError(f"event storm at t={t_hit}: {name} {m}")
                m = self._switch(name, t_hit, y, m)
                nev += 1
                if nev > max_events:
                    raise SimulationError("too many events")
            t = t_hit
        self.segs = segs
        return self

    def sample(self, ts):
        """Outputs at times ts (t < t0: plant at rest).

        Parameters
        ----------
        ts : array_like
            Times [s], increasing (after :meth:`simulate`).

        Returns
        -------
        dict
            numpy arrays: ``i_a`` armature current [A], ``speed_rpm`` fed-back (and logged) speed,
            ``speed_true_rpm`` motor speed, ``ref_rpm`` reference [rpm], ``e_a`` armature voltage [V], ``psi``
            burden angle [rad], ``v_rel`` kiln minus burden speed [rad/s], ``kiln_rpm``, ``phi`` flux [-],
            ``Ilim`` current limit [A] (0 without ``i2t_limit``).
        """
        ts = np.asarray(ts, float)
        out = {k: np.zeros(len(ts)) for k in ("i_a", "speed_rpm", "speed_true_rpm", "ref_rpm", "e_a", "psi", "v_rel", "kiln_rpm", "phi", "Ilim")}
        seg_i = 0
        for j, t in enumerate(ts):
            if t < self.t0:
                out["speed_rpm"][j] = 0.0
                if "i2t_limit" in self.fx:
                    out["Ilim"][j] = self.fx["i2t_limit"]["I_hi"]
                continue
            while seg_i + 1 < len(self.segs) and t >= self.segs[seg_i][1]:
                seg_i += 1
            ta, tb, solf, mm = self.segs[seg_i]
            y = solf(min(max(t, ta), tb))
            d = self.derived(t, y, mm)
            out["i_a"][j] = d["ia"]
            out["speed_rpm"][j] = KFB * d["w_fb"]
            out["speed_true_rpm"][j] = KFB * y[self.ix["wm"]]
            out["ref_rpm"][j] = d["ev"]
            out["e_a"][j] = d["ea"]
            out["psi"][j] = y[self.ix["psi"]]
            out["v_rel"][j] = y[self.ix["wo"]] - y[self.ix["wb"]]
            out["kiln_rpm"][j] = KFB * y[self.ix["wo"]]
            out["phi"][j] = d["phi"]
            out["Ilim"][j] = d.get("Ilim", 0.0)
        return out
