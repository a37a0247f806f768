"""Candidates refitted against a stick-slip model (calibrate._Search.fit_all, Calibration.fit's start ranking,
Diagnosis._refit_from_setup), and the base calibrated under a stated torque law (Diagnosis._base_fit).

Truths: records of the independently written plants (benchmarks/foreign_records.py and the benchmark plant
of benchmarks/diagnose_records.py, each with its own stick-slip state machine) and of kilnctl's generator;
kilnctl's model at the plant's own values gives the fit a refit must reach, and the generator's values the
parameter it must find.
"""

import math

import numpy as np
import pytest


@pytest.fixture(scope="module")
def coulomb_stick_slip(tmp_path_factory):
    """40 s at 10 Hz of the foreign plant: torque-law stick-slip and a motor-side Coulomb torque of 100 N m."""
    from conftest import foreign_stick_slip_record

    return foreign_stick_slip_record(tmp_path_factory.mktemp("coulomb_stick_slip"), "tc100",
                                     {"coulomb": {"T": 100.0}})


def test_effect_refit_from_a_fitted_stick_slip_model_reaches_the_true_structure(coulomb_stick_slip):
    # truth: the fit of kilnctl's model with the motor Coulomb friction at the plant's own values (97.4 %).
    # The model without it (the setup states the torque law) fitted first, as a diagnosis round does: its
    # m_v and J_v make up for part of the missing torque and its stick-slip cycles are in step with the
    # record's.  From there the phase-free and timing stages of every local fit led into poorer valleys
    # (93.7-95.3 %) and the refit returned its start with T_cm at the null value (95.8 %): the effect went
    # unseen.  When a staged local fit ends above its start, the same fit is now run without the stages
    # and the lower end is kept: 97.2 %, T_cm = 86 N m.
    from kilnctl.measure import compare
    from kilnctl.measure.diagnose import CHANNELS, Diagnosis
    from kilnctl.measure.runner import run_model

    m, params, truth = coulomb_stick_slip
    d = Diagnosis(params)
    exp = m.experiment(params)
    model, comps, p, _ = d._structure(params, ("motor_coulomb_friction",))
    true_fit = compare(m, p.replace(T_cm=100.0, **truth["base"]), model=model, effects=comps).fit["current_A"]
    act = m.t >= exp.t0 - 1e-9
    run = run_model(params.replace(**truth["base"]), m, exp)
    scales = {c: float(np.sqrt(np.mean((m.channels[c][act] - run.outputs[c]) ** 2))) for c in CHANNELS}
    without = d._calibrate(m, params, (), scales, None, dict(truth["base"]), [], exp, None, None, 1)
    cal, error, _ = d._refit(m, params, [], "motor_coulomb_friction", dict(without.values_), None, scales,
                             None, exp)
    assert error is None
    assert without.fit_percent_["current_A"] < true_fit - 1.0  # the effect is visible in the record
    assert cal.fit_percent_["current_A"] > true_fit - 0.5
    assert 75.0 < cal.values_["T_cm"] < 125.0


def _hard_record(name, effects):
    """A record of the hard set (benchmarks/diagnose_records.py), the diagnosis' setup and the structure
    base + ``effects``: (m, truth, params, d, exp, (model, comps, p), the true structure's current fit at the
    plant's values [%], the fitting part)."""
    from benchmarks.diagnose_records import find, make
    from kilnctl import Parameters
    from kilnctl.measure import compare
    from kilnctl.measure.calibrate import holdout_masks
    from kilnctl.measure.diagnose import Diagnosis
    from kilnctl.measure.synthetic import DEFAULT_GAINS
    from kilnctl.simulate import resolve_gains

    m, truth = make(find(name))
    params = resolve_gains(Parameters(DEFAULT_GAINS))
    d = Diagnosis(params)
    exp = m.experiment(params)
    model, comps, p, _ = d._structure(params, effects)
    true_fit = compare(m, p.replace(**truth["base"], **truth["catalogue_values"]), model=model,
                       effects=comps).fit["current_A"]
    train, _ = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    return m, truth, params, d, exp, (model, comps, p), true_fit, train


