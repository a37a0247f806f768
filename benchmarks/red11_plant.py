"""Red team 11: an independent rotary-kiln start-up plant (numpy/scipy only), written by a helper that did not
read kilnctl's code (2026-11-27, fifth session); kept as written.  Its cascade drive (a PI speed loop over a PI
current loop) and its inching drive are outside kilnctl's model: tests/test_red11_plant.py.

Written from van Dyk & Pretorius (1994), NOTES.md and docs/model_reference.md (equations
only).  Integration: scipy solve_ivp (RK45, max_step 2 ms) between reference corners,
with terminal events for the burden's mode guards (stick / held / slip+ / slip-).

Controllers:
  'pid'      : the paper's eq. 21 (speed PID, k_D realised through L_a), voltage clamp
               with conditional integration.
  'cascade'  : PI speed controller -> current reference (clamped to I_max) -> PI current
               loop -> armature voltage (clamped).  NOT kilnctl's model.
Extras (all keys of the dict P):
  motors        number of identical powered motors, fed alike (logged: one motor's current)
  J_m2          extra inertia on the motor shaft
  B_o           viscous drag on the kiln
  T_unb,phi_unb once-per-revolution kiln torque -T_unb sin(theta_o + phi_unb)
  T_cm          motor Coulomb friction (smooth, tanh(w/0.01))
  tau_s         first-order speed sensor lag (controller and log)
  k_po,C_po     drive-train spring-damper at the kiln axis (None: rigid)
  inch          (w_target_rpm, Kc, t_on) inching drive on the motor shaft through an
                overrunning clutch; the main drive is off until t_on
"""
import math
import numpy as np
from scipy.integrate import solve_ivp

KFB = 60.0 / (2.0 * math.pi)


def table1(**kw):
    P = dict(R_a=0.00961, L_a=0.00057, k_i=4.6, k_b=4.6, J_m=21.5, B_m=0.005,
             k_p=2.0, k_I=5.0, k_D=0.01, V_max=500.0, I_max=1500.0,
             n=1076.5, J_o=6.978e6, J_v=1.678e6, m_v=580e3, L=1.353, R=2.17,
             mu_c=0.4, mu_s=0.51, g=9.81, mu_brg=0.001, P=16.512e6,
             l_brg=0.7155, k_brg=0.5475, law='paper',
             ref=[(0.0, 0.0), (1.0, 0.0), (1.0 + 500 / 74.0, 500.0)],
             ctrl='pid', Kps=6.0, Kis=15.0, Kpc=0.17, Kic=3.0,
             motors=1, J_m2=0.0, B_o=0.0, T_unb=0.0, phi_unb=0.0, T_cm=0.0,
             tau_s=None, k_po=None, C_po=0.0, inch=None)
    P.update(kw)
    return P


def kiln_D(**kw):
    """My own 4.0 m cement kiln, one 400 kW DC motor, 750 rpm, n = 1400."""
    R = 2.0
    m_v = 400e3
    M = 1.2e6
    P = table1(R_a=0.015, L_a=0.8e-3, k_i=5.0, k_b=5.0, J_m=12.0, B_m=0.004,
               k_p=1.5, k_I=4.0, k_D=0.005, V_max=480.0, I_max=1200.0,
               n=1400.0, J_o=0.9 * M * R * R, J_v=0.6 * m_v * R * R, m_v=m_v,
               L=1.25, R=R, mu_c=0.38, mu_s=0.48, P=(M + m_v) * 9.81,
               l_brg=0.60, k_brg=0.45,
               ref=[(0.0, 0.0), (1.0, 0.0), (1.0 + 750 / 60.0, 750.0)])
    P.update(kw)
    return P


def kiln_E(**kw):
    """Kiln D driven by two 200 kW motors on two pinions (per-motor nameplate)."""
    P = kiln_D(R_a=0.025, L_a=1.2e-3, k_i=3.0, k_b=3.0, J_m=7.0, B_m=0.003,
               k_p=0.8, k_I=2.0, k_D=0.004, V_max=300.0, I_max=800.0, motors=2)
    P.update(kw)
    return P


