"""Red team 9: an independent rotary-kiln start-up plant (numpy only), written from
van Dyk & Pretorius (1994), eqs. 1-21, 17, and NOTES.md (torque-consistent law), by a helper that did not
read kilnctl's model (2026-11-27); kept as written, records in :mod:`benchmarks.red9_records`.

Fixed-step RK4 (dt 0.5 ms) with guard crossings located by bisection on the step
length and known time break points (ramp corners) hit exactly.

Options (dict `p`, see DEFAULTS) beyond the paper:
  law           'paper' | 'torque'
  B_o           viscous drag on the kiln [N m s/rad]
  k_po, C_po    drive-train compliance at the kiln axis (None: rigid reducer)
  T_cm, w_cm    motor Coulomb friction T_cm*tanh(w/w_cm)
  J_m2          rigid second motor inertia
  I_max         ideal current clamp (None: none), integrator frozen while held
  tau_ctrl      first-order filter on the speed feedback, controller path only
                (the logged speed is the shaft speed)
  ar_a          armature reaction: flux factor 1 - ar_a*(i/1000)^2 on k_i and k_b
  T_tp, z_tp, phi_tp   tooth-pass torque ripple on the kiln T_tp*sin(z_tp*theta_o+phi)
  scurve_Tj     S-curve reference rounding time (None: straight ramp)
"""
import math
import numpy as np

DEFAULTS = dict(
    R_a=0.00961, L_a=0.57e-3, k_i=4.6, k_b=4.6, J_m=21.5, B_m=0.005,
    K=60.0 / (2 * math.pi), k_p=2.0, k_I=5.0, k_D=0.01, V_max=500.0,
    J_o=6.978e6, J_v=1.678e6, m_v=580e3, L=1.353, R=2.17, mu_c=0.4, mu_s=0.51,
    g=9.81, n=1076.5, mu_brg=0.001, P=16.512e6, l_brg=0.7155, k_brg=0.5475,
    omega_ref=500.0, ramp_rate=74.0, t0=1.0, law='paper',
    B_o=0.0, k_po=None, C_po=0.0, T_cm=0.0, w_cm=0.005, J_m2=0.0, I_max=None,
    tau_ctrl=None, ar_a=0.0, T_tp=0.0, z_tp=240, phi_tp=0.0, scurve_Tj=None,
)

# state: 0 z, 1 x_a, 2 w_m, 3 w_o, 4 phi_po, 5 w_b, 6 psi, 7 w_f, 8 th_o
NS = 9