@pytest.mark.slow  # 120 starting points, six phase-free stages and four local fits of a stick-slip pair (~25 s)
def test_a_search_from_the_setup_reaches_the_soft_drive_trains_valley():
    # truth: kilnctl's model at the independent plant's own values (benchmarks/diagnose_records.py, "plant"
    # source: its own stick-slip state machine and twist spring-damper, k_tw = 5.9e7 N m/rad, damping 0.93 %
    # of k_tw) fits the record's current to 98.1 %.  The base model calibrated with the printed friction law
    # sits at mu_c 0.49, J_v 1.1e6 (the plant: 0.42, 1.6e6), 75.5 %, and the pair refitted from there ended
    # at 77 %.  The search from the setup's values ranks its starts by the phase-free cost, screens twice as
    # many as it fits by the phase-free stage (the valley start ranked third; the first two led to 82 % and
    # 76 %), and weighs the channels by their spread: by the base's residual (the speed fitted to 0.5 rpm)
    # the speed's cycles ruled the stage and the valley was missed again (77 %).
    from kilnctl.measure import compare
    from kilnctl.measure.diagnose import CHANNELS
    from kilnctl.measure.effects import CATALOGUE
    from kilnctl.measure.runner import run_model

    effects = ("torque_friction_law", "drivetrain_compliance")
    m, truth, params, d, exp, (model, comps, p), true_fit, train = _hard_record("plant:torque_law+compliance/s2",
                                                                                effects)
    base = {"mu_c": 0.4857, "mu_s": 0.6193, "m_v": 5.108e5, "J_v": 1.112e6}  # the base's calibration
    act = m.t >= exp.t0 - 1e-9
    run = run_model(params.replace(**base), m, exp)
    scales = {c: float(np.sqrt(np.mean((m.channels[c][act] - run.outputs[c]) ** 2))) for c in CHANNELS}
    setup = d._setup_values(params)
    cal = d._refit_from_setup(m, params, effects, CATALOGUE["drivetrain_compliance"], p, base, setup, scales,
                              train, exp, None, 3)
    assert true_fit > 97.5
    assert compare(m, cal.params_, model=model, effects=comps).fit["current_A"] > true_fit - 1.0
    assert cal.values_["k_po"] == pytest.approx(truth["catalogue_values"]["k_po"], rel=0.2)


def test_backlash_starts_against_a_stick_slip_model_are_ranked_to_the_gap():
    # truth: kilnctl's generator (benchmarks/diagnose_records.py, "pair:torque_friction_law+backlash/s2":
    # torque law, backlash delta_x = 9.47 mm); the true structure at the generator's values fits the current
    # to 98.1 %.  The round after the torque law was added refits the backlash from the torque-law model's
    # values (below, as the diagnosis had them; the round's weights: the base's residual RMS), ranking its
    # starts by the phase-free cost, whose ramp part was the residual itself: the gap's valley there is a few
    # tenths of a millimetre wide (the impact train 30 ms off costs as much as none), the catalogue grid's
    # points 0.4 mm either side of it (every 0.76 mm from 0 to 16 mm, below) ranked below no gap at all, and
    # the one local fit from the best start ended at 90.2 % (the diagnosis then took a heavily damped stiff
    # compliance for the backlash).  With the ramp part smoothed like the plain residual the grid's neighbours
    # of the gap rank first and the fit from there finds it.
    from kilnctl.measure import compare
    from kilnctl.measure.effects import CATALOGUE, grid_starts

    effects = ("torque_friction_law", "backlash")
    m, truth, params, d, exp, (model, comps, p), true_fit, train = _hard_record(
        "pair:torque_friction_law+backlash/s2", effects)
    law = {"mu_c": 0.38422, "mu_s": 0.48936, "m_v": 6.03392e5, "J_v": 1.763147e6}  # the torque-law model's fit
    scales = {"current_A": 71.445, "speed_rpm": 0.72759}
    grid = [g for g in grid_starts(CATALOGUE["backlash"].parameters, CATALOGUE["backlash"].grid_points)
            if g["delta_x"] < 0.0165]
    cal = d._calibrate(m, params, effects, scales, train, dict(law, delta_x=0.0), grid, exp, None, "backlash", 1)
    assert true_fit > 97.5
    assert compare(m, cal.params_, model=model, effects=comps).fit["current_A"] > true_fit - 1.0
    assert cal.values_["delta_x"] == pytest.approx(truth["catalogue_values"]["delta_x"], rel=0.05)


