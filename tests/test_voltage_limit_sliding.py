"""The voltage limit's Filippov sliding mode (model/drive.py VoltageLimit, Eqs.equivalent_control).

A slowly ringing speed filter (zeta_s 0.32, tau_s 131 ms) on a fast ramp: when the PI voltage reaches
V_max, freezing the integrator brings it back below the limit at once while running it pushes it above
again. Before the sliding mode both engines refused the run ("voltage_limit switches between modes
['free', 'upper'] without time passing": point 203 of the differential search over the new structures).
Truths: Filippov's convex combination, read off the states by hand (the PI voltage k_p e_f + k_I z stays
at V_max, and the integrator runs at a fraction u in [0, 1] of e_f), and the CVODES engine (a second
integrator and event locator) at tight tolerance.
"""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.simulate import resolve_gains, simulate

P = Parameters(friction_law="torque", m_v=579618.5473819016, J_v=977578.5034574254, mu_c=0.28505685192180075,
               mu_s=0.3340752941762585, ramp_rate=884.2617572025134, tau_s=0.13147607781709297,
               zeta_s=0.3161500289915766, I_max=1836.7811048514338)
EFFECTS = ["speed_sensor_filter", "current_limit"]


def test_sliding_at_the_voltage_limit_is_a_convex_combination():
    r = simulate(P, "macro", 8.0, effects=EFFECTS, dt=1e-3)
    slide = r.modes["voltage_limit"] == "slide_upper"
    assert slide.sum() > 20  # it slides for tens of milliseconds (7.832-7.871 s)
    t, z = r.t[slide], r.states["z"][slide]
    e_f = r.outputs["speed_ref_rpm"][slide] - P.K_fb * r.states["omega_meas"][slide]
    # the PI voltage, from the states by hand with the gains the run used, held at the limit (and the clamp
    # gives the motor V_max)
    g = resolve_gains(P)
    assert np.allclose(g.k_p * e_f + g.k_I * z, P.V_max, rtol=1e-7)
    assert np.allclose(r.outputs["e_a"][slide], P.V_max)
    keep = np.diff(t) > 1e-6  # event points stand twice (before and after the switch)
    dz = np.diff(z)[keep] / np.diff(t)[keep]
    u = dz / (0.5 * (e_f[1:] + e_f[:-1]))[keep]
    assert np.all(u > -1e-3) and np.all(u < 1 + 1e-3)  # partly integrating: neither frozen nor free
    assert 0.05 < np.median(u) < 0.95


def test_both_engines_take_the_same_path_through_the_voltage_limit():
    a = simulate(P, "macro", 13.0, effects=EFFECTS)
    b = simulate(P, "macro", 13.0, effects=EFFECTS, method="cvodes", rtol=1e-10, atol=1e-11)
    path = [(e.kind, e.to_mode) for e in a.events if e.component == "voltage_limit"]
    assert ("voltage_limit_release", "slide_upper") in path
    assert [(e.kind, e.to_mode) for e in a.events] == [(e.kind, e.to_mode) for e in b.events]
    assert np.allclose([e.t for e in a.events], [e.t for e in b.events], atol=2e-4)
    assert a.outputs["i_a"][-1] == pytest.approx(b.outputs["i_a"][-1], rel=5e-3)