class Sim:
    # x = [z, xa, w_m, w_o, w_b, psi, phi_s, w_meas, th_o, zc]
    def __init__(self, P):
        self.P = P
        self.Tbrg = 2 * P['mu_brg'] * (P['P'] / 2) * math.cos(math.pi / 6) * (P['l_brg'] + P['k_brg']) / 2
        self.mode = 'stick'
        self.on_t = P['inch'][2] if P['inch'] else -1e9

    def ref(self, t):
        r = self.P['ref']
        ts = [a for a, _ in r]
        vs = [b for _, b in r]
        return float(np.interp(t, ts, vs))

    def drive(self, t, x):
        """returns (i_a, dz, dxa, dzc)."""
        P = self.P
        z, xa, w_m, w_meas, zc = x[0], x[1], x[2], x[7], x[9]
        if t < self.on_t:
            return 0.0, 0.0, 0.0, 0.0
        wfb = w_meas if P['tau_s'] else w_m
        ef = self.ref(t) - KFB * wfb
        if P['ctrl'] == 'pid':
            u = P['k_p'] * ef + P['k_I'] * z
            sat = 0
            if u > P['V_max']:
                u, sat = P['V_max'], 1
            elif u < -P['V_max']:
                u, sat = -P['V_max'], -1
            ia = xa + P['k_D'] / P['L_a'] * ef
            dz = 0.0 if sat * ef > 0 else ef
            dxa = (u - P['R_a'] * ia - P['k_b'] * w_m) / P['L_a']
            return ia, dz, dxa, 0.0
        # cascade: xa is the current itself
        ia = xa
        iref = P['Kps'] * ef + P['Kis'] * z
        s1 = 0
        if iref > P['I_max']:
            iref, s1 = P['I_max'], 1
        elif iref < -P['I_max']:
            iref, s1 = -P['I_max'], -1
        dz = 0.0 if s1 * ef > 0 else ef
        ec = iref - ia
        u = P['Kpc'] * ec + P['Kic'] * zc
        s2 = 0
        if u > P['V_max']:
            u, s2 = P['V_max'], 1
        elif u < -P['V_max']:
            u, s2 = -P['V_max'], -1
        dzc = 0.0 if s2 * ec > 0 else ec
        dxa = (u - P['R_a'] * ia - P['k_b'] * w_m) / P['L_a']
        return ia, dz, dxa, dzc

    def dyn(self, t, x):
        P = self.P
        ia, dz, dxa, dzc = self.drive(t, x)
        w_m, w_o, w_b, psi, phi_s, w_meas, th_o = x[2], x[3], x[4], x[5], x[6], x[7], x[8]
        nm = P['motors']
        Tm = nm * (P['k_i'] * ia - P['B_m'] * w_m) - P['T_cm'] * math.tanh(w_m / 0.01)
        if P['inch']:
            wt = P['inch'][0] / KFB
            Tm += max(0.0, P['inch'][1] * (wt - w_m))
        Jm = nm * P['J_m'] + P['J_m2']
        Tk = -self.Tbrg * math.tanh(w_o / 1e-4) - P['B_o'] * w_o - P['T_unb'] * math.sin(th_o + P['phi_unb'])
        Tg = P['m_v'] * P['g'] * P['L'] * math.sin(psi)
        N = P['m_v'] * P['g'] * max(math.cos(psi), 0.0)
        n = P['n']
        stuck = self.mode in ('stick', 'held')
        Tw = 0.0
        if not stuck:
            Tw = P['mu_c'] * N * P['R'] * (1.0 if self.mode == 'slip+' else -1.0)
        if P['k_po'] is None:
            Jk = n * n * Jm + P['J_o']
            Tin = n * Tm + Tk
            if stuck:
                ao = (Tin - Tg) / (Jk + P['J_v'])
                ab = ao
                Tneed = P['J_v'] * ao + Tg
            else:
                ao = (Tin - Tw) / Jk
                ab = (Tw - Tg) / P['J_v']
                Tneed = 0.0
            am = n * ao
            dphi = 0.0
        else:
            dphi = w_m / n - w_o
            Ts = P['k_po'] * phi_s + P['C_po'] * dphi
            am = (Tm - Ts / n) / Jm
            if stuck:
                ao = (Ts + Tk - Tg) / (P['J_o'] + P['J_v'])
                ab = ao
                Tneed = P['J_v'] * ao + Tg
            else:
                ao = (Ts + Tk - Tw) / P['J_o']
                ab = (Tw - Tg) / P['J_v']
                Tneed = 0.0
        dwmeas = (w_m - w_meas) / P['tau_s'] if P['tau_s'] else 0.0
        d = np.array([dz, dxa, am, ao, ab, w_b, dphi, dwmeas, w_o, dzc])
        return d, Tneed, N, ia

    def rhs(self, t, x):
        return self.dyn(t, x)[0]

    def guard(self, t, x, mode=None):
        P = self.P
        m0 = self.mode
        if mode is not None:
            self.mode = mode
        _, Tneed, N, _ = self.dyn(t, x)
        m = self.mode
        self.mode = m0
        psi = x[5]
        if m == 'stick':
            if P['law'] == 'torque':
                return (P['mu_s'] * N * P['R'] - abs(Tneed)) / 1e5
            return P['mu_s'] * math.cos(psi) - abs(math.sin(psi))
        if m == 'held':
            return (P['mu_c'] * N * P['R'] - abs(Tneed)) / 1e5
        v = x[3] - x[4]
        return (v if m == 'slip+' else -v) / 1e-3

    def switch(self, t, x):
        m0 = self.mode
        if m0 in ('stick', 'held'):
            if m0 == 'stick' and self.P['law'] == 'paper' and self.guard(t, x, 'held') > 0:
                return 'held'
            _, Tneed, _, _ = self.dyn(t, x)
            return 'slip+' if Tneed > 0 else 'slip-'
        # slipping, relative speed reached zero
        if self.guard(t, x, 'stick') > 1e-9:
            return 'stick'
        if self.P['law'] == 'paper' and self.guard(t, x, 'held') > 1e-9:
            return 'held'
        return 'slip-' if m0 == 'slip+' else 'slip+'

    def run(self, t_end, x0=None, mode0='stick', dt_out=0.002, t_start=0.0):
        P = self.P
        x = np.zeros(10) if x0 is None else np.array(x0, float)
        self.mode = mode0
        brk = sorted(set([a for a, _ in P['ref']] + ([self.on_t] if P['inch'] else [])))
        brk = [b for b in brk if t_start < b < t_end] + [t_end]
        t = t_start
        T, I, W, EV = [], [], [], []
        def rec(ts, xs):
            for k in range(len(ts)):
                ia = self.drive(ts[k], xs[:, k])[0]
                T.append(ts[k]); I.append(ia)
                W.append(KFB * (xs[7, k] if P['tau_s'] else xs[2, k]))
        rec(np.array([t]), x[:, None])
        nsw = 0
        for b in brk:
            while t < b - 1e-12:
                def ev(tt, xx):
                    return self.guard(tt, xx)
                ev.terminal = True
                ev.direction = -1
                grid = np.arange(math.floor(t / dt_out) + 1, math.floor(b / dt_out) + 1) * dt_out
                grid = grid[(grid > t) & (grid <= b)]
                sol = solve_ivp(self.rhs, (t, b), x, method='RK45', max_step=0.002,
                                rtol=1e-7, atol=1e-9, events=ev, dense_output=True)
                tend = sol.t[-1]
                g = grid[grid <= tend]
                if len(g):
                    rec(g, sol.sol(g))
                x = sol.y[:, -1].copy()
                t = tend
                if sol.status == 1:
                    new = self.switch(t, x)
                    EV.append((t, self.mode, new))
                    self.mode = new
                    nsw += 1
                    if nsw > 20000:
                        raise RuntimeError('event storm')
                    # nudge past the guard
                    if self.guard(t, x) <= 0:
                        x = x + 1e-7 * self.rhs(t, x)
                        t = t + 1e-7
        return dict(t=np.array(T), i=np.array(I), w=np.array(W), ev=EV, x=x, mode=self.mode)


def noise(n, dt, rng, white, ar, tau):
    a = math.exp(-dt / tau)
    e = rng.standard_normal(n) * ar * math.sqrt(1 - a * a)
    y = np.zeros(n)
    y[0] = rng.standard_normal() * ar
    for k in range(1, n):
        y[k] = a * y[k - 1] + e[k]
    return y + white * rng.standard_normal(n)


def fitpct(y, yh):
    return 100.0 * (1 - np.linalg.norm(y - yh) / np.linalg.norm(y - y.mean()))