def test_a_compliance_too_damped_to_ring_is_not_taken_for_one():
    # truth: kilnctl's generator (benchmarks/diagnose_records.py, "pair:torque_friction_law+kiln_unbalance/s2":
    # torque law and a kiln unbalance, a rigid drive train).  The values are the diagnosis' final ones at
    # 1aa76b4, which had added a drivetrain compliance of k_po 4.0e9 N m/rad and C_po 9.9e9 N m s/rad: a damping
    # ratio of 29 (hand: C / (2 sqrt(k J_eff)), J_eff = 7.37e6 kg m^2 from the motor side J_m n^2 = 2.49e7
    # and the kiln side J_kiln + J_v), which cannot ring.  Against the same values without it the refit was
    # supported (BIC down by thousands); the effect's signature is a torsional ring, so it is not.  The
    # generator's true compliances of the hard set (damping ratios 0.013-0.29) are not touched.
    from kilnctl.measure.calibrate import holdout_masks
    from kilnctl.measure.effects import CATALOGUE
    from kilnctl.model.drivetrain import damping_ratio

    effects = ("torque_friction_law", "kiln_unbalance", "drivetrain_compliance")
    m, truth, params, d, exp, _, _, train = _hard_record("pair:torque_friction_law+kiln_unbalance/s2", effects)
    assert truth["expected"] == ["torque_friction_law", "kiln_unbalance"]
    final = {"mu_c": 0.38752347496221073, "mu_s": 0.5235724476623269, "m_v": 561142.3614881688,
             "J_v": 1620774.621494095, "T_unb": 218976.9188558143, "phi_unb": 1.8469066845809297,
             "k_po": 4036473066.01556, "C_po": 9937634843.211077}
    without = {k: v for k, v in final.items() if k not in ("k_po", "C_po")}
    scales = {"current_A": 71.4, "speed_rpm": 0.73}
    _, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    cal = d._calibrate(m, params, effects, scales, train, final, (), exp, None, None, 0)
    current = d._calibrate(m, params, effects[:2], scales, train, without, (), exp, None, None, 0)
    p_fit = cal.params_
    j_eff = ((p_fit.J_m + p_fit.J_m2) * p_fit.n ** 2 * p_fit.J_e_eff) / ((p_fit.J_m + p_fit.J_m2) * p_fit.n ** 2
                                                                         + p_fit.J_e_eff)
    assert damping_ratio(final["k_po"], final["C_po"], p_fit) == pytest.approx(
        final["C_po"] / (2 * np.sqrt(final["k_po"] * j_eff)), rel=1e-12)
    r = d._evidence(m, "drivetrain_compliance", cal, current, scales, train, test, exp, 0.0)
    assert r.delta_bic < -100 and not r.supported and "cannot ring" in r.reason
    for v in ({"k_po": 2.58e8, "C_po": 2.35e6}, {"k_po": 5.17e7, "C_po": 1.11e7}, {"k_po": 1.5e9, "C_po": 6e7}):
        assert CATALOGUE["drivetrain_compliance"].contradicts(v, p_fit) is None


def test_a_stand_ins_base_values_re_anchor_the_model_in_the_missing_effects_basin():
    # truth: kilnctl's generator ("pair:torque_friction_law+speed_sensor_lag/s2": the torque law and a speed
    # sensor lag of 4.45 ms, J_v 1.744e6 kg m^2) and the true structure's fit at the plant's values.  The values
    # are the diagnosis' own in its second round at 2e9e435: the torque law fitted with J_v 1.61e6, and the
    # compliance refit that gained dBIC -2662 at a damping ratio far above one (a stand-in, rejected).  The
    # lag's own refit about the current values had ended at its null value (dBIC -10), and the lag was missed
    # (96.6 % against the true structure's 98.1 %).  The torque law refitted from the stand-in's base values
    # lands near the plant's J_v, where the lag's valley lies.
    from kilnctl.measure.calibrate import holdout_masks

    law = ("torque_friction_law",)
    m, truth, params, d, exp, _, true_fit, train = _hard_record("pair:torque_friction_law+speed_sensor_lag/s2",
                                                                 law + ("speed_sensor_lag",))
    assert truth["expected"] == ["torque_friction_law", "speed_sensor_lag"]
    scales = {"current_A": 68.30, "speed_rpm": 0.5736}
    _, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    before = {"mu_c": 0.41386780886193714, "mu_s": 0.5303241853612255, "m_v": 605109.1879167828,
              "J_v": 1609479.3588934739}
    stand_values = {"mu_c": 0.409572546522956, "mu_s": 0.5226296345393945, "m_v": 608944.5714205187,
                    "J_v": 1751996.9308139025, "k_po": 625536522.589016, "C_po": 1839557681.9474716}
    current = d._calibrate(m, params, law, scales, train, before, (), exp, None, None, 0)
    cal = d._calibrate(m, params, law + ("drivetrain_compliance",), scales, train, stand_values, (), exp, None,
                       None, 0)
    r = d._evidence(m, "drivetrain_compliance", cal, current, scales, train, test, exp, 0.0)
    assert r.stand_in and not r.supported and r.delta_bic < -1000
    said = []
    anchored, _ = d._reanchor(m, params, list(law), current, [r], scales, train, test, exp, said.append)
    assert anchored.cost_ < 0.7 * current.cost_ and "drivetrain_compliance's base values" in said[0]
    assert anchored.values_["J_v"] == pytest.approx(truth["plant"]["J_v"], rel=0.03)
    assert current.fit_percent_["current_A"] < true_fit - 5.0