class Plant:
    def __init__(self, **kw):
        p = dict(DEFAULTS)
        for k in kw:
            if k not in p:
                raise KeyError(k)
        p.update(kw)
        self.p = p
        self.T_brg = 2 * p['mu_brg'] * p['P'] / 2 * math.cos(math.pi / 6) * (p['l_brg'] + p['k_brg']) / 2
        self.rigid = p['k_po'] is None
        a, Tj = p['ramp_rate'], p['scurve_Tj']
        if Tj is None:
            self.breaks = [p['t0'], p['t0'] + p['omega_ref'] / a]
        else:
            T2 = p['omega_ref'] / a - Tj
            assert T2 > 0
            self.T2 = T2
            self.breaks = [p['t0'], p['t0'] + Tj, p['t0'] + Tj + T2, p['t0'] + 2 * Tj + T2]

    # ---------------- reference
    def ref(self, t):
        p = self.p
        tau = t - p['t0']
        a = p['ramp_rate']
        if tau <= 0:
            return 0.0, 0.0
        Tj = p['scurve_Tj']
        if Tj is None:
            v = a * tau
            if v >= p['omega_ref']:
                return p['omega_ref'], 0.0
            return v, a
        T2 = self.T2
        if tau < Tj:
            return a * tau * tau / (2 * Tj), a * tau / Tj
        if tau < Tj + T2:
            return a * Tj / 2 + a * (tau - Tj), a
        if tau < 2 * Tj + T2:
            s = tau - Tj - T2
            return a * Tj / 2 + a * T2 + a * s - a * s * s / (2 * Tj), a * (1 - s / Tj)
        return p['omega_ref'], 0.0

    # ---------------- right-hand side
    def aux(self, t, y, mode):
        """Returns dict with derivatives and algebraic quantities."""
        p = self.p
        bm, lim = mode
        z, x_a, w_m, w_o, phi, w_b, psi, w_f, th = y
        if self.rigid:
            w_o = w_m / p['n']
        ev, dev = self.ref(t)
        w_fb = w_m if p['tau_ctrl'] is None else w_f
        e_f = ev - p['K'] * w_fb
        e_pi = p['k_p'] * e_f + p['k_I'] * z
        e_a = min(max(e_pi, -p['V_max']), p['V_max'])
        vclamp = e_a != e_pi
        if lim:
            i = p['I_max']
        else:
            i = x_a + p['k_D'] / p['L_a'] * e_f
        flux = 1.0 - p['ar_a'] * (i / 1000.0) ** 2
        T_m = p['k_i'] * flux * i - p['B_m'] * w_m
        if p['T_cm']:
            T_m -= p['T_cm'] * math.tanh(w_m / p['w_cm'])
        m_v, J_v = p['m_v'], p['J_v']
        mgL = m_v * p['g'] * p['L']
        N = m_v * p['g'] * max(math.cos(psi), 0.0)
        sp = math.sin(psi)
        # external torques on the kiln (opposing positive)
        T_k = self.T_brg * math.tanh(w_o / 1e-4) + p['B_o'] * w_o
        if p['T_tp']:
            T_k += p['T_tp'] * math.sin(p['z_tp'] * th + p['phi_tp'])
        stuck = bm in ('stick', 'held')
        T_w = 0.0
        if not stuck:
            s = 1.0 if bm == 'slip_pos' else -1.0
            T_w = s * p['mu_c'] * N * p['R']
        Jm = p['J_m'] + p['J_m2']
        n = p['n']
        if self.rigid:
            if stuck:
                J = Jm + (p['J_o'] + J_v) / n ** 2
                dw_m = (T_m - (T_k + mgL * sp) / n) / J
                a_o = dw_m / n
                dw_b = a_o
            else:
                J = Jm + p['J_o'] / n ** 2
                dw_m = (T_m - (T_k + T_w) / n) / J
                a_o = dw_m / n
                dw_b = (-mgL * sp + T_w) / J_v
            dphi = 0.0
            w_b_eff = w_o if stuck else w_b
        else:
            T_po = p['k_po'] * phi + p['C_po'] * (w_m / n - w_o)
            dw_m = (T_m - T_po / n) / Jm
            dphi = w_m / n - w_o
            if stuck:
                a_o = (T_po - T_k - mgL * sp) / (p['J_o'] + J_v)
                dw_b = a_o
            else:
                a_o = (T_po - T_k - T_w) / p['J_o']
                dw_b = (-mgL * sp + T_w) / J_v
            w_b_eff = w_o if stuck else w_b
        T_need = J_v * a_o + mgL * sp if stuck else None
        if p['tau_ctrl'] is not None:
            dw_f = (w_m - w_f) / p['tau_ctrl']
            dw_fb = dw_f
        else:
            dw_f = 0.0
            dw_fb = dw_m
        de_f = dev - p['K'] * dw_fb
        if lim:
            dx_a = -p['k_D'] / p['L_a'] * de_f
            dz = 0.0
        else:
            dx_a = (e_a - p['R_a'] * i - p['k_b'] * flux * w_m) / p['L_a']
            dz = 0.0 if (vclamp and e_pi * e_f > 0) else e_f
        dy = np.array([dz, dx_a, dw_m, a_o, dphi, dw_b, w_b_eff, dw_f, w_o])
        return dict(dy=dy, i=i, T_need=T_need, N=N, sp=sp, cp=math.cos(psi), e_pi=e_a,
                    de_f=de_f, w_m=w_m, w_o=w_o, w_b=w_b_eff, mgL=mgL,
                    e_unl=None if not lim else (e_a + p['k_D'] * de_f - p['R_a'] * i - p['k_b'] * flux * w_m),
                    i_unl=x_a + p['k_D'] / p['L_a'] * e_f)

    def guards(self, t, y, mode):
        p = self.p
        a = self.aux(t, y, mode)
        bm, lim = mode
        g = {}
        R = p['R']
        if bm == 'stick':
            if p['law'] == 'torque':
                g['brk'] = p['mu_s'] * a['N'] * R - abs(a['T_need'])
            else:
                g['brk'] = p['mu_s'] * a['cp'] - a['sp']
        elif bm == 'held':
            g['brk'] = p['mu_c'] * a['N'] * R - a['T_need']
        else:
            vrel = a['w_o'] - y[5]
            g['vrel'] = vrel if bm == 'slip_pos' else -vrel
        if p['I_max'] is not None:
            if lim:
                g['rel'] = a['e_unl']
            else:
                g['lim'] = p['I_max'] - a['i_unl']
        return g, a

    def step(self, t, y, h, mode):
        f = lambda tt, yy: self.aux(tt, yy, mode)['dy']
        k1 = f(t, y)
        k2 = f(t + h / 2, y + h / 2 * k1)
        k3 = f(t + h / 2, y + h / 2 * k2)
        k4 = f(t + h, y + h * k3)
        return y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def transition(self, t, y, mode, key):
        p = self.p
        bm, lim = mode
        y = y.copy()
        n = p['n']
        if key == 'lim':
            return y, (bm, True)
        if key == 'rel':
            # continuity of the current: x_a + kD/La e_f = I_max
            a = self.aux(t, y, mode)
            return y, (bm, False)
        if key == 'brk':
            if bm == 'stick' and p['law'] == 'paper':
                a = self.aux(t, y, (bm, lim))
                if a['T_need'] <= p['mu_c'] * a['N'] * p['R']:
                    return y, ('held', lim)
            a = self.aux(t, y, (bm, lim))
            y[5] = a['w_o']
            s = 'slip_pos' if a['T_need'] > 0 else 'slip_neg'
            return y, (s, lim)
        if key == 'vrel':
            # plastic catch, momentum conserving
            if self.rigid:
                Jk = (p['J_m'] + p['J_m2']) * n ** 2 + p['J_o']
                w_o = y[2] / n
                wc = (Jk * w_o + p['J_v'] * y[5]) / (Jk + p['J_v'])
                y[2] = wc * n
            else:
                wc = (p['J_o'] * y[3] + p['J_v'] * y[5]) / (p['J_o'] + p['J_v'])
                y[3] = wc
            y[5] = wc
            new = 'stick'
            a = self.aux(t, y, ('stick', lim))
            if p['law'] == 'torque':
                if abs(a['T_need']) > p['mu_s'] * a['N'] * p['R']:
                    new = 'slip_neg' if bm == 'slip_pos' else 'slip_pos'
            else:
                if a['sp'] > p['mu_s'] * a['cp']:
                    new = 'held' if a['T_need'] <= p['mu_c'] * a['N'] * p['R'] else ('slip_pos' if a['T_need'] > 0 else 'slip_neg')
            return y, (new, lim)
        raise KeyError(key)

    def run(self, t_end, fs, dt=0.5e-3):
        """Simulate from rest at t=0; returns sample times and outputs."""
        ts = 1.0 / fs
        nsub = int(round(ts / dt))
        assert abs(nsub * dt - ts) < 1e-12
        y = np.zeros(NS)
        mode = ('stick', False)
        t = 0.0
        nsamp = int(round(t_end * fs)) + 1
        out = np.zeros((nsamp, 4))
        events = []
        breaks = list(self.breaks)

        def record(k, t, y, mode):
            a = self.aux(t, y, mode)
            ev, _ = self.ref(t)
            out[k] = (t, a['i'], y[2] * 60 / (2 * math.pi), ev)

        record(0, 0.0, y, mode)
        for k in range(1, nsamp):
            for j in range(nsub):
                t_tgt = (k - 1) * ts + (j + 1) * dt
                while t < t_tgt - 1e-13:
                    h = t_tgt - t
                    for b in breaks:
                        if t + 1e-13 < b < t + h:
                            h = b - t
                    g0, _ = self.guards(t, y, mode)
                    y1 = self.step(t, y, h, mode)
                    g1, _ = self.guards(t + h, y1, mode)
                    crossed = [key for key in g0 if g0[key] > 0 and g1[key] <= 0]
                    if not crossed:
                        t, y = t + h, y1
                        continue
                    lo, hi = 0.0, h
                    key_hit = crossed[0]
                    for _ in range(40):
                        mid = 0.5 * (lo + hi)
                        ym = self.step(t, y, mid, mode)
                        gm, _ = self.guards(t + mid, ym, mode)
                        c = [key for key in g0 if g0[key] > 0 and gm[key] <= 0]
                        if c:
                            hi = mid
                            key_hit = c[0]
                        else:
                            lo = mid
                    y = self.step(t, y, hi, mode)
                    t = t + hi
                    y, newmode = self.transition(t, y, mode, key_hit)
                    events.append((t, key_hit, mode, newmode))
                    mode = newmode
                    if len(events) > 5000:
                        raise RuntimeError('event storm')
            t = k * ts
            record(k, t, y, mode)
        return out, events
