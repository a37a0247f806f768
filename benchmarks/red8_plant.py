"""Red team 8's own kiln-drive plant (numpy only; written from the paper and NOTES.md by a helper that did
not read kilnctl's model, 2026-11-27; kept as written, records in :mod:`benchmarks.red8_records`).

Macro model of van Dyk & Pretorius (1994): DC motor with the paper's PID speed loop (eq. 21,
the derivative realised as a direct current term (k_D/L_a) e_f), ramped speed reference,
rigid reducer n (or a torsional spring at the kiln axis), kiln shell with the support-bearing
friction (eq. 17), burden as a rigid disc with wall friction (stick / slip, eqs. 1-3, 6, 16)
under either the printed force law ("paper", with a kinetically held mode) or the
torque-consistent law ("torque").

Integration: fixed-step classical RK4 (dt = 0.5 ms by default); the burden's mode switches,
the second motor's mesh contacts and the ramp corner are located inside a step (Illinois
root finding on the step length) and the step is restarted there.

Effects (dict `eff`, all optional; forms of red team 8's own):
  soft_limit      {"I_lim", "kp", "ki"}: a PI current-limit regulator acting on the armature
                  voltage (anti-windup: integrator >= 0; the speed integrator frozen while it acts)
  warming         {"dRa", "tau_th"}: armature resistance rising with i^2 heating,
                  R_a = R_a0 (1 + th), dth/dt = (dRa (i/840)^2 - th)/tau_th
  arm_reaction    {"a", "I_n"}: flux k = k0 (1 - a (i/I_n)^2) for torque and back-emf (not used:
                  at a few per cent it makes the armature circuit unstable, d(k_b w)/di > R_a)
  field           {"deficit", "tau_f"}: field still building up when the record starts (t = 0):
                  flux k = k0 (1 - deficit exp(-t / tau_f)) for torque and back-emf
  burden_visc     {"c_b"}: wall friction on a slipping burden + c_b * v_rel [N m s/rad]
  unbalance       {"T", "phi"}: kiln torque -T sin(theta_o + phi)
  motor_coulomb   {"T_c", "w_eps"}: -T_c tanh(w_m / w_eps) on the motor shaft
  compliance      {"k_po", "C_po"}: spring-damper at the kiln axis between motor/n and kiln
  motor2          {"J", "k", "c", "gap"}: second, electrically isolated motor on its own pinion,
                  linked to the girth gear by a spring k / damper c (motor-side units) with a
                  free play `gap` [rad, motor side]; contact force never pulls (clipped at 0)
"""
import math
import numpy as np

TABLE1 = dict(R_a=0.00961, L_a=0.57e-3, k_i=4.6, k_b=4.6, J_m=21.5, B_m=0.005, n=1076.5,
              J_o=6.978e6, J_v=1.678e6, m_v=580e3, L=1.353, R=2.17, mu_c=0.4, mu_s=0.51,
              mu_brg=0.001, P=16.512e6, l=0.7155, k=0.5475, g=9.81)
K_FB = 60.0 / (2.0 * math.pi)

# state indices
Z, XA, WM, WO, PHPO, THO, PSI, WB, WM2, PH2, WLIM, TH = range(12)
NX = 12


