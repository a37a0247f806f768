"""The current limit's Filippov sliding mode (model/drive.py CurrentLimit, Eqs.equivalent_control).

A fast ramp against a heavy burden: freezing the integrator at the limit makes the unlimited current fall
at once, running it makes the current rise again. Before the sliding mode both engines ended in an
EventStormError here (or chattered through 150 switches). Truths: Filippov's convex combination (the
held current stays at I_max and the integrator runs at a fraction u in [0, 1] of e_f, read off the
states), and the CVODES engine (a second integrator and event locator) at tight tolerance.
"""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.simulate import simulate

P = Parameters(friction_law="paper", m_v=555075.678517009, J_v=523161.8090332165, mu_c=0.302597173055968,
               mu_s=0.377273852425816, ramp_rate=2437.3349940802864, J_m2=20.700587583206815,
               tau_s=0.11349160406610875)
EFFECTS = ["second_motor", "speed_sensor_lag"]


def test_sliding_at_the_current_limit_is_a_convex_combination():
    r = simulate(P, "macro", 1.0, effects=EFFECTS, dt=1e-3)
    slide = r.modes["current_limit"] == "slide_upper"
    assert slide.sum() > 20  # it slides for tens of milliseconds
    assert np.allclose(r.outputs["i_a"][slide], P.I_max, rtol=1e-9)
    t, z = r.t[slide], r.states["z"][slide]
    e_f = r.outputs["speed_ref_rpm"][slide] - P.K_fb * r.states["omega_meas"][slide]
    keep = np.diff(t) > 1e-6  # event points stand twice (before and after the switch)
    dz = np.diff(z)[keep] / np.diff(t)[keep]
    u = dz / (0.5 * (e_f[1:] + e_f[:-1]))[keep]
    assert np.all(u > -1e-3) and np.all(u < 1 + 1e-3)  # partly integrating: neither frozen nor free
    assert 0.05 < np.median(u) < 0.95


def test_both_engines_take_the_same_path_through_the_limit():
    a = simulate(P, "macro", 30.0, effects=EFFECTS)
    b = simulate(P, "macro", 30.0, effects=EFFECTS, method="cvodes", rtol=1e-10, atol=1e-11)
    assert [(e.kind, e.to_mode) for e in a.events] == [(e.kind, e.to_mode) for e in b.events]
    assert np.allclose([e.t for e in a.events], [e.t for e in b.events], atol=2e-4 * len(a.events))
    assert a.outputs["i_a"][-1] == pytest.approx(b.outputs["i_a"][-1], rel=5e-3)