def test_a_small_held_out_gain_that_the_whitened_bic_contradicts_is_not_evidence():
    # truth: the benchmark's independent plant ("plant:compliance/s2": a two-mass drive train and nothing else).
    # The values are the diagnosis' own at 21a3c22: the compliance selected in round 1, then the second round's
    # refits of a kiln unbalance and a second motor on top of it.  Both lower the plain BIC (-30, -17) and the
    # held-out error (2.9 %, 4.1 %, above the 2 % threshold), but BIC with the coloured noise modelled rises
    # (+12, +11) and the held-out gain is about one standard error: before, the unbalance was added.
    from kilnctl.measure.calibrate import holdout_masks

    comp = {"mu_c": 0.3863755798212337, "mu_s": 0.5417322060597056, "m_v": 551048.4100864079,
            "J_v": 1619537.581101426, "k_po": 442692523.6741624, "C_po": 6720123.169584452}
    refits = {"kiln_unbalance": {"mu_c": 0.38752927270315785, "mu_s": 0.6203610602267365, "m_v": 550861.2350964266,
                                 "J_v": 1615973.1666181677, "k_po": 448502052.17904043, "C_po": 7083604.857617007,
                                 "T_unb": 14450.78921377147, "phi_unb": 2.5827474121606198},
              "second_motor": {"mu_c": 0.38653114535519273, "mu_s": 0.46356597840594155, "m_v": 550877.9951673159,
                               "J_v": 1618439.0060395089, "k_po": 443304438.80256385, "C_po": 6740397.968068712,
                               "J_m2": 1.1272024763334147}}
    m, truth, params, d, exp, _, _, train = _hard_record("plant:compliance/s2", ("drivetrain_compliance",))
    assert truth["expected"] == ["drivetrain_compliance"]
    scales = {"current_A": 6.060519707464501, "speed_rpm": 0.44317615373689345}
    _, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    current = d._calibrate(m, params, ("drivetrain_compliance",), scales, train, comp, (), exp, None, None, 0)
    for name, values in refits.items():
        cal = d._calibrate(m, params, ("drivetrain_compliance", name), scales, train, values, (), exp, None, None, 0)
        r = d._evidence(m, name, cal, current, scales, train, test, exp, 0.0)
        assert r.delta_bic < -d.min_delta_bic and d.min_holdout_gain < r.holdout_gain < 3 * d.min_holdout_gain
        assert r.delta_bic_corrected > 0 and r.holdout_z < d.holdout_z
        assert not r.supported and "slowly correlated noise" in r.reason


