"""Start-up ramp optimization against independent truths.

Truths used, test by test: analytic properties of the reference profiles
(closed forms); the exact hybrid plant (kilnctl.simulate) for the smooth
model and for the optimum (a brute-force bisection and grid on the hybrid
plant); central finite differences and CasADi's own CVODES sensitivities for
the hand-written sensitivity equations; a second transcription for the first.
"""

import math

import casadi as ca
import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import OptimizationError, ParameterError
from kilnctl.model.ramps import pwl_reference, scurve_reference, scurve_timing
from kilnctl.model.smooth import SMOOTH_DS
from kilnctl.optimize import DEFAULT_STAGES, Profile, RampProblem, RampSolveError, Stage, optimize_ramp
from kilnctl.optimize.model import SmoothStartup
from kilnctl.optimize.sensitivity import SensitivityRun
from kilnctl.optimize.transcription import TimeGrid, objective_quadrature
from kilnctl.optimize.verify import measure_hybrid
from kilnctl.simulate import simulate

#: fixed gains keep these tests independent of the root-locus design (its own tests cover it)
P = Parameters(gains="given", k_p=0.085, k_I=2.17, k_D=0.0142)
FINAL = DEFAULT_STAGES[-1].widths


def _eval(expr, t, value):
    return float(ca.evalf(ca.substitute(expr, t, value)))


# --- the reference profiles (truth: closed forms) ----------------------------------

def test_pwl_reference_is_the_piecewise_linear_ramp():
    t = ca.SX.sym("t")
    ev, evd, t_end = pwl_reference(t, [50.0, 100.0], 500.0)
    # truth: 250 rpm at 50 rpm/s take 5 s, then 250 rpm at 100 rpm/s take 2.5 s
    assert float(t_end) == pytest.approx(7.5)
    for tt, v, d in [(1.0, 50.0, 50.0), (5.0, 250.0, 75.0), (6.0, 350.0, 100.0), (9.0, 500.0, 0.0)]:
        assert _eval(ev, t, tt) == pytest.approx(v)
        if tt != 5.0:
            assert _eval(evd, t, tt) == pytest.approx(d)
    # the rounded version: exact far from the knots, within r*corner*ln2 at a knot
    ev_s, _, _ = pwl_reference(t, [50.0, 100.0], 500.0, corner=0.05)
    assert _eval(ev_s, t, 2.0) == pytest.approx(100.0, abs=1e-9)
    assert abs(_eval(ev_s, t, 5.0) - 250.0) <= 50.0 * 0.05 * math.log(2) + 1e-9
    assert _eval(ev_s, t, 12.0) == pytest.approx(500.0, abs=1e-9)


def test_scurve_reaches_the_set_point_with_zero_slope():
    t = ca.SX.sym("t")
    for a, j in [(100.0, 50.0), (400.0, 20.0)]:  # trapezoidal, then triangular acceleration
        ev, evd, t_end = scurve_reference(t, a, j, 500.0)
        a_eff, t1, te = scurve_timing(a, j, 500.0)
        assert a_eff == pytest.approx(min(a, math.sqrt(j * 500.0)))
        assert _eval(ev, t, te) == pytest.approx(500.0, rel=1e-12)
        assert _eval(evd, t, te) == pytest.approx(0.0, abs=1e-9)
        assert _eval(evd, t, 0.5 * te) == pytest.approx(a_eff, rel=1e-12)  # peak acceleration mid-way
        assert _eval(ev, t, te + 3.0) == pytest.approx(500.0, rel=1e-12)


def test_profile_parsing_and_bad_problems():
    assert Profile.parse("constant").names == ("ramp_r1",)
    assert Profile.parse("PWL:4").n == 4
    assert Profile.parse("scurve").units == ("rpm/s", "rpm/s^2")
    for bad in ("linear", "pwl:0", "pwl:x", 3):
        with pytest.raises(ParameterError):
            Profile.parse(bad)
    with pytest.raises(ParameterError, match="objective"):
        RampProblem(P, objective="mean")
    with pytest.raises(ParameterError, match="horizon"):
        RampProblem(P, t_max=10.0, horizon=5.0)
    with pytest.raises(ParameterError, match="t_max"):
        RampProblem(P, t_max=-1.0)
    # truth: the pwl end time is the sum of omega_ref/(N r_k)
    assert Profile.parse("pwl:2").end_time([50.0, 100.0], 500.0) == pytest.approx(7.5)


