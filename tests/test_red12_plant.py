"""Red team 12's independent plant (benchmarks/red12_plant.py: scipy DOP853 between its own burden switches) as
the truth for the evidence rules and the falling friction on records where the model already fits within noise.

The red team measured its plant against kilnctl's model at 0.0024-0.0035 A rms on its two kilns (no effect, no
noise).  Its R16 has no effect at all, under AR(1) noise correlated over 3 s: the diagnosis took a kiln
unbalance there, with no word of doubt.  Its R15 and R17 have a support-roller friction falling to nothing at
the set speed: taken for a constant motor friction and a lighter burden.  Here the candidates are refitted from
the diagnosis' own values of those runs (their diagnose.json), and judged as the diagnosis judges them.
"""

from types import SimpleNamespace

import pytest

from benchmarks.red12_plant import record
from kilnctl import Parameters
from kilnctl.measure import Measurement, compare
from kilnctl.measure.calibrate import holdout_masks
from kilnctl.measure.cautions import form_also_texts, form_kept_texts, form_rival_texts
from kilnctl.measure.diagnose import Diagnosis
from kilnctl.measure.runner import CHANNELS

FRICTION = "motor_coulomb_friction"

SETUP_KEYS = ("R_a", "L_a", "k_i", "k_b", "J_m", "B_m", "k_p", "k_I", "k_D", "ramp_rate", "omega_ref", "V_max",
              "I_max", "J_o", "J_v", "m_v", "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg", "n",
              "friction_law")


def _setup(name, baseline):
    """The record, its setup, the diagnosis and its scales (from the diagnosis' baseline values) and parts."""
    t, current, speed, ref, setup, plant = record(name)
    params = Parameters(gains="given", **{k: setup[k] for k in SETUP_KEYS})
    m = Measurement.from_arrays(t, current, speed, ref, source=f"red12 {name}", params=params)
    d = Diagnosis(params)
    exp = m.experiment(params)
    base = compare(m, params.replace(**baseline))
    scales = {c: base.channels[c].rms for c in CHANNELS}
    train, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    return m, params, d, exp, scales, train, test, plant


def _judged(name, baseline, current_values, effect, values):
    """The candidate judged against the current model (both refitted from the given values on the fitting
    part), and the current model."""
    m, params, d, exp, scales, train, test, _ = _setup(name, baseline)
    now = d._calibrate(m, params, (), scales, train, current_values, experiment=exp)
    cal = d._calibrate(m, params, (effect,), scales, train, values, experiment=exp)
    return d._evidence(m, effect, cal, now, scales, train, test, exp, 0.0), now


def _in_forms(name, baseline, current_values, own_values):
    """The motor Coulomb friction refitted from the given values, judged, then refitted in its forms as a round
    does (Diagnosis._in_best_form): (the round's result, the diagnosis, the plant's values)."""
    m, params, d, exp, scales, train, test, plant = _setup(name, baseline)
    now = d._calibrate(m, params, (), scales, train, current_values, experiment=exp)
    cal = d._calibrate(m, params, (FRICTION,), scales, train, own_values, experiment=exp)
    own = d._evidence(m, FRICTION, cal, now, scales, train, test, exp, 0.0)
    assert own.supported
    d.form_results_ = []  # as Diagnosis.fit starts it
    (r,) = d._in_best_form(m, params, [], [own], now, scales, train, test, exp, None, lambda s: None)
    return r, d, plant


def test_a_held_out_gain_that_the_whitened_bic_contradicts_is_no_unbalance_on_slow_noise():
    # R16: kiln G (a 38 s kiln revolution), no effect, AR(1) noise of 4 A over 3 s; the diagnosis' values at
    # round 1: the current model at 92.0 % (its base re-anchored), the unbalance refit at 3.6 kN m
    r, now = _judged("R16", {"mu_c": 0.37176, "mu_s": 0.48329, "m_v": 91897.2, "J_v": 74786.7},
                     {"mu_c": 0.374915, "mu_s": 0.386432, "m_v": 91159.8, "J_v": 81528.8}, "kiln_unbalance",
                     {"mu_c": 0.374951, "mu_s": 0.614045, "m_v": 91329.7, "J_v": 81678.1, "T_unb": 3635.9,
                      "phi_unb": 2.6212})
    assert now.fit_percent_["current_A"] > 90.0
    # plain BIC and the held-out blocks both favour it (the first rule's evidence) ...
    assert r.delta_bic < -100 and r.holdout_gain > 6.0, (r.delta_bic, r.holdout_gain)
    # ... and BIC with the coloured noise modelled rises: not supported, and the reason says why
    assert r.delta_bic_corrected > 10.0
    assert not r.supported and "slowly correlated noise" in r.reason, r.reason


