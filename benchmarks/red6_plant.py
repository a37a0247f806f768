"""Red team 6's independent plant of the rotary-kiln drive (van Dyk & Pretorius 1994).

Who and from what
-----------------
Written by a red-team helper (red team 6, 2026-11-27) from the paper's equations (eqs. 1-21 and
26-31) and its Table 1, apart from kilnctl: this module imports numpy, scipy and the standard library
only, and nothing of kilnctl's model, simulator or synthetic generator (nor ``benchmarks/baselines.py``
or ``benchmarks/foreign_records.py``).  It is kept here as the helper wrote it (originally
``/work/runs/red6/plant.py``); only this docstring, the functions' docstrings and comments were
tidied, the equations and numbers are unchanged, so records written with it are the red team's.
The records themselves and their truth are in :mod:`benchmarks.red6_records`.

Readings of the paper's choices (the helper's, stated once)
-----------------------------------------------------------
* Speed loop in rpm: ``e_f = e_v - K w_fb``, ``K = 60/(2 pi)``; ``e_a = k_p e_f + k_I int e_f``;
  eq. 21 line 2 read as the derivative action ``k_D de_f/dt`` in the armature voltage, i.e.
  ``L_a di/dt = e_a + k_D de_f/dt - R_a i - k_b w_m``.  State ``x = i - (k_D/L_a) e_f``.
  ``k_b = k_i = 4.6`` SI.  Speed reference: a ramp at 74 rpm/s to 500 rpm.
* Burden: rigid disc, angle psi from bottom dead centre, gravity torque ``-m g L sin psi``,
  normal force ``N = m g cos psi``, wall friction arm R (eqs. 1-3, 6, 16).  The friction torque
  opposes the relative velocity (eq. 16 has no sign).  The stick condition of eq. 3
  (``tan psi <= mu_s``, forces) is, at its own breakaway angle, weaker than the kinetic
  friction torque ``mu_c N R``; the burden then cannot slip (it would re-stick at once) and
  is carried along by kinetic friction until the torque needed to carry it exceeds
  ``mu_c N R``.  So the ``'paper'`` law here: the burden moves with the wall while
  ``tan psi <= mu_s`` OR the torque needed ``<= mu_c N R``.  ``'torque'`` law: while the torque
  needed ``<= mu_s N R``.  Optional Stribeck: kinetic coefficient
  ``mu_c + (mu_s - mu_c) exp(-|v_rel|/v_st)``.
* Bearing friction eq. 17 on the kiln, its sign regularised as ``tanh(w_o/1e-3)``.
* Integration: scipy ``solve_ivp`` (RK45, rtol 1e-7, atol 1e-9, max_step 2 ms) between the
  burden's mode switches, which are located by terminal events (stick -> slip when the needed
  torque reaches the static limit; slip -> stick when ``v_rel = 0`` and the static limit can
  hold the burden).  With a sampled speed measurement (``encoder``) the integration is split at
  every controller tick (zero-order hold).

Effects (all off by default, in this plant's own forms; see :data:`BASE`): a rigid extra
motor-side inertia ``J_m2`` [kg m^2]; a kiln drag quadratic in speed ``drag_quad`` [N m s^2/rad^2];
a Stribeck motor-shaft friction ``mot_fric``; a kiln unbalance of several harmonics ``unb``; a
drive train at the kiln axis (``spring``: hardening stiffness, or a backlash with soft Hertzian,
Hunt-Crossley damped contact); an encoder speed measurement ``encoder`` (planned, not used in the
records: it made this controller reading's speed loop unstable); a burden friction change
``mu_c_change`` (outside kilnctl's catalogue).

How it was checked against kilnctl (with no effect)
---------------------------------------------------
The helper wrote noise-free records whose true values equal the setup (Table 1, gains
2 / 5 / 0.01) and ran them through ``kilnctl compare``: current rms difference 0.067 A under
the paper law and 0.078 A under the torque law (stick-slip, 8 switches), current and speed fit
100.0 % in both; with the records' noise the effect-free record fits 97.9 %.  The helper's
reading of the paper therefore gives the same base model as kilnctl
(``/work/runs/red6/REPORT.md``, "The plant and how it was checked";
``tests/test_red6_records.py`` repeats the check on a regenerated record).
"""
from __future__ import annotations