class Plant:
    def __init__(self, p=None, eff=None, law="paper", gains=(2.0, 5.0, 0.01), ramp_rate=74.0,
                 omega_ref=500.0, t0=1.0, V_max=500.0):
        self.p = dict(TABLE1)
        if p:
            self.p.update(p)
        self.eff = eff or {}
        self.law = law
        self.kp, self.kI, self.kD = gains
        self.ramp_rate, self.omega_ref, self.t0, self.V_max = ramp_rate, omega_ref, t0, V_max
        self.t_ramp_end = t0 + omega_ref / ramp_rate
        P = self.p
        self.T_brg = 2 * P["mu_brg"] * P["P"] / 2 * math.cos(math.pi / 6) * (P["l"] + P["k"]) / 2
        e = self.eff
        self.has_m2 = "motor2" in e
        self.compliant = "compliance" in e

    # ------------------------------------------------------------------ dynamics
    def ref(self, t):
        if t <= self.t0:
            return 0.0
        return min(self.ramp_rate * (t - self.t0), self.omega_ref)

    def deriv(self, t, x, mode):
        """Return (dx list, aux dict). mode = (burden_mode, mesh_mode)."""
        P, e = self.p, self.eff
        bmode, mmode = mode
        n = P["n"]
        if t < self.t0 - 1e-12:  # drive off, kiln held by its brake until the start-up
            return [0.0] * NX, dict(i=0.0, ev=0.0, Tneed=0.0, N=P["m_v"] * P["g"], Tg=0.0, vrel=0.0,
                                    Ra=P["R_a"], kf=P["k_i"], T2=0.0, vlim=0.0)
        z, xa, wm, wo, phpo, tho, psi, wb, wm2, ph2, wlim, th = x
        ev = self.ref(t)
        ef = ev - K_FB * wm
        La = P["L_a"]
        i = xa + self.kD / La * ef
        # motor constants
        kf = P["k_i"]
        kb = P["k_b"]
        if "arm_reaction" in e:
            ar = e["arm_reaction"]
            fac = 1.0 - ar["a"] * (i / ar["I_n"]) ** 2
            kf *= fac
            kb *= fac
        if "field" in e:
            fe = e["field"]
            fac = 1.0 - fe["deficit"] * math.exp(-t / fe["tau_f"])
            kf *= fac
            kb *= fac
        Ra = P["R_a"]
        dth = 0.0
        if "warming" in e:
            w = e["warming"]
            Ra *= 1.0 + th
            dth = (w["dRa"] * (i / 840.0) ** 2 - th) / w["tau_th"]
        # speed PID, limits
        epid = self.kp * ef + self.kI * z
        vlim = 0.0
        dwlim = 0.0
        if "soft_limit" in e:
            sl = e["soft_limit"]
            el = i - sl["I_lim"]
            vlim = max(0.0, sl["kp"] * el + sl["ki"] * wlim)
            dwlim = el if (wlim > 0.0 or el > 0.0) else 0.0
        ea = epid - vlim
        clamped = False
        if ea > self.V_max:
            ea, clamped = self.V_max, True
        elif ea < -self.V_max:
            ea, clamped = -self.V_max, True
        dz = 0.0 if (clamped or vlim > 0.0) else ef
        dxa = (ea - Ra * i - kb * wm) / La
        Te = kf * i
        Tfm = P["B_m"] * wm
        if "motor_coulomb" in e:
            mc = e["motor_coulomb"]
            Tfm += mc["T_c"] * math.tanh(wm / mc["w_eps"])
        # second motor branch (motor-side units): twist ph2 = n*theta_o - theta_m2
        T2 = 0.0
        dwm2 = 0.0
        dph2 = 0.0
        if self.has_m2:
            m2 = e["motor2"]
            dph2 = n * wo - wm2
            gap = m2["gap"]
            if mmode == "spring":
                T2 = m2["k"] * ph2 + m2["c"] * dph2
            elif mmode == "contact":
                T2 = max(0.0, m2["k"] * (ph2 - gap) + m2["c"] * dph2)
            elif mmode == "back":
                T2 = min(0.0, m2["k"] * ph2 + m2["c"] * dph2)
            dwm2 = (T2 - P["B_m"] * wm2 - m2.get("T_f", 0.0) * math.tanh(wm2 / 0.02)) / m2["J"]
        # kiln external torques (other than drive and burden)
        Tk = -self.T_brg * math.tanh(wo / 1e-4) - n * T2
        if "unbalance" in e:
            u = e["unbalance"]
            Tk -= u["T"] * math.sin(tho + u["phi"])
        mg = P["m_v"] * P["g"]
        Tg = mg * P["L"] * math.sin(psi)
        Nn = mg * max(math.cos(psi), 0.0)
        Jv, Jo, Jm = P["J_v"], P["J_o"], P["J_m"]
        stuck = bmode in ("stick", "held")
        Tw = 0.0
        vrel = wo - wb
        if not stuck:
            sgn = 1.0 if bmode == "slip_pos" else -1.0
            Tw = sgn * P["mu_c"] * Nn * P["R"]
            if "burden_visc" in e:
                Tw += e["burden_visc"]["c_b"] * vrel
        if self.compliant:
            c = e["compliance"]
            dphpo = wm / n - wo
            Tpo = c["k_po"] * phpo + c["C_po"] * dphpo
            dwm = (Te - Tfm - Tpo / n) / Jm
            if stuck:
                dwo = (Tpo + Tk - Tg) / (Jo + Jv)
                dwb = dwo
            else:
                dwo = (Tpo + Tk - Tw) / Jo
                dwb = (Tw - Tg) / Jv
        else:
            dphpo = 0.0
            if stuck:
                dwo = (n * (Te - Tfm) + Tk - Tg) / (Jm * n * n + Jo + Jv)
                dwb = dwo
            else:
                dwo = (n * (Te - Tfm) + Tk - Tw) / (Jm * n * n + Jo)
                dwb = (Tw - Tg) / Jv
            dwm = n * dwo
        Tneed = Jv * dwo + Tg  # wall torque needed to keep the burden with the kiln (stuck modes)
        dx = [dz, dxa, dwm, dwo, dphpo, wo, wb, dwb, dwm2, dph2, dwlim, dth]
        aux = dict(i=i, ev=ev, Tneed=Tneed, N=Nn, Tg=Tg, vrel=vrel, Ra=Ra, kf=kf, T2=T2, vlim=vlim)
        return dx, aux

    # ------------------------------------------------------------------ hybrid logic
    def guards(self, t, x, mode):
        P = self.p
        bmode, mmode = mode
        out = []
        _, a = self.deriv(t, x, mode)
        NR = a["N"] * P["R"]
        if bmode == "stick":
            if self.law == "torque":
                out.append(P["mu_s"] * NR - abs(a["Tneed"]))
            else:
                out.append(P["mu_s"] * math.cos(x[PSI]) - math.sin(x[PSI]))
        elif bmode == "held":
            out.append(P["mu_c"] * NR - a["Tneed"])
        elif bmode == "slip_pos":
            out.append(x[WO] - x[WB])
        elif bmode == "slip_neg":
            out.append(x[WB] - x[WO])
        if self.has_m2 and mmode != "spring":
            gap = self.eff["motor2"]["gap"]
            if mmode == "gap":
                out.append(gap - x[PH2])
                out.append(x[PH2] + 1e-12 if gap > 0 else 1.0)
            elif mmode == "contact":
                out.append(x[PH2] - gap + 1e-12)
            elif mmode == "back":
                out.append(-x[PH2] + 1e-12)
        return out

    def new_mode(self, t, x, mode):
        """Mode after a guard crossing at (t, x)."""
        P = self.p
        bmode, mmode = mode
        if self.has_m2 and mmode != "spring":
            gap = self.eff["motor2"]["gap"]
            ph = x[PH2]
            if mmode == "gap" and ph >= gap - 1e-12:
                mmode = "contact"
            elif mmode == "gap" and ph <= 1e-12 and gap > 0:
                mmode = "back"
            elif mmode == "contact" and ph < gap:
                mmode = "gap" if gap > 0 else "back"
            elif mmode == "back" and ph > 0:
                mmode = "gap" if gap > 0 else "contact"
        # burden
        _, a = self.deriv(t, x, ("stick", mmode))
        NR = a["N"] * P["R"]
        Tn = a["Tneed"]
        vrel = x[WO] - x[WB]
        g_b = self.guards(t, x, (bmode, mmode))[0]
        if g_b <= 0.0:
            if bmode == "stick":
                if self.law == "torque":
                    bmode = "slip_pos" if Tn > 0 else "slip_neg"
                else:
                    bmode = "held" if abs(Tn) <= P["mu_c"] * NR else ("slip_pos" if Tn > 0 else "slip_neg")
            elif bmode == "held":
                bmode = "slip_pos"
            elif bmode in ("slip_pos", "slip_neg"):
                # relative velocity reached zero: stick if the wall can hold the burden
                if self.law == "torque":
                    if abs(Tn) <= P["mu_s"] * NR:
                        bmode = "stick"
                    else:
                        bmode = "slip_pos" if Tn > 0 else "slip_neg"
                else:
                    if P["mu_s"] * math.cos(x[PSI]) - math.sin(x[PSI]) >= 0 and abs(Tn) <= P["mu_s"] * NR:
                        bmode = "stick"
                    elif abs(Tn) <= P["mu_c"] * NR:
                        bmode = "held"
                    else:
                        bmode = "slip_pos" if Tn > 0 else "slip_neg"
                if bmode in ("stick", "held"):
                    x[WB] = x[WO]  # plastic catch (v_rel is ~0 here)
        return (bmode, mmode)

    # ------------------------------------------------------------------ integrator
    def rk4(self, t, x, h, mode):
        f = self.deriv
        k1, _ = f(t, x, mode)
        x2 = [xi + 0.5 * h * ki for xi, ki in zip(x, k1)]
        k2, _ = f(t + 0.5 * h, x2, mode)
        x3 = [xi + 0.5 * h * ki for xi, ki in zip(x, k2)]
        k3, _ = f(t + 0.5 * h, x3, mode)
        x4 = [xi + h * ki for xi, ki in zip(x, k3)]
        k4, _ = f(t + h, x4, mode)
        xn = [xi + h / 6.0 * (a + 2 * b + 2 * c + d) for xi, a, b, c, d in zip(x, k1, k2, k3, k4)]
        if "soft_limit" in self.eff and xn[WLIM] < 0.0:
            xn[WLIM] = 0.0
        return xn

    def simulate(self, t_end=40.0, dt=5e-4, fs=50.0, max_events=20000):
        """Simulate from rest at t = 0; return dict of arrays sampled at fs (t = 0, 1/fs, ...)."""
        x = [0.0] * NX
        mode = ("stick", ("gap" if self.eff["motor2"]["gap"] > 0 else "spring") if self.has_m2 else "none")
        t = 0.0
        nsub = int(round(1.0 / fs / dt))
        nout = int(round(t_end * fs)) + 1
        out = {k: np.zeros(nout) for k in ("t", "i", "rpm", "ref", "psi", "vrel", "rpm2")}
        events = []
        breaks = [self.t0, self.t_ramp_end]

        def record(k, t, x):
            _, a = self.deriv(t, x, mode)
            out["t"][k] = t
            out["i"][k] = a["i"]
            out["rpm"][k] = x[WM] * K_FB
            out["ref"][k] = a["ev"]
            out["psi"][k] = x[PSI]
            out["vrel"][k] = x[WO] - x[WB]
            out["rpm2"][k] = x[WM2] * K_FB

        record(0, t, x)
        nstep = (nout - 1) * nsub
        for s in range(1, nstep + 1):
            t_target = s * dt
            while t < t_target - 1e-13:
                h = t_target - t
                for b in breaks:  # forced break points (ramp start and corner)
                    if t + 1e-12 < b < t + h:
                        h = b - t
                g0 = self.guards(t, x, mode)
                xn = self.rk4(t, x, h, mode)
                g1 = self.guards(t + h, xn, mode)
                crossed = [j for j, (a0, a1) in enumerate(zip(g0, g1)) if a0 > 0.0 and a1 <= 0.0]
                if not crossed:
                    t, x = t + h, xn
                    continue
                # locate earliest crossing by Illinois on the step length
                best = None
                for j in crossed:
                    lo, hi, glo, ghi = 0.0, h, g0[j], g1[j]
                    side = 0
                    for _ in range(60):
                        m = (lo * ghi - hi * glo) / (ghi - glo) if ghi != glo else 0.5 * (lo + hi)
                        if not (lo < m < hi):
                            m = 0.5 * (lo + hi)
                        gm = self.guards(t + m, self.rk4(t, x, m, mode), mode)[j]
                        if gm > 0.0:
                            lo, glo = m, gm
                            if side == 1:
                                ghi *= 0.5
                            side = 1
                        else:
                            hi, ghi = m, gm
                            if side == -1:
                                glo *= 0.5
                            side = -1
                        if hi - lo < 1e-9:
                            break
                    if best is None or hi < best:
                        best = hi
                x = self.rk4(t, x, best, mode)
                t = t + best
                old = mode
                mode = self.new_mode(t, x, mode)
                events.append((t, old, mode))
                if len(events) > max_events:
                    raise RuntimeError("event storm at t=%.6f %s" % (t, mode))
                if mode == old:
                    # guard touched zero but the mode stays: step past it with a tiny nudge
                    x = self.rk4(t, x, 1e-7, mode)
                    t += 1e-7
            if s % nsub == 0:
                record(s // nsub, round(s * dt, 9), x)
        out["events"] = events
        return out


# ---------------------------------------------------------------------- helpers
def fit_percent(y, yhat):
    y = np.asarray(y)
    return 100.0 * (1.0 - np.linalg.norm(y - yhat) / np.linalg.norm(y - y.mean()))


def ar1(rng, n, sigma, tau, dt):
    a = math.exp(-dt / tau)
    w = rng.normal(0.0, sigma * math.sqrt(1 - a * a), n)
    out = np.empty(n)
    acc = rng.normal(0.0, sigma)
    for k in range(n):
        acc = a * acc + w[k]
        out[k] = acc
    return out
