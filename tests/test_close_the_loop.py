"""The close-the-loop study (kilnctl.close_loop) against independent truths.

One run of the loop on the structure the shipped example's diagnosis learns
(the macro model with a second motor of 20.7 kg m^2) serves every test; it is
given as a component list with its values, so no diagnosis runs here.
"""

import csv
import io

import control as ct
import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.close_loop import COLUMNS, close_the_loop
from kilnctl.errors import KilnctlError, ModelError, ParameterError
from kilnctl.gains import PIDGains
from kilnctl.linear import closed_loop_ss
from kilnctl.linearize import linearize
from kilnctl.model import component_names
from kilnctl.optimize.model import load_stress
from kilnctl.simulate import simulate

COMPS = component_names("macro", ["second_motor"])
#: the example's diagnosis (kilnctl/data/example_record.csv), rounded: J_m2 20.7 kg m^2, m_v 610 t, mu_c 0.419
PARAMS = Parameters(J_m2=20.7, m_v=610e3, mu_c=0.419, mu_s=0.498)


@pytest.fixture(scope="module")
def study():
    return close_the_loop(COMPS, PARAMS, selected=["second_motor"], record="test")


def _given(gains: PIDGains) -> Parameters:
    return PARAMS.replace(gains="given", k_p=gains.k_p, k_I=gains.k_I, k_D=gains.k_D)


@pytest.mark.parametrize("column", ["rigid", "redesigned"])
def test_damping_equals_python_control_on_a_fresh_linearization(study, column):
    # truth: control.damp() of the closed loop linearized anew from the parameters (gains set in params, not via
    # with_gains), over both burden conditions; the table's mode is the least damped pair the gains act on (the
    # sliding burden's undamped pendulum at 0.38 Hz is not moved by them and stays out). Within 1e-6: the fresh
    # linearization starts the plant up with these gains, so its operating point (the end of a finite start-up)
    # differs from the one with_gains keeps by the last traces of the start-up transient (1.3e-8 seen)
    g = study.gains[column]
    mode = study.limiting_mode(column)
    sys = linearize(_given(g), components=COMPS, burden=mode["condition"]).sys
    with np.errstate(invalid="ignore", divide="ignore"):  # the kinematic angles' poles at 0 have no damping
        wn, zeta, _ = ct.damp(sys, doprint=False)
    k = int(np.argmin(np.abs(wn - mode["omega_n_rad_s"])))
    assert zeta[k] == pytest.approx(mode["zeta"], rel=1e-6)
    row = next(r for r in study.table() if r["quantity"].startswith("least damping"))
    assert row[column] == pytest.approx(zeta[k], rel=1e-6)


@pytest.mark.parametrize("column", ["rigid", "redesigned"])
def test_damping_equals_the_hand_derived_rigid_model_with_both_inertias(study, column):
    # truth: eq. 21 written by hand (kilnctl.linear) with the motor inertia J_m + J_m2: a second motor on the
    # shaft is exactly a larger rotor inertia. Slip: equal to solver precision. Stick: within 0.1 % (the exact
    # linearization keeps the bearing friction's slope at speed, which eq. 21 leaves out)
    g = study.gains[column]
    rigid = PARAMS.replace(J_m=PARAMS.J_m + PARAMS.J_m2)
    for cond, tol in (("slip", 1e-7), ("stick", 1e-3)):
        wn, zeta, _ = ct.damp(closed_loop_ss(rigid, g, cond), doprint=False)
        pair = zeta < 0.999
        rows = [r for r in study._check(column).modes[cond] if r["moved"] and 0 < r["zeta"] < 0.999]
        assert len(rows) == 1
        assert rows[0]["zeta"] == pytest.approx(float(zeta[pair][0]), rel=tol)
        assert rows[0]["omega_n_rad_s"] == pytest.approx(float(wn[pair][0]), rel=tol)
    # the dominant (real) pole in stick is the hand model's real pole
    wn, zeta, _ = ct.damp(closed_loop_ss(rigid, g, "stick"), doprint=False)
    assert study.dominant_mode(column)["omega_n_rad_s"] == pytest.approx(float(wn[zeta >= 0.999][0]), rel=1e-3)


def test_the_rigid_gains_miss_and_the_redesign_meets_the_damping(study):
    # truth: the zeta of the hand-derived model above (0.64 vs 0.71 on the example's structure); the requirement
    # is the documented default 0.7
    b, a = study.retuned.before, study.retuned.after
    assert not b.ok and a.ok
    assert study.limiting_mode("rigid")["zeta"] < 0.7 <= study.limiting_mode("redesigned")["zeta"]
    # and the natural-frequency cap: the hand-derived model's real pole (J_m + J_m2, stick) is above wn_max with
    # the rigid gains (4.68 rad/s) and at or below it with the redesigned ones; the summary no longer notes it
    rigid = PARAMS.replace(J_m=PARAMS.J_m + PARAMS.J_m2)
    wn = {}
    for col in ("rigid", "redesigned"):
        w, z, _ = ct.damp(closed_loop_ss(rigid, study.gains[col], "stick"), doprint=False)
        wn[col] = float(w[z >= 0.999][0])
    assert wn["rigid"] > study.requirements.wn_max * 1.02
    assert wn["redesigned"] <= study.requirements.wn_max * 1.002
    assert "above wn_max" not in study.summary() and "meets every requirement" in study.summary()
    # the rigid column's gains are the root-locus design of the paper's model (the same values in both)
    from kilnctl.design import design_pid

    assert study.gains["rigid"] == design_pid(PARAMS).gains