import math
import numpy as np
from scipy.integrate import solve_ivp

G = 9.81  # m/s^2
#: The plant's values (SI unless named): Table 1 of the paper, the drive's gains k_p [V/rpm],
#: k_I [V/(rpm s)], k_D [V s/rpm], the reference ``ramp`` [rpm/s] to ``w_ref`` [rpm], the friction
#: ``law`` ('paper' or 'torque') with an optional Stribeck speed ``v_st`` [rad/s], and the effects
#: (all off by default).  :class:`Plant` takes any of them as keyword overrides.
BASE = dict(
    R_a=0.00961, L_a=0.57e-3, k_i=4.6, k_b=4.6, J_m=21.5, B_m=0.005,
    K=60 / (2 * math.pi), k_p=2.0, k_I=5.0, k_D=0.01,
    ramp=74.0, w_ref=500.0,
    J_o=6.978e6, J_v=1.678e6, m_v=580e3, L=1.353, R=2.17, mu_c=0.4, mu_s=0.51,
    n=1076.5, mu_brg=0.001, P=16.512e6, l_brg=0.7155, k_brg=0.5475,
    law="paper", v_st=None,
    # effects (all off by default)
    J_m2=0.0,                      # rigid extra motor-side inertia
    drag_quad=0.0,                 # kiln drag c2*w_o*|w_o| [N m s^2/rad^2]
    mot_fric=None,                 # dict(Tc, Ts [N m], ws, eps [rad/s]): Stribeck friction on motor shaft
    unb=None,                      # list of (T [N m], harmonic, phase [rad]): torque -T sin(h*theta_o + phase) on kiln
    spring=None,                   # dict(kind='hardening'|'hertz_backlash', ...) drivetrain at kiln axis
    encoder=None,                  # dict(counts [per rev], window [s], Ts [s]): speed from encoder counts
    mu_c_change=None,              # (t_start [s], t_end [s], mu_c_new): burden friction change (charge shift)
)


def T_brg(p):
    """Bearing friction torque of eq. 17 [N m] on the kiln axis.

    Parameters
    ----------
    p : dict
        Plant values (:data:`BASE`): ``mu_brg``, ``P`` [N], ``l_brg``, ``k_brg`` [m].

    Returns
    -------
    float
        ``2 mu_brg (P/2) cos 30 deg (l_brg + k_brg)/2`` [N m].
    """
    return 2 * p["mu_brg"] * p["P"] / 2 * math.cos(math.radians(30)) * (p["l_brg"] + p["k_brg"]) / 2