def test_the_base_under_the_torque_law_fits_about_as_well_as_the_plants_own_values(tmp_path):
    # truth: kilnctl's base model at the foreign plant's own base values (m_v, mu_c, mu_s, J_v): the base
    # calibration must fit about as well as they do (its local fits end within 5 % of their cost here).
    # The record is red team 4's f25 (benchmarks/foreign_records.py) logged at 50 Hz: a second rotor of
    # 25 kg m^2 on a coupling of 4e4 N m/rad (8.7 Hz), which the base lacks, under the torque law.  Every
    # local fit of the base calibration began with the phase-free stage, whose residual preferred a burden
    # inertia ~20 times the plant's (the cycles stop, the ramp current rises): 3.7 times the cost of the
    # plant's values, and every round of the diagnosis then refitted about it.  The same starts are now
    # also fitted by simulation error alone, and the lower cost is kept.
    import dataclasses

    from benchmarks import foreign_records as fr
    from kilnctl.measure import load_setup, read_record
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.diagnose import Diagnosis

    spec = next(s for s in fr.RECORDS if s.name == "f25_coupling_j2")
    spec = dataclasses.replace(spec, fs=50.0, layout="plain", h=1e-3)
    truth = fr.write_record(spec, tmp_path)
    params = load_setup(tmp_path / f"{spec.name}.toml").params
    m = read_record(truth["csv"], params, columns=truth["columns"])
    d = Diagnosis(params)
    exp = m.experiment(params)
    at_plant = Calibration(params, d.calibrate, t0=d.t0).fit(m, experiment=exp, init=truth["base"], n_local=0)
    base = d._base_fit(m, params, exp)
    assert base.cost_ <= 1.1 * at_plant.cost_, (base.values_, base.cost_, at_plant.cost_)
    assert base.values_["J_v"] == pytest.approx(truth["base"]["J_v"], rel=0.1)


@pytest.mark.slow  # a local fit of the torque-law model and one of the drag (~30 s)
def test_a_drag_absorbed_as_a_heavier_burden_is_found_from_a_start_that_keeps_the_steady_current():
    # truth: kilnctl's generator (benchmarks/diagnose_records.py, "pair:torque_friction_law+viscous_drag/s1":
    # torque law, a drag of 7.5e6 N m s/rad, burden 607 t); the true structure at the generator's values fits
    # the current to 98.1 %.  The model with the torque law and no drag, fitted from the generator's base
    # values, takes the drag's load at the set speed as a heavier burden (665 t, 92.1 %); the drag's refit from
    # there must cross a rugged valley (the drag up, the burden down), as on red team 15's E2 (a drag of 4e6
    # absorbed as a burden 14 % heavy, every refit kept its start).  The restart from the own start that fits
    # the ramp best, with the burden moved to keep the steady current, finds the drag and the burden.
    from types import SimpleNamespace

    from kilnctl.measure import compare
    from kilnctl.measure.diagnose import CHANNELS
    from kilnctl.measure.effects import CATALOGUE
    from kilnctl.measure.runner import run_model

    effects = ("torque_friction_law", "viscous_drag")
    m, truth, params, d, exp, (model, comps, p), true_fit, train = _hard_record(
        "pair:torque_friction_law+viscous_drag/s1", effects)
    act = m.t >= exp.t0 - 1e-9
    run = run_model(params.replace(**truth["base"]), m, exp)
    scales = {c: float(np.sqrt(np.mean((m.channels[c][act] - run.outputs[c]) ** 2))) for c in CHANNELS}
    law = d._calibrate(m, params, ("torque_friction_law",), scales, train, dict(truth["base"]), (), exp, None, None, 1)
    assert law.values_["m_v"] > 1.05 * truth["base"]["m_v"]  # the drag's load taken by the burden
    init = dict(law.values_, B_o=CATALOGUE["viscous_drag"].null["B_o"])
    stuck = SimpleNamespace(cost_=law.cost_, n_starts_=0, local_fits_=[])
    cal = d._restart_at_load(m, params, effects, CATALOGUE["viscous_drag"], (model, comps, p), init, stuck,
                             scales, train, exp, None)
    assert cal is not stuck
    # the restart's fit against the model without the drag (92.1 %): where it lands within the valley is the
    # stick-slip cycles' phase, which moves with the last bits of the arithmetic; at values within 1 % of the
    # generator's it fitted 98.1 % (true structure: 98.1 %) on the machines of earlier sessions and 96.1 % on
    # the 2026-11-28 morning one (numpy 2.4.6), so the values below, not the fit to a point, tell that the drag
    # and the burden were found
    law_fit = compare(m, law.params_, model=law.model, effects=law.effects).fit["current_A"]
    assert compare(m, cal.params_, model=model, effects=comps).fit["current_A"] > law_fit + 3.0
    assert cal.values_["B_o"] == pytest.approx(truth["catalogue_values"]["B_o"], rel=0.15)
    assert cal.values_["m_v"] == pytest.approx(truth["base"]["m_v"], rel=0.02)
