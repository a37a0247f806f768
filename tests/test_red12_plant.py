"""Red team 12's independent plant (benchmarks/red12_plant.py: scipy DOP853 between its own burden switches) as
the truth for the evidence rules on records where the model already fits within noise.

The red team measured its plant against kilnctl's model at 0.0024-0.0035 A rms on its two kilns (no effect, no
noise).  Its R16 has no effect at all, under AR(1) noise correlated over 3 s; its R07 has a support-roller
friction lifting off in the first second, outside the catalogue.  The diagnosis took a kiln unbalance on R16
and a motor Coulomb friction on R07, with no word of doubt.  Here the candidates are refitted from the
diagnosis' own values of that run (diagnose.json at 27cb9fb), and judged as the diagnosis judges them.
"""

from benchmarks.red12_plant import record
from kilnctl import Parameters
from kilnctl.measure import Measurement, compare
from kilnctl.measure.calibrate import holdout_masks
from kilnctl.measure.diagnose import Diagnosis
from kilnctl.measure.runner import CHANNELS

SETUP_KEYS = ("R_a", "L_a", "k_i", "k_b", "J_m", "B_m", "k_p", "k_I", "k_D", "ramp_rate", "omega_ref", "V_max",
              "I_max", "J_o", "J_v", "m_v", "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg", "n",
              "friction_law")


def _judged(name, baseline, current_values, effect, values):
    """The record, the diagnosis' scales from its baseline values, and the candidate judged against the current
    model (both refitted from the given values on the fitting part)."""
    t, current, speed, ref, setup, _ = record(name)
    params = Parameters(gains="given", **{k: setup[k] for k in SETUP_KEYS})
    m = Measurement.from_arrays(t, current, speed, ref, source=f"red12 {name}", params=params)
    d = Diagnosis(params)
    exp = m.experiment(params)
    base = compare(m, params.replace(**baseline))
    scales = {c: base.channels[c].rms for c in CHANNELS}
    train, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    now = d._calibrate(m, params, (), scales, train, current_values, experiment=exp)
    cal = d._calibrate(m, params, (effect,), scales, train, values, experiment=exp)
    return d._evidence(m, effect, cal, now, scales, train, test, exp, 0.0), now


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


def test_a_large_held_out_loss_is_no_support_where_the_model_fits_within_noise():
    # R07: kiln F, a support-roller friction of 150 kN m lifting off over 0.008 rad/s of kiln speed (outside the
    # catalogue); the diagnosis' values at round 1: the current model at 95.8 %, the motor Coulomb friction
    # refit at 29.7 N m
    r, now = _judged("R07", {"mu_c": 0.394841, "mu_s": 0.513294, "m_v": 308166.9, "J_v": 569860.5},
                     {"mu_c": 0.399061, "mu_s": 0.518779, "m_v": 306011.4, "J_v": 564111.8},
                     "motor_coulomb_friction",
                     {"mu_c": 0.408275, "mu_s": 0.530757, "m_v": 294859.2, "J_v": 539036.6, "T_cm": 29.73})
    assert now.fit_percent_["current_A"] > 90.0
    assert r.delta_bic < -10.0 and r.delta_bic_corrected < -10.0, (r.delta_bic, r.delta_bic_corrected)
    assert r.holdout_gain < -10.0, r.holdout_gain
    assert not r.supported and "predicted worse by" in r.reason, r.reason