# --- the smooth model against the hybrid plant ------------------------------------------

def test_exact_pwl1_component_reproduces_the_paper_ramp():
    # truth: the paper's ramp component with its corner as a mode switch
    a = simulate(P.replace(ramp_rate=74.0), "micro", t_end=3.0)
    b, _ = measure_hybrid(P, Profile("pwl", 1), [74.0], horizon=3.0)
    assert b.peak_stress_Pa == pytest.approx(a.summary()["peak_stress_Pa"], rel=1e-4)


@pytest.mark.parametrize("rate", [40.0, 150.0])
def test_smooth_model_tracks_the_hybrid_plant(rate):
    # truth: the exact hybrid plant (backlash contact events, stick-slip, limits)
    prof = Profile.parse("constant")
    model = SmoothStartup(prof, P)
    grid = TimeGrid.make(6.0, 20.0, 1e-3)
    r = model.run(P, [rate], FINAL, grid.t)
    m, _ = measure_hybrid(P, prof, [rate], horizon=grid.t[-1])
    assert np.max(np.abs(r["sigma"])) == pytest.approx(m.peak_stress_Pa, rel=0.01)
    assert np.max(np.abs(r["sigma_dyn"])) == pytest.approx(m.peak_dynamic_stress_Pa, rel=0.01)
    assert np.max(np.abs(r["i_a"])) == pytest.approx(m.peak_current_A, rel=0.01)


# --- gradients -----------------------------------------------------------------------------

@pytest.mark.parametrize("spec, theta", [("constant", [90.0]), ("pwl:2", [200.0, 300.0]), ("scurve", [120.0, 80.0])])
def test_sensitivities_match_finite_differences_and_casadi(spec, theta):
    prof = Profile.parse(spec)
    model = SmoothStartup(prof, P)
    grid = TimeGrid.make(2.0, 3.0, 1e-2)
    q, pq = objective_quadrature(model)
    run = SensitivityRun(model, grid.t, (q, pq), rtol=1e-10, atol=1e-10)
    plain = model.run(P, theta, FINAL, grid.t)
    inv = 1.0 / np.max(np.abs(plain["sigma"]))
    pqv = [20.0, 1.0, np.max(np.abs(plain["sigma_dyn"])) * inv, inv]  # shifts at the sampled peaks
    r = run(P, np.array(theta), FINAL, pqv)
    k = grid.k_tmax
    fd_Q = np.zeros_like(r["dQ"])
    for i in range(len(theta)):
        # truth 1: central finite differences of the same smooth model
        h = 1e-3 * theta[i]
        tp, tm = np.array(theta, float), np.array(theta, float)
        tp[i] += h
        tm[i] -= h
        rp, rm = run(P, tp, FINAL, pqv), run(P, tm, FINAL, pqv)
        fd_Q[:, i] = (rp["Q"] - rm["Q"]) / (2 * h)
        fd_speed = (rp["Y"][4, k] - rm["Y"][4, k]) / (2 * h)
        assert abs(fd_speed) > 1e-4  # every profile number moves the speed at t_max here
        assert r["dY"][4, k, i] == pytest.approx(fd_speed, rel=2e-4)
    for row in range(fd_Q.shape[0]):  # objective integrals: gradient vectors agree to 1e-3 of their size
        assert np.abs(r["dQ"][row] - fd_Q[row]).max() <= 1e-3 * np.abs(fd_Q[row]).max()
    # truth 2: CasADi's own CVODES forward sensitivities of the plain model
    th = ca.MX.sym("th", len(theta))
    F = model.integrator(0.0, grid.t)
    X = F(x0=model.x0(P, th, FINAL), p=model.param_vector(P))["xf"]
    speed = model.output_map(grid.n)(X, grid.t, model.param_vector(P))[4, k]
    jac = ca.Function("j", [th], [ca.jacobian(speed, th)])(theta)
    assert np.asarray(jac).ravel() == pytest.approx(r["dY"][4, k], rel=1e-4)