class Plant:
    """The kiln drive with its burden, controller and optional effects.

    Parameters
    ----------
    **kw
        Overrides of :data:`BASE` (true plant values and effects), e.g. ``Plant(m_v=597e3,
        drag_quad=8.45e7)``.

    Attributes
    ----------
    p : dict
        The plant's values.
    Tb : float
        Bearing friction torque [N m].
    nswitch : int
        Burden mode switches of the last :meth:`simulate`.
    T, Y : ndarray
        Solver times [s] and states ``[z, x, th_m, w_m, th_o, w_o, psi, w_b]`` of the last run.
    """
    def __init__(self, **kw):
        self.p = dict(BASE)
        self.p.update(kw)
        p = self.p
        self.Tb = T_brg(p)
        self.rigid = p["spring"] is None
        self.t_ramp_end = p["w_ref"] / p["ramp"]

    # ---- references and friction laws -------------------------------------------
    def e_v(self, t):
        """Speed reference [rpm] at time t [s] after the start."""
        return min(self.p["ramp"] * max(t, 0.0), self.p["w_ref"])

    def de_v(self, t):
        """Rate of the speed reference [rpm/s] at time t [s]."""
        return self.p["ramp"] if 0.0 <= t < self.t_ramp_end else 0.0

    def mu_c(self, t):
        """Kinetic burden friction coefficient at time t [s] (``mu_c_change``: a smooth S between its times)."""
        p = self.p
        if p["mu_c_change"] is None:
            return p["mu_c"]
        t1, t2, mu2 = p["mu_c_change"]
        if t <= t1:
            return p["mu_c"]
        if t >= t2:
            return mu2
        s = (t - t1) / (t2 - t1)
        s = s * s * (3 - 2 * s)           # smooth transition
        return p["mu_c"] + (mu2 - p["mu_c"]) * s

    def mu_kin(self, t, v):
        """Kinetic coefficient at time t [s] and relative speed v [rad/s] (Stribeck if ``v_st`` is set)."""
        p = self.p
        mc = self.mu_c(t)
        if p["v_st"]:
            return mc + (p["mu_s"] - mc) * math.exp(-abs(v) / p["v_st"])
        return mc

    def static_ok(self, t, psi, Tneed):
        """Can the wall hold the burden with the torque Tneed at angle psi?"""
        p = self.p
        N = p["m_v"] * G * max(math.cos(psi), 0.0)
        if p["law"] == "paper":
            return math.tan(psi) <= p["mu_s"] or abs(Tneed) <= self.mu_c(t) * N * p["R"]
        return abs(Tneed) <= p["mu_s"] * N * p["R"]

    def static_margin(self, t, psi, Tneed):
        """Event function of the stuck burden: positive while it holds, through zero at breakaway.

        Parameters
        ----------
        t : float
            Time [s].
        psi : float
            Burden angle [rad].
        Tneed : float
            Wall torque needed to carry the burden along [N m].

        Returns
        -------
        float
            Margin [N m] (the 'paper' law's angle margin scaled by 1e7).
        """
        p = self.p
        N = p["m_v"] * G * max(math.cos(psi), 0.0)
        if p["law"] == "paper":
            a = p["mu_s"] * math.cos(psi) - math.sin(psi)     # >0: paper stick
            b = self.mu_c(t) * N * p["R"] - abs(Tneed)          # >0: carried by kinetic friction
            return max(a * 1e7, b)
        return p["mu_s"] * N * p["R"] - abs(Tneed)

    # ---- torques ----------------------------------------------------------------
    def motor_friction(self, w):
        """Motor-shaft friction torque [N m] at motor speed w [rad/s] (``mot_fric``; 0 without it)."""
        mf = self.p["mot_fric"]
        if mf is None:
            return 0.0
        mag = mf["Tc"] + (mf["Ts"] - mf["Tc"]) * math.exp(-(w / mf["ws"]) ** 2)
        return mag * math.tanh(w / mf["eps"])

    def kiln_ext(self, t, th_o, w_o):
        """External torque on the kiln [N m]: bearing friction, quadratic drag and unbalance.

        Parameters
        ----------
        t : float
            Time [s].
        th_o, w_o : float
            Kiln angle [rad] and speed [rad/s].

        Returns
        -------
        float
            Torque [N m], positive driving the kiln.
        """
        p = self.p
        T = -self.Tb * math.tanh(w_o / 1e-3) - p["drag_quad"] * w_o * abs(w_o)
        if p["unb"]:
            for (A, h, ph) in p["unb"]:
                T -= A * math.sin(h * th_o + ph)
        return T

    def spring_torque(self, phi, dphi):
        """Drive-train torque at the kiln axis [N m] for twist phi [rad] and twist rate dphi [rad/s]."""
        s = self.p["spring"]
        if s["kind"] == "hardening":
            return s["k0"] * phi * (1 + (phi / s["phi0"]) ** 2) + s["c"] * dphi
        if s["kind"] == "hertz_backlash":
            d = phi - s["gap"]          # driving flank
            if d > 0:
                return max(s["K15"] * d ** 1.5 * (1 + s["alpha"] * dphi), 0.0)
            if phi < 0:                 # back flank
                return min(-s["K15"] * (-phi) ** 1.5 * (1 - s["alpha"] * dphi), 0.0)
            return 0.0
        raise ValueError(s["kind"])

    # ---- state: [z, x, th_m, w_m, th_o, w_o, psi, w_b] ---------------------------
    def currents(self, t, y, w_fb):
        """Speed error e_f [rpm] and armature current i [A] from the state y and the speed feedback w_fb [rad/s]."""
        p = self.p
        e_f = self.e_v(t) - p["K"] * w_fb
        i = y[1] + p["k_D"] / p["L_a"] * e_f
        return e_f, i

    def rhs(self, t, y, mode, w_fb_held):
        """Right-hand side in a burden mode.

        Parameters
        ----------
        t : float
            Time [s].
        y : array_like
            State ``[z, x, th_m, w_m, th_o, w_o, psi, w_b]`` (integral of e_f [rpm s], x [A], motor angle
            [rad] and speed [rad/s], kiln angle and speed, burden angle and speed).
        mode : int
            0 stuck, +1 / -1 sliding (sign of the wall's speed relative to the burden).
        w_fb_held : float or None
            Held speed feedback [rad/s] (encoder), or None for the true motor speed.

        Returns
        -------
        dy : list
            Time derivative of y.
        i : float
            Armature current [A].
        Tneed : float or None
            Wall torque needed to keep the burden stuck [N m] (None while sliding).
        """
        p = self.p
        z, x, th_m, w_m, th_o, w_o, psi, w_b = y
        w_fb = w_m if w_fb_held is None else w_fb_held
        e_f, i = self.currents(t, y, w_fb)
        e_a = p["k_p"] * e_f + p["k_I"] * z
        dx = (e_a - p["R_a"] * i - p["k_b"] * w_m) / p["L_a"]
        tau_m = p["k_i"] * i - p["B_m"] * w_m - self.motor_friction(w_m)
        tau_k = self.kiln_ext(t, th_o, w_o)
        tau_g = -p["m_v"] * G * p["L"] * math.sin(psi)
        N = p["m_v"] * G * max(math.cos(psi), 0.0)
        Jm = p["J_m"] + p["J_m2"]
        n = p["n"]
        if self.rigid:
            if mode == 0:      # stick
                J = Jm + (p["J_o"] + p["J_v"]) / n ** 2
                a_m = (tau_m + (tau_k + tau_g) / n) / J
                a_o = a_m / n
                a_b = a_o
                Tneed = p["J_v"] * a_o - tau_g
            else:
                v = w_o - w_b
                Tw = mode * self.mu_kin(t, v) * N * p["R"]
                J = Jm + p["J_o"] / n ** 2
                a_m = (tau_m + (tau_k - Tw) / n) / J
                a_o = a_m / n
                a_b = (tau_g + Tw) / p["J_v"]
                Tneed = None
        else:
            phi = th_m / n - th_o
            dphi = w_m / n - w_o
            Ts = self.spring_torque(phi, dphi)
            a_m = (tau_m - Ts / n) / Jm
            if mode == 0:
                a_o = (tau_k + Ts + tau_g) / (p["J_o"] + p["J_v"])
                a_b = a_o
                Tneed = p["J_v"] * a_o - tau_g
            else:
                v = w_o - w_b
                Tw = mode * self.mu_kin(t, v) * N * p["R"]
                a_o = (tau_k + Ts - Tw) / p["J_o"]
                a_b = (tau_g + Tw) / p["J_v"]
                Tneed = None
        dy = [e_f, dx, w_m, a_m, w_o, a_o, w_b, a_b]
        return dy, i, Tneed

    def simulate(self, t_end, t_out, max_step=2e-3):
        """Simulate from rest at t = 0 to t_end.

        Parameters
        ----------
        t_end : float
            End time [s] after the start of the ramp.
        t_out : array_like
            Output times [s] in [0, t_end].
        max_step : float, default 2e-3
            Largest solver step [s].

        Returns
        -------
        i : ndarray
            Armature current [A] at t_out.
        w : ndarray
            Speed feedback [rpm] at t_out (the motor speed, or the held encoder value).
        extra : dict
            Solver times ``T`` [s], burden angle ``psi`` [rad], kiln and burden speeds ``w_o``,
            ``w_b`` [rad/s] and current ``i`` [A] at them.
        """
        p = self.p
        y = np.zeros(8)
        mode = 0
        t = 0.0
        enc = p["encoder"]
        # breakpoints: ramp end and controller ticks
        if enc:
            ticks = np.arange(0.0, t_end + enc["Ts"] / 2, enc["Ts"])
            q = 2 * math.pi / enc["counts"]
            nwin = int(round(enc["window"] / enc["Ts"]))
            hist = [0.0] * (nwin + 1)
        else:
            ticks = np.array([0.0, t_end])
        bps = sorted(set(list(ticks) + [self.t_ramp_end]))
        bps = [b for b in bps if b <= t_end + 1e-12]
        tickset = set(float(x) for x in ticks) if enc else set()
        ts_all, ys_all, modes_all, wfb_all = [], [], [], []
        w_fb_held = 0.0 if enc else None
        nswitch = 0
        for k in range(len(bps) - 1):
            a, b = bps[k], bps[k + 1]
            if enc and a in tickset:
                # controller tick at a: sample encoder
                cnt = math.floor(y[2] / q)
                hist.append(cnt)
                hist.pop(0)
                w_fb_held = (hist[-1] - hist[0]) * q / enc["window"]
            t = a
            while t < b - 1e-12:
                def f(tt, yy):
                    return self.rhs(tt, yy, mode, w_fb_held)[0]

                evs = []
                if mode == 0:
                    def ev_break(tt, yy):
                        _, _, Tn = self.rhs(tt, yy, 0, w_fb_held)
                        return self.static_margin(tt, yy[6], Tn)
                    ev_break.terminal = True
                    ev_break.direction = -1
                    evs.append(ev_break)
                else:
                    def ev_stick(tt, yy, m=mode):
                        return m * (yy[5] - yy[7])
                    ev_stick.terminal = True
                    ev_stick.direction = -1
                    evs.append(ev_stick)
                sol = solve_ivp(f, (t, b), y, method="RK45", rtol=1e-7, atol=1e-9,
                                max_step=max_step, events=evs, dense_output=False)
                ts_all.append(sol.t)
                ys_all.append(sol.y)
                modes_all.append(np.full(sol.t.size, mode))
                wfb_all.append(np.full(sol.t.size, np.nan if w_fb_held is None else w_fb_held))
                t = sol.t[-1]
                y = sol.y[:, -1].copy()
                if sol.status == 1:          # event: new mode
                    nswitch += 1
                    if nswitch > 200000:
                        raise RuntimeError("too many switches")
                    mode = self.new_mode(t, y, mode, w_fb_held)
                    if mode == 0:
                        y[7] = y[5]          # plastic catch of the burden by the wall
                    t = t + 0.0
        T = np.concatenate(ts_all)
        Y = np.concatenate(ys_all, axis=1)
        WF = np.concatenate(wfb_all)
        # remove duplicate times
        keep = np.concatenate([[True], np.diff(T) > 0])
        T, Y, WF = T[keep], Y[:, keep], WF[keep]
        self.T, self.Y = T, Y
        w_fb = np.where(np.isnan(WF), Y[3], WF)
        e_f = np.array([self.e_v(tt) for tt in T]) - p["K"] * w_fb
        i = Y[1] + p["k_D"] / p["L_a"] * e_f
        out_i = np.interp(t_out, T, i)
        if enc:
            # logged speed = the drive's own (held) feedback value
            idx = np.searchsorted(T, t_out, side="right") - 1
            out_w = w_fb[np.clip(idx, 0, T.size - 1)] * p["K"]
        else:
            out_w = np.interp(t_out, T, Y[3]) * p["K"]
        self.nswitch = nswitch
        return out_i, out_w, dict(T=T, psi=Y[6], w_o=Y[5], w_b=Y[7], i=i)

    def new_mode(self, t, y, mode, w_fb_held):
        """Mode after an event at (t, y)."""
        p = self.p
        if mode != 0:
            # v_rel reached zero: can the wall hold it?
            y2 = y.copy()
            y2[7] = y2[5]
            _, _, Tn = self.rhs(t, y2, 0, w_fb_held)
            if self.static_ok(t, y2[6], Tn):
                # catch: the plastic catch changes speeds only by the tiny v_rel left
                y[7] = y[5]
                return 0
            return 1 if Tn > 0 else -1
        # breakaway from stick: slide in the direction the needed torque points
        _, _, Tn = self.rhs(t, y, 0, w_fb_held)
        return 1 if Tn > 0 else -1