def test_a_roller_friction_falling_to_nothing_at_the_set_speed_is_found_in_the_falling_form():
    # R17: kiln F, a support-roller friction of 140 kN m at rest falling linearly to nothing at the set speed
    # (112 N m at the motor through n = 1250), the plant's burden 309 t.  The constant friction had been selected
    # with a burden 8 % light (84.3 N m, 284.5 t), which cancels it at the set speed; the falling form, refitted
    # from the starts that keep the friction at the set speed, reaches the plant's own story
    r, _, plant = _in_forms("R17", {"mu_c": 0.383719, "mu_s": 0.489241, "m_v": 313718.1, "J_v": 589187.6},
                            {"mu_c": 0.379123, "mu_s": 0.483382, "m_v": 316450.5, "J_v": 593478.7},
                            {"mu_c": 0.403878, "mu_s": 0.514945, "m_v": 284541.2, "J_v": 520523.3, "T_cm": 84.3044})
    assert r.supported and r.form == "falling", r.reason
    v = r.calibration.values_
    assert v["a_cm"] > 0.9
    assert v["T_cm"] == pytest.approx(plant["T_vw"] / plant["n"], rel=0.1)
    assert v["m_v"] == pytest.approx(plant["m_v"], rel=0.01)


def test_a_falling_friction_the_record_cannot_tell_from_a_constant_one_is_cautioned():
    # R15: kiln G, as R17 with 15 kN m (21 N m at the motor), under noise of 1.5 A white and 2.5 A over 0.4 s:
    # the falling form fits about as well as the constant friction (plain BIC better, the whitened BIC and the
    # held-out blocks not), so the constant one stays, with a caution that names the falling story
    r, d, _ = _in_forms("R15", {"mu_c": 0.359698, "mu_s": 0.473287, "m_v": 95067.6, "J_v": 85140.7},
                        {"mu_c": 0.368506, "mu_s": 0.484876, "m_v": 93474.5, "J_v": 83730.2},
                        {"mu_c": 0.373744, "mu_s": 0.57857, "m_v": 87616.0, "J_v": 78450.0, "T_cm": 27.2353})
    assert r.supported and r.form is None
    # both forms tried (falling, building), neither supported
    assert [(e[1], e[2].supported) for e in d.form_results_] == [("falling", False), ("building", False)]
    entry = d.form_results_[0]
    assert entry[2].calibration.values_["a_cm"] > 0.3
    final = SimpleNamespace(values_=r.calibration.values_)
    fitted = SimpleNamespace(forms_={}, form_results_=d.form_results_, selected_=[FRICTION], min_delta_bic=10.0,
                             final_calibration_=final)
    (text,) = form_rival_texts(fitted, FRICTION)
    assert text.startswith("motor_coulomb_friction: in its falling form it fits this record about as well (a "
                           "friction of ") and "the record hardly tells the two apart" in text, text
    # a falling refit within twice the BIC threshold still tells its story (red team 14's F14: +11.9), beyond
    # it not; nor does one that ends where the constant friction is (a_cm under 0.3, the burden within 1 %)
    ev = entry[2]
    for dbic, a_cm, m_v, said in ((11.9, 0.58, 1.0, True), (25.0, 0.58, 1.0, False), (5.0, 0.27, 1.017, True),
                                  (5.0, 0.27, 1.005, False)):
        values = dict(ev.calibration.values_, a_cm=a_cm, m_v=m_v * final.values_["m_v"])
        moved = SimpleNamespace(**dict(vars(ev), delta_bic=dbic, calibration=SimpleNamespace(values_=values)))
        tried = SimpleNamespace(**dict(vars(fitted), form_results_=[[FRICTION, "falling", moved, False, ()]]))
        assert bool(form_rival_texts(tried, FRICTION)) == said, (dbic, a_cm, m_v)
    # an effect selected after the friction is named as a possible part of its story (red team 14's F4: a
    # second motor after a friction that falls only above half speed)
    after = SimpleNamespace(**dict(vars(fitted), selected_=[FRICTION, "second_motor"]))
    (text,) = form_rival_texts(after, FRICTION)
    assert "second_motor, added after it, may stand in for the rest of that story" in text
    # kept in its falling form, or with nothing tried, there is nothing to say
    assert form_rival_texts(SimpleNamespace(**dict(vars(fitted), forms_={FRICTION: "falling"})), FRICTION) == []
    assert form_rival_texts(SimpleNamespace(**dict(vars(fitted), form_results_=[])), FRICTION) == []


