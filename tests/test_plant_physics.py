"""The nonlinear plant against independent truths: analytic mechanics and energy.

Each test names its truth: an exact energy balance, a hand linearisation, a
conservation law, or a number from the paper.
"""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from kilnctl import Parameters
from kilnctl.simulate import simulate

PENDULUM = ("kiln", "kiln_fixed", "burden")


def _turning_points(r):
    """Burden angles at the re-stick events (turning points of the swing)."""
    t = list(r.t)
    return [float(r["psi"][t.index(e.t)]) for e in r.events if e.kind == "restick"]


def test_coulomb_pendulum_exact_energy_decrement():
    # Truth: energy balance between turning points a -> b with kinetic wall torque mu_c*m*g*R*cos(psi):
    #   L*(cos b - cos a) = mu_c*R*|sin b - sin a|   (exact, any amplitude: potential lost = work of friction)
    p = Parameters(mu_c=0.005, mu_s=0.05, psi_0=0.3)
    r = simulate(p, components=PENDULUM, t_end=40.0, dt=1e-3, rtol=1e-10, atol=1e-11)
    tp = [p.psi_0] + _turning_points(r)
    assert len(tp) >= 4
    for a, b in zip(tp[:-1], tp[1:]):
        f = lambda x: p.L * (math.cos(x) - math.cos(a)) - p.mu_c * p.R * abs(math.sin(x) - math.sin(a))
        exact = brentq(f, -abs(a) + 1e-12, 0.0) if a > 0 else brentq(f, 0.0, abs(a) - 1e-12)
        assert b == pytest.approx(exact, abs=1e-7)


def test_coulomb_pendulum_small_angle_decrement_and_static_band():
    # Truth (small angles): each half swing loses 2*mu_c*R/L of amplitude; the burden sticks at the
    # first turning point inside the printed static band |tan psi| <= mu_s (eq. 3).
    p = Parameters(mu_c=0.005, mu_s=0.05, psi_0=0.1)
    r = simulate(p, components=PENDULUM, t_end=30.0, dt=1e-3)
    tp = [p.psi_0] + _turning_points(r)
    dec = [abs(a) - abs(b) for a, b in zip(tp[:-1], tp[1:])]
    assert np.allclose(dec, 2 * p.mu_c * p.R / p.L, rtol=2e-3)
    assert r.burden_mode[-1] == "stick"
    assert abs(math.tan(tp[-1])) <= p.mu_s
    assert all(abs(math.tan(a)) > p.mu_s for a in tp[:-1])
    # half period of the swing: pi / sqrt(C1/J_v) (eq. 25, C1 = m_v*g*L)
    rest = [e.t for e in r.events if e.kind == "restick"]
    w = math.sqrt(p.m_v * p.g * p.L / p.J_v)
    assert np.diff([0.0] + rest) == pytest.approx(math.pi / w, rel=2e-3)


def test_torque_law_static_band_is_wider():
    # Truth: with the torque-consistent law the band is tan(psi) <= mu_s*R/L: released inside it, no motion.
    p = Parameters(mu_c=0.3, mu_s=0.35, psi_0=0.45, friction_law="torque")  # tan 0.45 = 0.483 < 0.35*R/L = 0.561
    r = simulate(p, components=PENDULUM, t_end=5.0, dt=1e-2)
    assert r.events == [] and np.allclose(r["psi"], 0.45)
    r2 = simulate(p.replace(friction_law="paper"), components=PENDULUM, t_end=5.0, dt=1e-2)
    assert r2.events[0].kind == "breakaway" and r2.events[0].t == 0.0  # tan 0.45 > mu_s: the printed law lets go
    # back at the turning point, kinetic friction holds it (tan psi < mu_c*R/L): Filippov sliding mode
    assert (r2.events[-1].kind, r2.events[-1].to_mode) == ("sliding_mode", "held")