@pytest.mark.parametrize("column", ["rigid", "redesigned"])
def test_verified_figures_equal_a_direct_simulation(study, column):
    # truth: simulate() of the micro model with the second motor and the same gains, read here, with the
    # dynamic stress formed from its outputs by load_stress
    g = study.gains[column]
    r = simulate(_given(g), components=study.hybrid_components, t_end=study.ramp.problem.horizon, dt=1e-3)
    m = study.measures[column]
    assert m.peak_current_A == pytest.approx(float(np.max(np.abs(r.outputs["i_a"]))), rel=1e-6)
    assert m.peak_stress_Pa == pytest.approx(float(np.max(np.abs(r.outputs["sigma"]))), rel=1e-6)
    dyn = r.outputs["sigma"] - load_stress(r.outputs["T_f"], r.states["omega_kiln"], r.params)
    assert m.peak_dynamic_stress_Pa == pytest.approx(float(np.max(np.abs(dyn))), rel=1e-6)
    assert "second_motor" in study.hybrid_components and "mesh" in study.hybrid_components


def test_the_optimized_column_is_the_optimizers_own_verification(study):
    # truth: the ramp optimizer verifies its optimum and its baseline on the hybrid plant itself
    # (RampResult.verified / .baseline); the study re-simulates both ways independently
    ver = study.ramp.verified["nominal"]
    assert study.measures["optimized"].peak_dynamic_stress_Pa == pytest.approx(ver.peak_dynamic_stress_Pa, rel=1e-6)
    # the optimizer's baseline is the 74 rpm/s ramp as an S-curve with a near-infinite jerk: within 1 %
    base = study.ramp.baseline["nominal"]
    assert study.measures["redesigned"].peak_dynamic_stress_Pa == pytest.approx(base.peak_dynamic_stress_Pa,
                                                                               rel=0.01)
    assert study.measures["optimized"].peak_dynamic_stress_Pa < 0.8 * study.measures["redesigned"].peak_dynamic_stress_Pa


def test_table_csv_and_markdown_carry_the_same_numbers(study):
    rows = study.table()
    parsed = list(csv.DictReader(io.StringIO(study.to_csv())))
    assert [p["quantity"] for p in parsed] == [r["quantity"].strip() for r in rows]
    for p, r in zip(parsed, rows):
        for key, _ in COLUMNS:
            if isinstance(r[key], float):
                assert float(p[key]) == pytest.approx(r[key], rel=1e-12)
    md = study.to_markdown()
    assert md.count("\n") == len(rows) + 2
    assert "| k_D | V*s/rpm | 0.01419 | 0.0164 | 0.0164 |" in md  # the gains of the example (tutorial_close_the_loop.md)
    assert "UNSAFE" in study.summary() or "MISSES" in study.summary()


def test_plot_draws_four_panels(study, tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from kilnctl.figures import save_figure

    fig = study.plot()
    assert len(fig.axes) == 4
    assert save_figure(fig, tmp_path / "loop.png").stat().st_size > 10_000


def test_bad_input_is_refused_with_the_fix():
    with pytest.raises(ParameterError, match="give params"):
        close_the_loop(COMPS)
    # an effect with modes or one that replaces a component cannot go into the ramp optimization: refused,
    # named, before anything long runs
    comps = component_names("macro", ["drivetrain_compliance"])
    with pytest.raises(ModelError, match="drivetrain_compliance"):
        close_the_loop(comps, Parameters())
    with pytest.raises(KilnctlError, match="--model-from"):
        close_the_loop("/nonexistent/diagnose.json")


def test_a_diagnosis_file_gives_the_same_loop_as_its_components_and_values(study, tmp_path):
    # truth: the module's study, built from the explicit component list and values; a diagnosis JSON with the
    # same selected effect and the same calibrated values (the keys kilnctl diagnose --json writes) must give
    # the same redesigned gains (make demo takes this path: a Structure from the file, not a tuple)
    import json

    d = {"selected": ["second_motor"], "settings": {"model": "macro"}, "baseline": {},
         "final_parameters": {k: {"value": getattr(PARAMS, k)} for k in ("J_m2", "m_v", "mu_c", "mu_s")}}
    f = tmp_path / "diagnose.json"
    f.write_text(json.dumps(d))
    from_file = close_the_loop(f, record="test")
    assert from_file.components == study.components
    a, b = from_file.retuned.after.gains, study.retuned.after.gains
    assert (a.k_p, a.k_I, a.k_D) == pytest.approx((b.k_p, b.k_I, b.k_D), rel=1e-9)
