"""The motor-side Coulomb friction (kilnctl/model/motor_friction.py), against hand-derived truths.

Truths: the torque balance of the motor shaft at constant speed (the current rises by T_cm/k_i), the
breakaway condition of Coulomb friction (the shaft stays at rest until k_i*i_a = T_cm when nothing else
loads it at standstill), and the hybrid plant itself for the optimizer's smooth twin.
"""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.model import component_names
from kilnctl.simulate import simulate

FRICTION = "motor_coulomb_friction"


def _run(p, add=(), remove=("burden",), t_end=25.0, model="macro"):
    return simulate(p, components=component_names(model, add, remove), t_end=t_end)


@pytest.mark.parametrize("model", ["macro", "micro"])
def test_current_rises_by_T_cm_over_k_i_at_constant_speed(model):
    # hand formula: at constant speed the shaft's torque balance k_i*i_a = B_m*w + T_load/n gains T_cm, so
    # i_a rises by T_cm/k_i (8.696 A with 40 N*m and k_i = 4.6 N*m/A); the integrator holds the speed at
    # the reference in both runs. The burden is taken out so that nothing oscillates at steady speed.
    p = Parameters(T_cm=40.0)
    base, fric = _run(p, model=model), _run(p, (FRICTION,), model=model)
    last = fric.t >= fric.t[-1] - 2.0
    assert fric["speed_rpm"][last] == pytest.approx(p.omega_ref, rel=1e-6)
    rise = fric["i_a"][-1] - base["i_a"][-1]
    assert rise == pytest.approx(p.T_cm / p.k_i, rel=1e-6)  # seen: 8.695652 A both models, to 1e-12
    assert np.all(fric.outputs["T_fm"][last] == -p.T_cm)  # slipping forwards: the full T_cm against it


def test_shaft_sticks_until_the_drive_torque_reaches_T_cm():
    # Coulomb friction: with the burden at bottom dead centre (no gravity torque) and the kiln at rest (the
    # bearing torque's tanh is zero), the shaft stays exactly at rest until k_i*i_a reaches T_cm, then breaks
    # away forwards; without the friction it turns from the first instant
    p = Parameters(T_cm=200.0, psi_0=0.0)
    r = simulate(p, components=component_names("macro", (FRICTION,)), t_end=1.0)
    away = [e for e in r.events if e.component == FRICTION]
    assert away and away[0].from_mode == "stick" and away[0].to_mode == "slip_pos"
    t_b = away[0].t
    assert t_b > 0.0
    before = r.t < t_b
    assert np.all(np.abs(r["speed_rpm"][before]) < 1e-9)  # at rest to round-off
    assert np.interp(t_b, r.t, r["i_a"]) * p.k_i == pytest.approx(p.T_cm, rel=2e-3)
    assert r["speed_rpm"][-1] > 0.0
    free = _run(p, remove=(), t_end=1.0)
    assert free["speed_rpm"][np.searchsorted(free.t, 0.5 * t_b)] > 0.0


def test_ramp_optimizer_takes_the_smooth_twin_and_agrees_with_the_hybrid_verification():
    # the effect has modes, so the optimizer's smooth model carries its twin (tanh over 0.01 rad/s) and the
    # verification the hybrid component; truth: the hybrid micro plant, on the same 74 rpm/s ramp, whose
    # peak dynamic stress and peak current the smooth model must predict to 1 %
    from kilnctl.optimize import RampProblem, measure_hybrid
    from kilnctl.optimize.model import SmoothStartup, hybrid_components, smooth_components
    from kilnctl.optimize.problem import Profile
    from kilnctl.optimize.verify import measure_arrays
    from kilnctl.simulate import resolve_gains

    prof = Profile.parse("constant")
    assert "motor_coulomb_friction_smooth" in smooth_components(prof, (FRICTION,))
    assert FRICTION in hybrid_components(prof, (FRICTION,))
    assert RampProblem(Parameters(), effects=(FRICTION,)).effects == (FRICTION,)
    p = resolve_gains(Parameters(T_cm=200.0))
    horizon = 12.0
    hyb, _ = measure_hybrid(p, prof, [74.0], horizon, effects=(FRICTION,))
    sm = SmoothStartup(prof, p, effects=(FRICTION,))
    grid = np.linspace(1e-3, horizon, 6001)
    o = sm.run(p, [74.0], {"smooth_ds": 1e-6, "smooth_v": 1e-4, "ramp_corner": 0.05}, grid)
    pred = measure_arrays(o["t"], o["sigma"], o["sigma_dyn"], o["i_a"], o["e_a"], o["speed_rpm"], p.omega_ref)
    assert pred.peak_dynamic_stress_Pa == pytest.approx(hyb.peak_dynamic_stress_Pa, rel=0.01)
    assert pred.peak_current_A == pytest.approx(hyb.peak_current_A, rel=0.01)
    plain, _ = measure_hybrid(p, prof, [74.0], horizon)
    assert hyb.peak_current_A > plain.peak_current_A  # the friction adds to the current


