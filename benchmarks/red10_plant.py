"""Red team 10: an independent rotary-kiln start-up plant (numpy only), written from
van Dyk & Pretorius (1994) and NOTES.md by a helper that did not read kilnctl's model (2026-11-27, fifth
session); kept as written.  Its kilns are not the paper's: kiln A (a 3.0 m lime kiln, 150 kW motor) and
kiln B (a 5.2 m cement kiln with two powered motors).  Its reference is any piecewise-linear profile
(``ref``: corners (t, rpm)), which found that kilnctl followed only one ramp and hold.

Macro model of van Dyk & Pretorius (1994): speed PID with the derivative realised through
L_a (eq. 21), DC motor, reducer n (rigid, or a spring-damper at the kiln axis), kiln with
bearing torque (eq. 17), burden with stick / held / slip modes (paper force law or the
torque-consistent law). Fixed-step RK4 (dt) with mode-guard crossings located by
bisection of the step; the reference's break points are hit exactly.

Everything is a key of the dict `p` (see base_params). Extras beyond the paper:
  J_m2     second motor inertia on the motor shaft (rigid)
  B_o      viscous drag on the kiln
  T_unb, phi_unb   once-per-rev kiln torque -T_unb sin(theta_o + phi)
  T_cm     motor Coulomb friction T_cm*tanh(w_m / 0.005)
  tau_s    first-order speed sensor lag (controller AND logged speed see it)
  k_po, C_po  drive-train compliance at the kiln axis (None = rigid)
  ref      list of (t, rpm) corners of a piecewise-linear reference
  mv_rate  (t_start, t_end, dm) burden mass rising linearly by dm over [t_start, t_end]
"""
import math
import numpy as np


def kiln_A():
    """A smaller lime kiln, 3.0 m shell, 150 kW DC drive (my own choice)."""
    R = 1.5
    m_v = 150e3
    M_shell = 450e3
    p = dict(
        # motor: 150 kW, 440 V DC, 1000 rpm
        R_a=0.040, L_a=2.0e-3, k_i=3.4, k_b=3.4, J_m=3.5, B_m=0.002,
        K=60 / (2 * math.pi), k_p=0.5, k_I=1.5, k_D=0.003, V_max=460.0,
        I_max=600.0,
        n=900.0,
        J_o=0.88 * M_shell * R ** 2, J_v=0.614 * m_v * R ** 2, m_v=m_v,
        L=0.95, R=R, mu_c=0.40, mu_s=0.51, g=9.81,
        mu_brg=0.001, P=M_shell * 9.81, l_brg=0.50, k_brg=0.38,
        ref=[(0.0, 0.0), (1.0, 0.0), (11.0, 1000.0)], law='paper',
        J_m2=0.0, B_o=0.0, T_unb=0.0, phi_unb=0.0, T_cm=0.0, tau_s=None,
        k_po=None, C_po=0.0, mv_rate=None,
        n_mot=1, T_step=None, Ra_rise=None,
    )
    return p