# --- optimum, transcriptions, infeasibility ----------------------------------------------

def test_optimum_on_a_reduced_problem_matches_brute_force_on_the_hybrid_plant():
    # reduced problem: 4 s to speed, 5 s horizon, objective 'dynamic' (the start-up stress the ramp causes).
    # truth: on the hybrid plant the dynamic stress grows with the ramp rate (grid), so the optimum is
    # the slowest rate that still reaches 95 % of the speed by t_max (bisection on the hybrid plant).
    t_max, horizon = 4.0, 5.0
    prof = Profile.parse("constant")
    grid_rates = [110.0, 130.0, 160.0, 200.0]
    dyn = [measure_hybrid(P, prof, [r], horizon)[0].peak_dynamic_stress_Pa for r in grid_rates]
    assert all(b > a for a, b in zip(dyn, dyn[1:]))

    def t95(r):
        return measure_hybrid(P, prof, [r], horizon)[0].time_to_speed_s

    lo, hi = 100.0, 300.0
    assert t95(lo) > t_max > t95(hi)
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if t95(mid) > t_max else (lo, mid)
    r_star = hi
    res = optimize_ramp(RampProblem(P, profile="constant", t_max=t_max, horizon=horizon, objective="dynamic"))
    assert res.values[0] == pytest.approx(r_star, rel=0.01)
    assert res.ok, res.flags
    assert res.summary()["peak_stress_verified_Pa"] == pytest.approx(res.summary()["peak_stress_predicted_Pa"],
                                                                     rel=0.01)


@pytest.mark.slow  # about 25 s (two transcriptions solved)
def test_single_and_multiple_shooting_agree():
    prob = RampProblem(P, profile="constant", t_max=3.0, horizon=3.5, objective="dynamic")
    stage = (Stage(smooth_ds=1e-5, smooth_v=1e-3, ramp_corner=0.2, beta=100.0),)
    a = optimize_ramp(prob, transcription="single_shooting", stages=stage, verify=False)
    b = optimize_ramp(prob, transcription="multiple_shooting", stages=stage, verify=False, n_shooting=3)
    assert b.values[0] == pytest.approx(a.values[0], rel=1e-4)
    assert b.stages[-1].objective == pytest.approx(a.stages[-1].objective, rel=1e-5)


@pytest.mark.slow  # about 16 s (IPOPT proves infeasibility)
def test_infeasible_requests_raise_with_status_and_constraint():
    # no ramp within the bounds reaches 95 % of 500 rpm in 0.1 s
    with pytest.raises(RampSolveError, match="infeasible") as e:
        optimize_ramp(RampProblem(P, t_max=0.1, horizon=1.0))
    assert "speed at t_max" in e.value.constraint
    # the running current (about 850 A) exceeds a 600 A limit whatever the ramp: IPOPT must fail
    with pytest.raises(OptimizationError) as e:
        optimize_ramp(RampProblem(P.replace(I_max=600.0), t_max=4.0, horizon=5.0, objective="dynamic"),
                      stages=DEFAULT_STAGES[:1], ipopt_options={"max_iter": 40})
    assert isinstance(e.value, RampSolveError)
    assert e.value.status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    assert "armature current" in e.value.constraint
    assert e.value.violation > 0


def test_smoothing_width_default_is_small_against_the_running_penetration():
    # truth (hand): the running load ~ 115 MPa is W = sigma*b*m*Y ~ 1.07 MN, a penetration W/k_e ~ 72 um
    W = 115e6 * P.face_width * P.module * P.Y_lewis
    assert SMOOTH_DS < 0.02 * W / P.k_e