def test_sliding_oscillation_frequency_eq25():
    # Truth: while the wall outruns the burden (sign of v_rel fixed), eq. 22 holds:
    #   J_v psi'' = -m g L sin psi + mu_c m g R cos psi,
    # equilibrium tan psi* = mu_c R / L, exact linearisation w^2 = m g sqrt(L^2 + (mu_c R)^2) / J_v;
    # the paper's small-angle eq. 25 gives sqrt(C1/J_v) = 2.14 rad/s (NOTES.md).
    p = Parameters(J_o=1e13)  # kiln turns at constant speed
    psi_star = math.atan(p.mu_c * p.R / p.L)
    r = simulate(p, components=("kiln", "burden"), t_end=20.0, dt=1e-3,
                 initial={"omega_kiln": 1.0, "psi": psi_star + 0.005, "omega_burden": 0.0},
                 initial_mode={"burden": "slip_pos"})
    assert r.events == []  # v_rel keeps its sign: no re-stick
    d = r["psi"] - psi_star
    up = np.nonzero((d[:-1] < 0) & (d[1:] >= 0))[0]
    tc = r.t[up] - d[up] * (r.t[up + 1] - r.t[up]) / (d[up + 1] - d[up])
    w_meas = 2 * math.pi / np.mean(np.diff(tc))
    w_exact = math.sqrt(p.m_v * p.g * math.hypot(p.L, p.mu_c * p.R) / p.J_v)
    assert w_meas == pytest.approx(w_exact, rel=1e-4)
    w_eq25 = math.sqrt(p.m_v * p.g * p.L / p.J_v)
    assert w_eq25 == pytest.approx(2.14, abs=0.01)  # NOTES.md
    assert w_meas / w_eq25 == pytest.approx((1 + (p.mu_c * p.R / p.L) ** 2) ** 0.25, rel=1e-4)
    assert np.mean(d) == pytest.approx(0.0, abs=5e-4)  # oscillates about the fixed offset psi*


def test_energy_conserved_through_backlash_impacts():
    # Truth: with C_e = 0 the mesh is a lossless spring with a dead zone; kinetic + spring energy is
    # conserved across every contact and separation event.
    p = Parameters(C_e=0.0, delta_x=4e-3, gap_0=0.5, J_p=1500.0, J_o=2e5)
    r = simulate(p, components=("pinion", "mesh", "kiln"), t_end=0.5, dt=1e-4, rtol=1e-11, atol=1e-12,
                 initial={"omega_pinion": 2.0})
    kinds = {e.kind for e in r.events}
    assert {"contact", "separation"} <= kinds and len(r.events) >= 4
    ds = r["ds"]
    spring = np.where(ds > p.delta_x, ds - p.delta_x, np.where(ds < 0, ds, 0.0))
    E = 0.5 * p.J_p * r["omega_pinion"] ** 2 + 0.5 * p.J_o * r["omega_kiln"] ** 2 + 0.5 * p.k_e * spring ** 2
    assert np.ptp(E) / E[0] < 1e-5


@pytest.mark.parametrize("zeta", [0.05, 0.3, 0.7])
def test_mesh_damping_sets_the_restitution_of_an_impact(zeta):
    # Truth: the closed-form impact of a spring and a damper in parallel that cannot pull (W = max(k x + c x', 0),
    # x = Delta s - Delta x, mass m = 1 / (R_p^2/J_p + R_o^2/J_o) on Delta s): x(t) = v0/w_d exp(-zeta w_n t)
    # sin(w_d t) until the force is zero at t_s, then free flight, so the teeth part at -x'(t_s) = e v0.  This
    # is what the backlash's 'impact' form fits through C_e.
    p = Parameters(delta_x=4e-3, gap_0=1.0, J_p=1500.0, J_o=2e5)
    m = 1.0 / (p.R_p ** 2 / p.J_p + p.R_o ** 2 / p.J_o)
    w_n = math.sqrt(p.k_e / m)
    c = 2.0 * zeta * math.sqrt(p.k_e * m)
    w_d = w_n * math.sqrt(1.0 - zeta ** 2)

    def rate(t):  # x'(t) / v0
        return math.exp(-zeta * w_n * t) * (math.cos(w_d * t) - zeta * w_n / w_d * math.sin(w_d * t))

    def force(t):  # (k x + c x') / v0
        return p.k_e * math.exp(-zeta * w_n * t) * math.sin(w_d * t) / w_d + c * rate(t)

    e_exact = -rate(brentq(force, 1e-9, math.pi / w_d))
    r = simulate(p.replace(C_e=c), components=("pinion", "mesh", "kiln"), t_end=0.012, dt=1e-5, rtol=1e-10,
                 atol=1e-12, initial={"omega_pinion": 2.0})
    t = list(r.t)
    v = p.R_p * r["omega_pinion"] - p.R_o * r["omega_kiln"]  # closing speed of the teeth [m/s]
    hit = next(e for e in r.events if e.kind == "contact")
    part = next(e for e in r.events if e.kind == "separation" and e.t > hit.t)
    e_sim = -v[t.index(part.t)] / v[t.index(hit.t)]
    assert e_sim == pytest.approx(e_exact, rel=1e-4)
    assert 0.0 < e_exact < 1.0