def ar1(rng, n, sigma, tau, dt):
    """AR(1) noise of standard deviation sigma and correlation time tau [s], sampled every dt [s].

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source (draws n innovations, then the first value).
    n : int
        Number of samples.
    sigma, tau, dt : float
        Standard deviation (unit of the signal), correlation time [s], sample step [s].

    Returns
    -------
    ndarray
    """
    a = math.exp(-dt / tau)
    e = rng.normal(0, sigma * math.sqrt(1 - a * a), n)
    x = np.empty(n)
    x[0] = rng.normal(0, sigma)
    for k in range(1, n):
        x[k] = a * x[k - 1] + e[k]
    return x


def make_record(path, plant, t_len=40.0, fs=50.0, pre=1.0, seed=0, noise=None, comment=""):
    """Simulate a start-up and write it as a CSV with noise, as the red team's records.

    Parameters
    ----------
    path : path-like
        CSV to write (``time_s,current_A,speed_rpm,speed_ref_rpm``; two comment lines first).
    plant : Plant
        The plant.
    t_len : float, default 40
        Record length [s] (samples from 0 to t_len inclusive).
    fs : float, default 50
        Logger rate [Hz].
    pre : float, default 1
        Seconds at rest logged before the start.
    seed : int, default 0
        Seed of ``numpy.random.default_rng`` for the noise.
    noise : dict, optional
        ``i_white``, ``i_ar`` [A], ``i_tau`` [s], ``w_white``, ``w_ar`` [rpm], ``w_tau`` [s]
        (default 4, 4, 0.4, 0.25, 0.25, 0.2).
    comment : str
        Text of the first comment line.

    Returns
    -------
    t_rec : ndarray
        Record times [s].
    i, w : ndarray
        Noise-free current [A] and speed [rpm] at t_rec.
    extra : dict
        :meth:`Plant.simulate`'s solver output.
    """
    noise = noise or dict(i_white=4.0, i_ar=4.0, i_tau=0.4, w_white=0.25, w_ar=0.25, w_tau=0.2)
    dt = 1.0 / fs
    t_rec = np.arange(0.0, t_len + 1e-9, dt)
    t_sim = t_rec - pre
    t_end = t_sim[-1]
    sim_t = np.clip(t_sim, 0.0, None)
    i, w, extra = plant.simulate(t_end, sim_t)
    i = np.where(t_sim < 0, 0.0, i)
    w = np.where(t_sim < 0, 0.0, w)
    rng = np.random.default_rng(seed)
    nn = t_rec.size
    i_m = i + rng.normal(0, noise["i_white"], nn) + ar1(rng, nn, noise["i_ar"], noise["i_tau"], dt)
    w_m = w + rng.normal(0, noise["w_white"], nn) + ar1(rng, nn, noise["w_ar"], noise["w_tau"], dt)
    ref = np.array([plant.e_v(tt) if tt >= 0 else 0.0 for tt in t_sim])
    with open(path, "w") as fh:
        fh.write(f"# red team 6 record: {comment}\n")
        fh.write(f"# logger at {fs:g} Hz, start-up at t = {pre:g} s\n")
        fh.write("time_s,current_A,speed_rpm,speed_ref_rpm\n")
        for k in range(nn):
            fh.write(f"{t_rec[k]:.6f},{i_m[k]:.4f},{w_m[k]:.4f},{ref[k]:.4f}\n")
    return t_rec, i, w, extra