def test_a_form_kept_in_a_model_with_stick_slip_on_a_held_out_gain_within_noise_is_cautioned():
    # red team 15's E8 (its own plant: a constant motor friction of 150 N m, the torque friction law, the burden
    # 434.3 t): the falling form kept against the constant one at dBIC -276.8 (whitened -147.0), held-out +1.3 %
    # at 1.3 standard errors, the burden 443.7 t against the constant form's 437.3 t; the numbers are that
    # run's (diagnose.json), the rule's truth is the probe in form_kept_texts' docstring (the constant form
    # reaches a cost 3.2 % lower from the plant's values than from the diagnosis' starts)
    ev = SimpleNamespace(delta_bic=-276.8, delta_bic_corrected=-147.0, holdout_gain=1.2536, holdout_z=1.3132)
    own = {"mu_c": 0.36731, "mu_s": 0.44154, "m_v": 437294.9, "J_v": 1152066.3, "T_cm": 136.74}
    final = SimpleNamespace(values_={"mu_c": 0.36729, "mu_s": 0.44169, "m_v": 443735.4, "J_v": 1165027.7,
                                     "T_cm": 162.67, "a_cm": 0.4595})
    d = SimpleNamespace(forms_={FRICTION: "falling"}, selected_=[FRICTION], stick_slip_=True, holdout_z=2.0,
                        form_results_=[[FRICTION, "falling", ev, True, (), own]], final_calibration_=final)
    (text,) = form_kept_texts(d, FRICTION)
    assert text.startswith("motor_coulomb_friction: kept in its falling form (a friction of 163 N*m at rest "
                           "falling by 46 % at the set speed, against a constant 137 N*m, with a burden of "
                           "443.7 t against 437.3 t in its own form), which fitted better (dBIC -276.8"), text
    assert "gain +1.3 %, 1.3 standard errors" in text and "Either form may be right." in text
    # nothing to say: without stick-slip (the BIC stands: red team 14's falling frictions at 1.0-1.7 standard
    # errors, rightly kept), with a held-out gain beyond holdout_z, in the effect's own form, with the form
    # tried but not kept, or where the form tells the constant friction's story (a_cm under 0.3, burden within 1 %)
    quiet = [dict(stick_slip_=False), dict(holdout_z=1.0), dict(forms_={}),
             dict(form_results_=[[FRICTION, "falling", ev, False, (), own]]),
             dict(final_calibration_=SimpleNamespace(values_=dict(final.values_, a_cm=0.2, m_v=own["m_v"] * 1.005)))]
    for change in quiet:
        assert form_kept_texts(SimpleNamespace(**dict(vars(d), **change)), FRICTION) == [], change


def test_a_friction_gone_by_the_set_speed_names_what_fades_with_the_time():
    # red team 21's X1 (its own plant, outside the catalogue: the motor field at 55 % at the ramp start, restored
    # with 1.6 s) was selected as a motor friction in its falling form, 141 N*m at rest falling by 100 % (a_cm
    # 1.0): along one ramp the speed grows with the time, so an excess that fades with the time draws the same
    # current (truth: the red team's plant, truth.json). Said from a_cm 0.8 on; not for a friction that keeps a
    # fifth or more at the set speed, nor for the constant form
    final = SimpleNamespace(values_={"mu_c": 0.3455, "mu_s": 0.4415, "m_v": 7.894e5, "J_v": 2.8e6, "T_cm": 141.0,
                                     "a_cm": 1.0})
    d = SimpleNamespace(forms_={FRICTION: "falling"}, final_calibration_=final)
    (text,) = form_also_texts(d, FRICTION)
    assert text.startswith("motor_coulomb_friction in its falling form: the friction, 100 % gone at the set "
                           "speed, is a current above the model at the start"), text
    assert "a motor field weakened at standstill and restored as the ramp starts" in text
    assert text.endswith("A record where they act differently (another ramp rate or set speed) decides.")
    low = SimpleNamespace(values_=dict(final.values_, a_cm=0.7))
    assert form_also_texts(SimpleNamespace(forms_={FRICTION: "falling"}, final_calibration_=low), FRICTION) == []
    assert form_also_texts(SimpleNamespace(forms_={}, final_calibration_=final), FRICTION) == []


@pytest.mark.parametrize("whitened, supported", [(3.4, False), (-0.4, True)])
def test_any_rise_of_the_whitened_bic_voids_a_held_out_gain_where_the_model_fits_within_noise(
        monkeypatch, whitened, supported):
    # R16's unbalance refit (plain dBIC below -100, held-out gain above 6 %, the current model above 90 %)
    # judged with BIC under the coloured noise as red team 15's X1 had it (+3.4: an unbalance standing in for a
    # load step, held-out +33.5 % at 2.8 standard errors; wrong) and as the benchmark's weak true unbalance had
    # it (-0.4, plant:unbalance/s2; right).  Truth: those two diagnoses' verdicts; the rest of the judgement is
    # R16's own
    from kilnctl.measure import evidence

    monkeypatch.setattr(evidence, "whitened_delta_bic", lambda *a, **k: whitened)
    r, now = _judged("R16", {"mu_c": 0.37176, "mu_s": 0.48329, "m_v": 91897.2, "J_v": 74786.7},
                     {"mu_c": 0.374915, "mu_s": 0.386432, "m_v": 91159.8, "J_v": 81528.8}, "kiln_unbalance",
                     {"mu_c": 0.374951, "mu_s": 0.614045, "m_v": 91329.7, "J_v": 81678.1, "T_unb": 3635.9,
                      "phi_unb": 2.6212})
    assert now.fit_percent_["current_A"] > 90.0 and r.delta_bic < -100 and r.holdout_gain > 6.0
    assert r.delta_bic_corrected == whitened
    assert r.supported is supported, r.reason
    if not supported:
        assert "slowly correlated noise" in r.reason, r.reason