def test_energy_conserved_frictionless_burden():
    # Truth: mu_c = mu_s = 0, kiln free: burden pendulum energy is conserved.
    p = Parameters(mu_c=0.0, mu_s=0.0, psi_0=0.4, friction_law="torque")
    r = simulate(p, components=("kiln", "burden"), t_end=10.0, dt=1e-3, rtol=1e-10, atol=1e-12)
    E = 0.5 * p.J_v * r["omega_burden"] ** 2 + p.m_v * p.g * p.L * (1 - np.cos(r["psi"])) \
        + 0.5 * p.J_o * r["omega_kiln"] ** 2
    assert np.ptp(E) / E[0] < 1e-6


def test_event_residuals_near_zero():
    # Truth: at each located event the guard is zero: mesh deflection at the backlash edge, relative
    # burden speed zero at re-stick.
    p = Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01, friction_law="torque")
    r = simulate(p, "micro", t_end=25.0)
    t = list(r.t)
    assert any(e.kind == "contact" for e in r.events) and any(e.kind == "restick" for e in r.events)
    for e in r.events:
        k = t.index(e.t)
        if e.kind in ("contact", "separation"):
            assert abs(r["ds"][k] - p.delta_x) < 1e-8
        if e.kind == "restick":
            assert abs(r["v_rel"][k]) < 1e-7


def test_printed_law_chattering_case_is_bounded():
    # Truth (NOTES.md): with the printed law, breakaway at tan psi = mu_s = 0.51 (27 deg) finds kinetic
    # friction able to hold the burden; a Filippov solution sticks (held) until tan psi = mu_c R/L = 0.642.
    p = Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01)
    r = simulate(p, "macro", t_end=30.0)
    assert len(r.events) < 10
    kinds = [(e.kind, e.to_mode) for e in r.events if e.component == "burden"]
    assert ("sliding_mode", "held") in kinds
    t = list(r.t)
    brk = [e for e in r.events if e.component == "burden" and e.kind == "breakaway"]
    assert math.tan(r["psi"][t.index(brk[0].t)]) == pytest.approx(p.mu_s, abs=1e-6)
    assert math.tan(r["psi"][t.index(brk[1].t)]) == pytest.approx(p.mu_c * p.R / p.L, rel=1e-3)
    assert r.burden_mode[-1] == "slip_pos"


def test_macro_tooth_force_is_the_reducer_torque_while_sticking():
    # Truth (eq. 9 and a free-body of the motor shaft): the girth gear receives
    # n*(k_i*i_a - B_m*omega_m - J_m*domega_m/dt); at constant speed W_t = n*(k_i*i_a - B_m*omega_m)/R_o.
    p = Parameters(gains="given", k_p=0.08, k_I=2.2, k_D=0.014, friction_law="torque")
    r = simulate(p, "macro", 17.0, dt=1e-3)
    k = np.searchsorted(r.t, 16.0)
    assert r.burden_mode[k] == "stick"
    w = r["omega_motor"][k]
    hand = p.n * (p.k_i * r["i_a"][k] - p.B_m * w) / p.R_o
    assert r["W_t"][k] == pytest.approx(hand, rel=2e-3)  # speed nearly constant: J_m*dw/dt is small
    assert r["sigma"][k] == pytest.approx(r["W_t"][k] / (p.face_width * p.module * p.Y_lewis))


def test_response_lists_its_components():
    r = simulate(Parameters(gains="given", k_p=0.08, k_I=2.2, k_D=0.014), "macro", 1.0, effects=("second_motor",))
    assert "second_motor" in r.components and "burden" in r.components