class Plant:
    # state: z, x_a, w_m, w_o, w_b, psi, phi_s, w_meas, th_o
    def __init__(self, p):
        self.p = dict(p)
        p = self.p
        self.Tbrg = 2 * p['mu_brg'] * (p['P'] / 2) * math.cos(math.radians(30)) * (p['l_brg'] + p['k_brg']) / 2
        self.rigid = p['k_po'] is None
        self.mode = 'stick'

    def eref(self, t):
        r = self.p['ref']
        if t <= r[0][0]:
            return r[0][1]
        for (t1, v1), (t2, v2) in zip(r[:-1], r[1:]):
            if t <= t2:
                return v1 + (v2 - v1) * (t - t1) / (t2 - t1)
        return r[-1][1]

    def mv(self, t):
        p = self.p
        if p['mv_rate'] is None:
            return p['m_v']
        ts, te, dm = p['mv_rate']
        f = min(max((t - ts) / (te - ts), 0.0), 1.0)
        return p['m_v'] + dm * f

    def elec(self, t, x):
        p = self.p
        z, x_a, w_m = x[0], x[1], x[2]
        w_fb = x[7] if p['tau_s'] else w_m
        e_f = self.eref(t) - p['K'] * w_fb
        u = p['k_p'] * e_f + p['k_I'] * z
        sat = 0
        if u > p['V_max']:
            u, sat = p['V_max'], 1
        elif u < -p['V_max']:
            u, sat = -p['V_max'], -1
        i_a = x_a + p['k_D'] / p['L_a'] * e_f
        return e_f, u, sat, i_a

    def forces(self, t, x):
        """returns derivative and the holding torque needed (stick/held) and N."""
        p = self.p
        e_f, u, sat, i_a = self.elec(t, x)
        z, x_a, w_m, w_o, w_b, psi, phi_s, w_meas, th_o = x
        dz = 0.0 if (sat != 0 and np.sign(e_f) == sat) else e_f
        Ra = p['R_a']
        if p['Ra_rise'] is not None:
            ts_, te_, f_ = p['Ra_rise']
            Ra = Ra * (1 + (f_ - 1) * min(max((t - ts_) / (te_ - ts_), 0.0), 1.0))
        dx_a = (u - Ra * i_a - p['k_b'] * w_m) / p['L_a']
        mv = self.mv(t)
        Tg = mv * p['g'] * p['L'] * math.sin(psi)
        N = mv * p['g'] * max(math.cos(psi), 0.0)
        nm = p['n_mot']
        Tm = nm * (p['k_i'] * i_a - p['B_m'] * w_m) - p['T_cm'] * math.tanh(w_m / 0.005)
        Jm = nm * p['J_m'] + p['J_m2']
        Tk = (-self.Tbrg * math.tanh(w_o / 1e-4) - p['B_o'] * w_o
              - p['T_unb'] * math.sin(th_o + p['phi_unb']))
        if p['T_step'] is not None and t >= p['T_step'][0]:
            Tk -= p['T_step'][1]
        n = p['n']
        Tneed = 0.0
        dphi = 0.0
        if self.rigid:
            Jeq = n * n * Jm + p['J_o']
            Tdrv = n * Tm + Tk
            if self.mode in ('stick', 'held'):
                a_o = (Tdrv - Tg) / (Jeq + p['J_v'])
                a_b = a_o
                Tneed = p['J_v'] * a_o + Tg
            else:
                Tw = p['mu_c'] * N * p['R'] * (1 if self.mode == 'slip_pos' else -1)
                a_o = (Tdrv - Tw) / Jeq
                a_b = (-Tg + Tw) / p['J_v']
            a_m = n * a_o
        else:
            dphi = w_m / n - w_o
            Ts = p['k_po'] * phi_s + p['C_po'] * dphi
            a_m = (Tm - Ts / n) / Jm
            Tko = Tk + Ts
            if self.mode in ('stick', 'held'):
                a_o = (Tko - Tg) / (p['J_o'] + p['J_v'])
                a_b = a_o
                Tneed = p['J_v'] * a_o + Tg
            else:
                Tw = p['mu_c'] * N * p['R'] * (1 if self.mode == 'slip_pos' else -1)
                a_o = (Tko - Tw) / p['J_o']
                a_b = (-Tg + Tw) / p['J_v']
        dwm = (w_m - w_meas) / p['tau_s'] if p['tau_s'] else 0.0
        d = np.array([dz, dx_a, a_m, a_o, a_b, w_b, dphi, dwm, w_o])
        return d, Tneed, N, i_a

    def rhs(self, t, x):
        return self.forces(t, x)[0]

    def guard(self, t, x):
        """positive while the current mode is valid."""
        p = self.p
        d, Tneed, N, _ = self.forces(t, x)
        psi = x[5]
        if self.mode == 'stick':
            if p['law'] == 'torque':
                return (p['mu_s'] * N * p['R'] - abs(Tneed)) / 1e4
            return (p['mu_s'] * math.cos(psi) - abs(math.sin(psi)))
        if self.mode == 'held':
            return (p['mu_c'] * N * p['R'] - abs(Tneed)) / 1e4
        vrel = x[3] - x[4]
        return vrel / 0.01 if self.mode == 'slip_pos' else -vrel / 0.01

    def next_mode(self, t, x):
        p = self.p
        m0 = self.mode
        if m0 in ('stick', 'held'):
            if m0 == 'stick' and p['law'] == 'paper':
                # printed law broke: slip only if kinetic friction cannot hold it
                self.mode = 'held'
                if self.guard(t, x) > 0:
                    return 'held'
            d, Tneed, N, _ = self.forces(t, x)
            return 'slip_pos' if Tneed > 0 else 'slip_neg'
        # re-stick attempt
        for m in ('stick', 'held'):
            if m == 'held' and p['law'] == 'torque':
                continue
            self.mode = m
            if self.guard(t, x) > 1e-9:
                return m
        return 'slip_neg' if m0 == 'slip_pos' else 'slip_pos'

    def step(self, t, x, h):
        k1 = self.rhs(t, x)
        k2 = self.rhs(t + h / 2, x + h / 2 * k1)
        k3 = self.rhs(t + h / 2, x + h / 2 * k2)
        k4 = self.rhs(t + h, x + h * k3)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def run(self, t_end, dt=5e-4):
        p = self.p
        x = np.zeros(9)
        t = 0.0
        breaks = sorted(set(tt for tt, _ in p['ref']))
        T, I, W, M = [0.0], [0.0], [0.0], [0.0]
        events = []
        while t < t_end - 1e-12:
            h = min(dt, t_end - t)
            for b in breaks:
                if t + 1e-12 < b < t + h:
                    h = b - t
            g0 = self.guard(t, x)
            x1 = self.step(t, x, h)
            g1 = self.guard(t + h, x1)
            if g1 < 0 <= g0 or (g0 < 0 and g1 < 0 and abs(g1) > 0):
                lo, hi = 0.0, h
                for _ in range(40):
                    mid = 0.5 * (lo + hi)
                    if self.guard(t + mid, self.step(t, x, mid)) >= 0:
                        lo = mid
                    else:
                        hi = mid
                x = self.step(t, x, hi)
                t = t + hi
                m0 = self.mode
                self.mode = self.next_mode(t, x)
                events.append((t, m0, self.mode))
            else:
                x, t = x1, t + h
            _, _, _, i_a = self.elec(t, x)
            T.append(t); I.append(i_a)
            W.append((x[7] if p['tau_s'] else x[2]) * p['K'])
            M.append(x[2] * p['K'])
        return dict(t=np.array(T), i=np.array(I), w=np.array(W), w_shaft=np.array(M), events=events)


def sample(out, ts):
    return np.interp(ts, out['t'], out['i']), np.interp(ts, out['t'], out['w'])


def kiln_B():
    """A larger cement kiln, 5.2 m shell, dual-pinion 2 x DC motor drive (one motor logged)."""
    R = 2.6
    m_v = 900e3
    M_shell = 2.4e6
    p = kiln_A()
    p.update(
        R_a=0.012, L_a=0.8e-3, k_i=7.0, k_b=7.0, J_m=45.0, B_m=0.01,
        k_p=1.5, k_I=4.0, k_D=0.004, V_max=650.0, I_max=1500.0,
        n=1800.0,
        J_o=0.88 * M_shell * R ** 2, J_v=0.614 * m_v * R ** 2, m_v=m_v,
        L=1.65, R=R, P=M_shell * 9.81, l_brg=0.8, k_brg=0.6,
        ref=[(0.0, 0.0), (1.0, 0.0), (16.0, 750.0)],
    )
    return p