@pytest.mark.parametrize("a_cm", [0.5, 1.0])
def test_the_falling_form_loses_a_cm_of_the_friction_at_the_set_speed(a_cm):
    # hand formula: the falling form's friction on the turning shaft is T_cm (1 - a_cm w/w_set); at constant
    # speed (w = w_set) the current rises by T_cm (1 - a_cm)/k_i over the run without friction, and on the ramp,
    # where the speed follows the reference as in the run without friction, by T_cm (1 - a_cm w(t)/w_set)/k_i
    p = Parameters(T_cm=100.0, a_cm=a_cm)
    base = _run(p)
    fall = _run(p, (FRICTION, "motor_friction_falloff"))
    assert fall["i_a"][-1] - base["i_a"][-1] == pytest.approx(p.T_cm * (1.0 - a_cm) / p.k_i, abs=1e-6)
    k = np.searchsorted(fall.t, 4.0)  # on the ramp (it ends at 1 + 500/74 = 7.8 s)
    expected = p.T_cm * (1.0 - a_cm * fall["speed_rpm"][k] / p.omega_ref) / p.k_i
    assert fall["i_a"][k] - base["i_a"][k] == pytest.approx(expected, rel=1e-3)  # seen: 9.5838 A for 9.5839


def test_the_building_form_is_dahls_friction_on_a_shaft_turning_one_way():
    # hand formula (Dahl 1968): dT/dtheta = sigma (1 - T/T_cm) for a shaft turning one way from rest, T(0) = 0,
    # gives T = T_cm (1 - exp(-theta sigma/T_cm)) with theta the angle turned; the form's theta_cm is T_cm/sigma.
    # Checked along the run against the angle the motor has turned, integrated from the logged speed by the
    # trapezoid rule (a second method), and no sticking: the shaft turns from the first instants, as without
    # friction (red team 21's E7: T_cm 420 N*m, sigma 600 N*m/rad, no stiction)
    from scipy.integrate import cumulative_trapezoid

    p = Parameters(T_cm=420.0, theta_cm=420.0 / 600.0)
    r = _run(p, ("motor_friction_building",), t_end=6.0)
    w = r["speed_rpm"] * np.pi / 30.0
    theta = cumulative_trapezoid(w, r.t, initial=0.0)
    dahl = -p.T_cm * (1.0 - np.exp(-theta / p.theta_cm))
    turning = w > 1.0  # rad/s: away from the tanh's 0.01 rad/s
    assert turning.sum() > 100
    np.testing.assert_allclose(r.outputs["T_fm"][turning], dahl[turning], atol=0.5)  # N*m of 420
    # built up after a few theta_cm: the full T_cm against the shaft
    assert r.outputs["T_fm"][-1] == pytest.approx(-p.T_cm, rel=1e-6)
    # no sticking: it turns when the run without friction does
    free = _run(p, t_end=6.0)
    k = np.searchsorted(r.t, 1.2)
    assert r["speed_rpm"][k] > 0.5 * free["speed_rpm"][k] > 0.0
