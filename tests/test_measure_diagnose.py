"""Diagnosis on small synthetic records with a known hidden effect (deterministic, seeded).

Truth for every check: the plant that generated the record (its hidden effect
and the value of the effect's parameter).  The full statistical version is
``benchmarks/diagnose_confusion.py``.
"""

import argparse
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.errors import ModelError, NotFittedError
from kilnctl.measure.cautions import drift_texts, effect_cautions, setup_cautions
from kilnctl.measure.diagnose import Diagnosis
from kilnctl.measure.stats import variance_inflation
from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

SETUP = Parameters(DEFAULT_GAINS)
FEW = ("second_motor", "viscous_drag", "kiln_unbalance", "speed_sensor_lag")


@pytest.fixture(scope="module")
def second_motor_case():
    m, truth = make_record(("second_motor",), seed=3, magnitudes={"J_m2": 30.0}, mismatch=("mu_c", "J_o"),
                           t_end=24.0)
    return m, truth, Diagnosis(SETUP, candidates=FEW).fit(m)


@pytest.mark.slow  # the shared second-motor diagnosis takes about 40 s; test_diagnose_cli_json covers diagnose in the fast tier
def test_hidden_second_motor_is_found_and_its_inertia_recovered(second_motor_case):
    m, truth, d = second_motor_case
    assert d.selected_ == ["second_motor"]
    assert d.ranking_[0].effect == "second_motor" and d.ranking_[0].supported
    # truth: J_m2 = 30 kg m^2 in the generating plant
    assert d.final_calibration_.values_["J_m2"] == pytest.approx(30.0, rel=0.10)
    assert d.final_["current_A"] > d.baseline_["current_A"] + 3.0
    assert "current fit rose from" in d.headline() and "J_m2" in d.headline()


@pytest.mark.slow  # the shared second-motor diagnosis takes about 40 s; test_diagnose_cli_json covers diagnose in the fast tier
def test_json_has_the_documented_keys(second_motor_case):
    _, _, d = second_motor_case
    out = json.loads(json.dumps(d.to_dict(), allow_nan=False))
    for key in ("baseline", "ranking", "selected", "final", "unexplained", "caveats"):
        assert key in out
    r = out["ranking"][0]
    for key in ("effect", "delta_bic", "fit_percent", "parameters", "on_bound"):
        assert key in r
    assert r["parameters"]["J_m2"]["stderr"] is not None


@pytest.fixture(scope="module")
def second_motor_report(second_motor_case, tmp_path_factory):
    """The second-motor diagnosis' report, written once: (files written, folder)."""
    folder = tmp_path_factory.mktemp("report") / "rep"
    return second_motor_case[2].report(folder), folder


@pytest.mark.slow  # the shared second-motor diagnosis takes about 40 s; test_diagnose_cli_json covers diagnose in the fast tier
def test_report_is_one_self_contained_page(second_motor_report):
    files, folder = second_motor_report
    html = (folder / "diagnose.html").read_text()
    assert html.count("data:image/png;base64,") == 2 and 'src="http' not in html
    assert {p.name for p in files} >= {"diagnose.html", "diagnose.json"}
    # truth: the PNG files written beside the page; each figure is drawn once, so the page shows those bytes
    import base64
    import re

    inline = [base64.b64decode(b) for b in re.findall(r'src="data:image/png;base64,([^"]+)"', html)]
    assert inline == [(folder / n).read_bytes() for n in ("diagnose_signals.png", "diagnose_ranking.png")]


def test_nothing_hidden_selects_nothing():
    # truth: the plant is the base model with +-5 % mismatch in two base parameters and coloured noise
    m, _ = make_record((), seed=5, mismatch=("mu_c", "J_v"), t_end=24.0)
    d = Diagnosis(SETUP, candidates=FEW[:3]).fit(m)
    assert d.selected_ == []
    assert d.final_ == d.baseline_


def test_variance_inflation_of_white_and_ar1_noise():
    import numpy as np

    rng = np.random.default_rng(0)
    e = rng.standard_normal(40000)
    assert variance_inflation(e) == pytest.approx(1.0, abs=0.1)  # truth: white noise, no inflation
    x = np.zeros_like(e)
    for k in range(1, e.size):
        x[k] = 0.8 * x[k - 1] + e[k]
    # truth: AR(1) with phi = 0.8 inflates the variance of a sum by (1 + phi)/(1 - phi) = 9
    assert variance_inflation(x) == pytest.approx(9.0, rel=0.15)


def test_a_script_without_a_main_guard_gets_the_fix_not_a_broken_pool(tmp_path):
    # truth: Python's spawn start method imports the calling script in every worker; a script whose code is not
    # under `if __name__ == "__main__":` makes each worker stop at once, and the pool reports only
    # "BrokenProcessPool: A process in the process pool was terminated abruptly" (seen on a user's script).
    from conftest import failing_script

    last = failing_script(tmp_path, "from kilnctl import Parameters\n"
                                    "from kilnctl.measure.diagnose import Diagnosis\n"
                                    "from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record\n"
                                    "m, _ = make_record((), seed=1, t_end=8.0, fs=20.0)\n"
                                    "d = Diagnosis(Parameters(DEFAULT_GAINS), candidates=['viscous_drag', "
                                    "'second_motor'], workers=2)\n"
                                    "d.fit(m)\n")
    assert last.startswith("kilnctl.errors.WorkerError: Diagnosis(workers=2): a worker process ended abruptly")
    assert 'if __name__ == "__main__":' in last and "workers=1" in last


def test_unfitted_and_unknown_candidate():
    with pytest.raises(NotFittedError):
        Diagnosis(SETUP).to_dict()
    with pytest.raises(ModelError, match="second_motor"):
        Diagnosis(SETUP, candidates=["second_motr"])


@pytest.fixture(scope="module")
def cli_run(tmp_path_factory):
    """``kilnctl diagnose --json --report`` on a small record: (JSON output, report folder)."""
    import contextlib
    import io

    from kilnctl.cli import diagnose_cmd

    tmp_path = tmp_path_factory.mktemp("cli")
    m, _ = make_record(("viscous_drag",), seed=8, magnitudes={"B_o": 6e6}, t_end=20.0)
    data = tmp_path / "rec.csv"
    m.to_csv(data)
    cfg = tmp_path / "setup.toml"
    cfg.write_text('[controller]\ngains = "given"\nk_p = 2.0\nk_I = 5.0\nk_D = 0.01\n'
                   '[measurement]\ncandidates = ["viscous_drag", "second_motor"]\n')
    ap = argparse.ArgumentParser()
    diagnose_cmd.register(ap.add_subparsers())
    args = ap.parse_args(["diagnose", "--data", str(data), "--config", str(cfg), "--json",
                          "--report", str(tmp_path / "rep")])
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        assert args.func(args) == 0
    return json.loads(buf.getvalue()), tmp_path / "rep"


def test_diagnose_cli_json(cli_run):
    out, _ = cli_run
    assert out["selected"] == ["viscous_drag"]
    # truth: B_o = 6e6 N m s/rad in the plant
    assert out["final_parameters"]["B_o"]["value"] == pytest.approx(6e6, rel=0.10)


def test_diagnose_report_loads_in_a_browser(cli_run, load_in_chromium):
    # the fast tier's browser check of diagnose.html: no errors, both figures decode, fits a 1300 px window
    _, rep = cli_run
    text = (rep / "diagnose.html").read_text()
    assert "± inf" not in text and "{'" not in text and "How to read this" in text
    page = load_in_chromium(rep / "diagnose.html")
    assert page["errors"] == [] and page["broken_images"] == [] and page["images"] == 2
    assert page["page_width"] <= 1300


@pytest.mark.slow  # about 40 s (micro model calibration)
def test_backlash_impact_is_located_to_a_fraction_of_a_millimetre():
    # truth: the plant is the micro model with a 9.5 mm gap, half-way between two points of the 80-point start
    # grid.  The impact is a spike one sample long, so the cost in delta_x is a valley 0.3 mm wide: found only
    # through the smoothed residual (without it, nothing was selected and the fit stayed at 72 %)
    m, truth = make_record(("backlash",), seed=100, magnitudes={"delta_x": 0.0095}, t_end=12.0)
    d = Diagnosis(SETUP, candidates=["backlash"]).fit(m)
    assert d.selected_ == ["backlash"]
    assert d.final_calibration_.values_["delta_x"] == pytest.approx(0.0095, rel=0.02)


def test_current_limit_close_to_the_setup_value_is_found():
    # truth: I_max = 778 A in the plant, 1500 A in the setup; the measured peak is within a factor e of the
    # setup's value, which once kept the best start from getting a local fit
    m, truth = make_record(("current_limit",), seed=100, magnitudes={"I_max": 778.0}, t_end=15.0)
    d = Diagnosis(SETUP, candidates=["current_limit"]).fit(m)
    assert d.selected_ == ["current_limit"]
    assert d.final_calibration_.values_["I_max"] == pytest.approx(778.0, rel=0.01)


def test_a_candidate_whose_gain_is_a_better_base_fit_is_not_supported():
    # truth: nothing is hidden.  The current model is the base left at a poor mu_c (one evaluation); the
    # candidate adds a second motor but its refit starts from the plant's values, so it fits far better with
    # J_m2 near 0.  Against the poor fit that looks like evidence; re-anchoring must see through it.
    from kilnctl.measure.calibrate import Calibration, holdout_masks
    from kilnctl.simulate import resolve_gains

    m, truth = make_record((), seed=11, mismatch=("mu_c",), t_end=20.0)
    d = Diagnosis(SETUP, candidates=["second_motor"])
    params = resolve_gains(SETUP)
    exp = m.experiment(params)
    train, test = holdout_masks(m, "blocks", 0.3, t0=exp.t0)
    scales = {"current_A": 10.0, "speed_rpm": 0.5}
    poor = Calibration(params, d.calibrate, scales=scales, max_nfev=1).fit(
        m, mask=train, init={"mu_c": 0.9 * truth["plant"]["mu_c"]}, starts=[], n_local=1, experiment=exp)
    cand = Calibration(params, list(d.calibrate) + ["J_m2"], effects=("second_motor",), scales=scales).fit(
        m, mask=train, init=dict(truth["plant"], J_m2=0.0), starts=[], n_local=1, experiment=exp)
    r = d._evidence(m, "second_motor", cand, poor, scales, train, test, exp, 0.0)
    assert r.supported and cand.values_["J_m2"] < 2.0
    current, results = d._reanchor(m, params, [], poor, [r], scales, train, test, exp, lambda s: None)
    assert current.cost_ < poor.cost_
    assert not results[0].supported


@pytest.mark.slow  # about 15 s
def test_unbalance_in_a_record_shorter_than_a_revolution_comes_with_a_caution():
    # truth: the plant has an unbalance of 3e5 N m; the record (20 s) is a sixth of a kiln revolution
    # (60 n / omega_ref = 129 s with Table 1), where the unbalance is a slow drift a sensor offset also makes
    m, _ = make_record(("kiln_unbalance",), seed=4, magnitudes={"T_unb": 3e5, "phi_unb": 1.0}, t_end=20.0)
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"]).fit(m)
    assert d.selected_ == ["kiln_unbalance"]
    assert any("slow drift" in c and "129 s" in c for c in d.caveats_)
    assert d.to_dict()["caveats"] == d.caveats_
    assert "caution: kiln_unbalance" in d.summary()


# --- cautions: the exact text a user reads, for effects with and without a period ----------------------------
def _selected(name, dbic_corr, values=None):
    """A Diagnosis whose first round selected ``name`` with the given corrected dBIC (no fit run)."""
    from kilnctl.measure.diagnose import CandidateResult

    d = Diagnosis(SETUP)
    d.selected_ = [name]
    d.rounds_ = [[CandidateResult(name, -500.0, 20.0, {}, {}, {}, [], [], True, "", 0.0,
                                  delta_bic_corrected=dbic_corr)]]
    d.final_calibration_ = SimpleNamespace(values_=dict(values or {}))
    return d


def _exp(omega_ref=500.0):
    from kilnctl.measure.io import Experiment

    return Experiment(t0=0.0, ramp_rate=74.0, omega_ref=omega_ref, source="test")


def test_caution_of_an_effect_without_a_period():
    # truth: second_motor has no period (Effect.period is None): a strong one gets no caution at all, a weak one
    # only the autocorrelation caution -- never a "0.00 of its period (inf s)" text (issue 12, item 4)
    m, _ = make_record((), seed=0, t_end=4.0)
    exp = _exp()
    assert effect_cautions(_selected("second_motor", -300.0), m, exp, SETUP) == []
    weak = effect_cautions(_selected("second_motor", -4.0), m, exp, SETUP)
    assert weak == ["second_motor: the evidence is weak once the residual's autocorrelation is allowed for "
                    "(whitened dBIC -4.0 against the threshold -10); small effects (a few-millisecond sensor lag, "
                    "a stiff drive train) are often like this, but so is an effect that fits slow noise."]
    for name in ("second_motor", "viscous_drag", "backlash", "current_limit", "speed_sensor_lag",
                 "drivetrain_compliance", "torque_friction_law"):
        for text in effect_cautions(_selected(name, -4.0), m, exp, SETUP):
            assert "period" not in text and "inf" not in text and " ." not in text


def test_caution_of_an_effect_with_a_period():
    # truth: one kiln revolution at the set speed is 60 n / omega_ref = 60 * 1076.5 / 500 = 129 s (Table 1's
    # reduction); a record of 40 s is 40 / 129.2 = 0.31 of it
    from kilnctl.measure.cautions import caution_texts
    from kilnctl.measure.effects import CATALOGUE

    note = CATALOGUE["kiln_unbalance"].short_record_note
    period = 60.0 * SETUP.n / 500.0
    assert period == pytest.approx(129.2, abs=0.1)
    m, _ = make_record((), seed=0, t_end=40.02)
    exp = _exp()
    strong = effect_cautions(_selected("kiln_unbalance", -300.0), m, exp, SETUP)
    assert strong == ["kiln_unbalance was selected on a record of 40 s, 0.31 of its period (129 s): there it is "
                      + note + ". A record longer than one period tells them apart."]
    weak = effect_cautions(_selected("kiln_unbalance", -4.0), m, exp, SETUP)
    assert weak == ["kiln_unbalance was selected on a record of 40 s, 0.31 of its period (129 s): there it is "
                    + note + "; its evidence is weak once the residual's autocorrelation is allowed for "
                    "(whitened dBIC -4.0). A record longer than one period tells them apart."]
    # a record longer than the period: only the weak-evidence caution remains
    assert caution_texts("kiln_unbalance", 200.0, period, note, -300.0, 10.0) == []
    assert caution_texts("kiln_unbalance", 200.0, period, note, -4.0, 10.0)[0].startswith(
        "kiln_unbalance: the evidence is weak")
    # a periodic effect without a note still reads as a sentence
    assert caution_texts("x", 10.0, 20.0, "", -300.0, 10.0) == [
        "x was selected on a record of 10 s, 0.50 of its period (20 s): only part of a cycle is seen, which other "
        "causes can also produce. A record longer than one period tells them apart."]
    # no period, or a non-finite one, never gives a period caution
    assert caution_texts("x", 10.0, None, "", -300.0, 10.0) == []
    assert caution_texts("x", 10.0, float("inf"), "", -300.0, 10.0) == []


def test_every_periodic_catalogue_effect_says_what_else_makes_its_signature():
    # truth: the catalogue's own declarations; a period without a note would leave the caution without its reason
    from kilnctl.measure.effects import CATALOGUE

    for eff in CATALOGUE.values():
        if eff.period is not None:
            assert eff.short_record_note and not eff.short_record_note.endswith(".")


@pytest.mark.slow  # needs the shared second-motor diagnosis (about 40 s)
def test_report_reads_without_statistics_and_loads_in_a_browser(second_motor_case, second_motor_report,
                                                                 load_in_chromium):
    _, _, d = second_motor_case
    _, folder = second_motor_report
    text = (folder / "diagnose.html").read_text()
    assert "± inf" not in text and "+- inf" not in text and "{'" not in text  # no infinities, no Python dicts
    # truth: the diagnosis' own thresholds are the ones the how-to-read box explains
    assert f"below −{d.min_delta_bic:g}" in text and f"more than {d.min_holdout_gain:g} %" in text
    assert "Missing from the model: second motor" in text
    out = load_in_chromium(folder / "diagnose.html")
    assert out["errors"] == [] and out["broken_images"] == [] and out["images"] == 2
    assert out["page_width"] <= 1300


def test_a_value_outside_the_usual_range_is_reported_in_words_not_refused():
    # truth: the catalogue's usual range of a second motor's inertia is 10-45 kg m^2 (the paper's motor: 21.5)
    from kilnctl.measure.effects import CATALOGUE

    m, _ = make_record((), seed=0, t_end=4.0)
    d = _selected("second_motor", -300.0, {"J_m2": 8.0})
    assert effect_cautions(d, m, _exp(), SETUP) == [
        "second_motor: J_m2 = 8 kg*m^2, below the usual 10-45 kg*m^2 (a value outside the usual range is reported, "
        "not refused)"]
    assert effect_cautions(_selected("second_motor", -300.0, {"J_m2": 21.5}), m, _exp(), SETUP) == []
    assert CATALOGUE["viscous_drag"].plausibility({"B_o": 3e7}) == [
        "B_o = 3e+07 N*m*s/rad, above the usual 2e+06-1e+07 N*m*s/rad"]
    # a range that is not in the parameter's unit (I_max as a fraction of the peak current) is not compared
    assert CATALOGUE["current_limit"].plausibility({"I_max": 800.0}) == []


def test_an_abrupt_change_outside_the_catalogue_ends_unexplained_with_its_time():
    # truth: nothing of the catalogue is hidden; the measured current steps by +60 A at t = 25 s while the drive
    # runs at its set speed (a load step or a sensor fault: no catalogued effect makes one).  A slow unbalance
    # torque can imitate part of it; it must be rejected with that reason and the step named as unexplained.
    import numpy as np

    from kilnctl.measure import Measurement

    m0, _ = make_record((), seed=21, mismatch=("mu_c", "m_v"), t_end=40.0)
    cur = m0.current + 60.0 * (m0.t >= 25.0)
    m = Measurement.from_arrays(m0.t, cur, m0.speed, m0.speed_ref, source="step at 25 s", params=SETUP)
    d = Diagnosis(SETUP, candidates=["kiln_unbalance", "viscous_drag"]).fit(m)
    assert d.selected_ == []
    assert d.unexplained_ is not None
    assert "abrupt change at t = 25.0 s" in d.unexplained_["text"]
    assert "+60 A" in d.unexplained_["hint"] or "+59 A" in d.unexplained_["hint"] or "+61 A" in d.unexplained_["hint"]
    # the JSON says where it comes from; its residual verdict stays the final residual's (red team 6: "structured"
    # true here and false under residual_signature, for the same final model)
    assert d.unexplained_["sources"][0] == "outside_change"
    assert d.unexplained_["structured"] == d.signature_["structured"]
    # every candidate says why it was not selected
    assert all(r.reason for r in d.ranking_)
    imitators = [r for r in d.ranking_ if "abrupt change at t = 25" in r.reason]
    assert imitators, [r.reason for r in d.ranking_]
    assert np.isfinite(d.final_["current_A"])


def _pulse_record():
    """Nothing of the catalogue hidden; the measured current rises by 40 A at 21 s and falls back at 30 s of a 45 s
    record while the drive runs at its set speed (a load carried up the shell that slumps back, as red team 18's
    X1: no catalogued effect does it)."""
    from kilnctl.measure import Measurement

    m0, truth = make_record((), seed=21, mismatch=("mu_c", "m_v"), t_end=45.0)
    cur = m0.current + 40.0 * ((m0.t >= 21.0) & (m0.t < 30.0))
    return Measurement.from_arrays(m0.t, cur, m0.speed, m0.speed_ref, source="pulse 21-30 s", params=SETUP), truth


def test_a_change_that_comes_and_goes_is_named_as_unexplained():
    # truth: the pulse the record was built with (_pulse_record: +40 A from 21 to 30 s).  The base model, fitted
    # through it, leaves about +34 A inside against the level outside; the candidates are not supported and the
    # residual's best pulse, 63 % of its variance, names it
    m, _ = _pulse_record()
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"]).fit(m)
    assert d.selected_ == []
    assert d.unexplained_ is not None and d.signature_["strongest"] == "a change from t = 21.0 to 30.0 s"
    assert d.unexplained_["hint"].startswith("a change outside the catalogue that comes and goes: the current "
                                             "moves by +3")
    assert "from t = 21.0 s to 30.0 s while the drive runs at its set speed" in d.unexplained_["hint"]


def test_the_final_check_replaces_a_kiln_unbalance_by_the_change_it_imitates():
    # truth: the pulse the record was built with (_pulse_record: +40 A from 21 to 30 s) and the plant's base
    # values.  A kiln unbalance fitted on the whole record follows part of the pulse (one period per kiln
    # revolution, 129 s here); refitted without it, with the pulse beside the base, the BIC and the BIC with the
    # coloured noise modelled both fall: the unbalance is removed, the pulse named with the edges and height it
    # was built with, and the base values fitted beside it are the plant's
    from kilnctl.measure import holdout_masks

    m, truth = _pulse_record()
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"])
    exp = m.experiment(SETUP, t0=d.t0)
    init = {k: float(SETUP[k]) for k in d.calibrate}
    final = d._calibrate(m, SETUP, ("kiln_unbalance",), "std", None, dict(init, T_unb=1e5, phi_unb=0.0), (), exp,
                         None, None, 1, True)
    assert abs(final.values_["T_unb"]) > 1e4  # it follows the pulse
    train, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    scales = {"current_A": 8.0, "speed_rpm": 1.0}
    kept, refit, gone, change = d._final_pulse(m, SETUP, ["kiln_unbalance"], final, scales, train, test, exp,
                                               lambda s: None)
    assert kept == [] and "T_unb" not in refit.values_
    assert change["kind"] == "pulse"
    assert change["t"] == pytest.approx(21.0, abs=0.1) and change["t_end"] == pytest.approx(30.0, abs=0.1)
    assert change["size_A"] == pytest.approx(40.0, abs=2.0) and change["delta_bic"] < -d.min_delta_bic
    (r,) = gone
    assert r.effect == "kiln_unbalance" and not r.supported and r.delta_bic > 0
    assert r.reason.startswith("removed in the final check: a change that comes and goes from t = 21.0 s to 30.0 s")
    for k in ("mu_c", "m_v"):
        assert refit.values_[k] == pytest.approx(truth["plant"][k], rel=0.02)


def _line_record(hz):
    """Nothing of the catalogue hidden; the measured current carries a sinusoid of 20 A at ``hz`` from the set
    speed's start on (red team 20's X1: an eccentric pinion's 8e4 N m at 0.105 Hz, 19.5 A)."""
    from kilnctl.measure import Measurement

    m0, truth = make_record((), seed=22, mismatch=("mu_c", "m_v"), t_end=45.0)
    swing = 20.0 * np.sin(2 * np.pi * hz * m0.t + 0.3) * (m0.t >= 10.0)
    return (Measurement.from_arrays(m0.t, m0.current + swing, m0.speed, m0.speed_ref, source=f"line {hz:g} Hz",
                                    params=SETUP), truth)


@pytest.mark.parametrize("kiln_turns", [False, True])
def test_the_final_check_replaces_a_drag_by_the_periodic_change_it_imitates(kiln_turns):
    # truth: the sinusoid the record was built with (_line_record: 20 A at 0.105 Hz, a period of 9.5 s, from
    # 10 s on) and the plant's base values.  A drag fitted on the whole record (B_o from ten times the usual,
    # as red team 20's X1 ended) stands in the final model; refitted without it, with a sinusoid at the
    # residual's line beside the base, both BICs fall: the drag is removed, the line named at the frequency and
    # size it was built with.  At the kiln's own turn frequency (a kiln unbalance's) nothing is tried
    from kilnctl.measure import holdout_masks

    d = Diagnosis(SETUP, candidates=["viscous_drag"])
    turn = SETUP.omega_ref / (60.0 * SETUP.n)
    m, truth = _line_record(turn if kiln_turns else 0.105)
    exp = m.experiment(SETUP, t0=d.t0)
    init = {k: float(SETUP[k]) for k in d.calibrate}
    final = d._calibrate(m, SETUP, ("viscous_drag",), "std", None, dict(init, B_o=3e6), (), exp, None, None, 1,
                         True)
    train, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    scales = {"current_A": 8.0, "speed_rpm": 1.0}
    kept, refit, gone, change = d._final_line(m, SETUP, ["viscous_drag"], final, scales, train, test, exp,
                                              lambda s: None)
    if kiln_turns:
        assert kept == ["viscous_drag"] and change is None and refit is final
        return
    assert kept == [] and "B_o" not in refit.values_
    assert change["kind"] == "line" and change["hz"] == pytest.approx(0.105, rel=0.03)
    assert change["amplitude_A"] == pytest.approx(20.0, rel=0.1) and change["delta_bic"] < -d.min_delta_bic
    (r,) = gone
    assert r.effect == "viscous_drag" and not r.supported
    assert r.reason.startswith("removed in the final check: a periodic change at 0.10")
    for k in ("mu_c", "m_v"):
        assert refit.values_[k] == pytest.approx(truth["plant"][k], rel=0.02)


def test_a_line_term_recovers_the_sinusoid_it_is_fitted_to():
    # truth by construction: 12 sin(w t) - 5 cos(w t) from 3 s on, plus white noise of 1 A
    from kilnctl.measure.outside import CurrentLine

    rng = np.random.default_rng(4)
    t = np.arange(0.0, 30.0, 0.02)
    w = 2 * np.pi * 0.2
    e = (12.0 * np.sin(w * t) - 5.0 * np.cos(w * t)) * (t >= 3.0) + rng.normal(0.0, 1.0, t.size)
    term = CurrentLine(0.2, 3.0)
    f = term.fit(t, e)
    assert f["sin"] == pytest.approx(12.0, abs=0.1) and f["cos"] == pytest.approx(-5.0, abs=0.1)
    assert f["amplitude"] == pytest.approx(13.0, abs=0.1) and f["rss"] == pytest.approx(t.size, rel=0.1)
    assert np.all(term.shape(t[t < 3.0], f) == 0.0)
    assert term.text(f).startswith("a periodic change at 0.2 Hz (a period of 5 s) from t = 3.0 s: the current "
                                   "swings by +-13 A")


def test_a_drifting_current_offset_is_not_taken_for_a_kiln_unbalance():
    # truth: nothing of the catalogue is hidden; the logged current carries an offset drifting 0.25 A/s from the
    # record's start (a current-sensor offset warming up: 35 A over 140 s, no torque).  A kiln unbalance (one
    # period per kiln revolution, 129 s here) imitates part of it; over a record longer than the period the
    # line explains the record better and is named as unexplained, with the rate it was built with.
    import numpy as np

    from kilnctl.measure import Measurement

    m0, _ = make_record((), seed=21, mismatch=("mu_c", "m_v"), t_end=140.0, fs=10.0)
    cur = m0.current + 0.25 * (m0.t - m0.t[0])
    m = Measurement.from_arrays(m0.t, cur, m0.speed, m0.speed_ref, source="drift 0.25 A/s", params=SETUP)
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"]).fit(m)
    assert d.selected_ == []
    change = d.unexplained_["outside_change"]
    # (0.21 A/s: the base values, fitted before, lean on part of the line)
    assert change["kind"] == "drift" and change["rate_A_per_s"] == pytest.approx(0.25, abs=0.05)
    assert d.unexplained_["text"].startswith("a slow drift of the current: +")
    assert "Suggests" not in d.unexplained_["text"]  # the final model's residual is described, not read again
    assert any("slow drift" in r.reason and r.effect == "kiln_unbalance" for r in d.ranking_)
    assert np.isfinite(d.final_["current_A"])


def test_a_kiln_unbalance_is_not_taken_for_a_drift(monkeypatch):
    # truth: the plant has a kiln unbalance of 2.5e5 N m (the usual 1e5-4e5) seen over 140 s, longer than one
    # kiln revolution (129 s); the drift hypothesis is tested against it and loses.  On a record shorter than the
    # period it is not tried (a sinusoid's fragment is nearly a line).
    m, truth = make_record(("kiln_unbalance",), seed=5, magnitudes={"T_unb": 2.5e5, "phi_unb": 1.0},
                           mismatch=("mu_c", "m_v"), t_end=140.0, fs=10.0)
    from kilnctl.measure.outside import CurrentDrift

    tried = []
    fit = CurrentDrift.fit
    monkeypatch.setattr(CurrentDrift, "fit", lambda self, t, e: tried.append(t[-1]) or fit(self, t, e))
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"]).fit(m)
    assert tried  # the hypothesis was fitted
    assert d.selected_ == ["kiln_unbalance"]
    assert d.outside_change_ is None
    assert d.final_calibration_.values_["T_unb"] == pytest.approx(2.5e5, rel=0.2)


def test_a_kiln_unbalance_sampled_at_100_hz_is_not_taken_for_an_abrupt_change(monkeypatch):
    # truth: the benchmark's independent plant ("plant:unbalance/s2" of benchmarks/diagnose_records.py: its own
    # unbalance form, T_unb 1.29e5 N m), here logged at 100 Hz instead of 50.  By BIC alone a current step at
    # 25.3 s explained it better (dBIC -602 against -584) and the diagnosis ended "unexplained"; the unbalance
    # predicts the held-out part better (+5.3 % against +3.3 %), and a change outside the catalogue must win
    # by every test.  A pulse in its place (the final check's) does not win either.
    import benchmarks.diagnose_records as dr

    monkeypatch.setattr(dr, "T_END", 40.0)
    monkeypatch.setattr(dr, "FS", 100.0)
    m, truth = dr.make(dr.find("plant:unbalance/s2"))
    from kilnctl.measure.outside import CurrentPulse

    tried = []
    fit = CurrentPulse.fit
    monkeypatch.setattr(CurrentPulse, "fit", lambda self, t, e: tried.append(t[-1]) or fit(self, t, e))
    d = Diagnosis(SETUP, candidates=["kiln_unbalance"]).fit(m)
    assert tried  # the final check tried the pulse in the unbalance's place, and it lost
    assert d.selected_ == ["kiln_unbalance"] and d.outside_change_ is None
    assert d.final_calibration_.values_["T_unb"] == pytest.approx(truth["catalogue_values"]["T_unb"], rel=0.15)


@pytest.mark.slow  # about 20 s: a micro-model diagnosis with two candidates
def test_a_backlash_behind_a_stiffer_link_than_assumed_is_fitted_in_its_coupling_form():
    # truth: the benchmark's independent plant ("plant:backlash/s1" of benchmarks/diagnose_records.py): a dead
    # zone of 1.6e-3 rad at the kiln (delta_x = gap R_o = 6.34 mm) in a stiff link, with no elastomeric coupling.
    # kilnctl's micro model puts its assumed coupling (k_c 1e5 N m/rad) behind the play, which rings at about
    # 11 Hz after the teeth meet where the plant does not: in its own form the backlash fitted 96.3 % and a
    # speed-sensor lag of 0.57 ms (dBIC -1512) was added beside it to damp that ring (97.6 %).  In its coupling
    # form (k_c, c_c fitted) it reaches 97.9 % alone, and the lag is not supported.
    import benchmarks.diagnose_records as dr

    m, truth = dr.make(dr.find("plant:backlash/s1"))
    d = Diagnosis(SETUP, candidates=["backlash", "speed_sensor_lag"]).fit(m)
    assert d.selected_ == ["backlash"]
    assert d.forms_ == {"backlash": "coupling"}
    values = d.final_calibration_.values_
    assert values["delta_x"] == pytest.approx(truth["catalogue_values"]["delta_x"], rel=0.03)
    assert values["k_c"] > 10 * SETUP.k_c  # a link far stiffer than the assumed coupling
    assert "backlash (coupling form)" in d.summary()


@pytest.mark.parametrize("k_c, c_c, pinned", [
    (9e8, 5e3, []),            # k_c 5 % below its upper bound: the coupling rigid, a physical limit of the form
    (1e7, 9.9e5, []),          # c_c at its upper bound: a coupling damped so hard it is rigid too
    (1.1e4, 5e3, ["k_c"]),     # k_c at its lower bound: a coupling softer than any elastomer, a stand-in
    (1e7, 1.2, ["c_c"]),       # c_c at its lower bound: an undamped coupling ringing for ever
])
def test_the_coupling_form_may_end_rigid_but_not_at_its_other_bounds(k_c, c_c, pinned):
    # truth: the ranges worked out by hand (k_c 1e4-1e9, c_c 1-1e6, log): 9e8 lies ln(1e9/9e8) = 0.11 from the
    # upper bound, under 5 % of ln(1e5) = 11.5 (0.58); 1.1e4 lies 0.10 above the lower; 9.9e5 0.01 below the
    # upper; 1.2 0.18 above the lower (5 % of ln(1e6) is 0.69).  A rigid link is what a plant without an
    # elastomeric coupling has, so only the soft and the undamped ends mark the form as a stand-in
    from kilnctl.measure.checks import _pinned
    from kilnctl.measure.effects import CATALOGUE

    form = CATALOGUE["backlash"].form("coupling")
    assert [(fp.name, fp.lower, fp.upper, fp.kind) for fp in form.parameters] == [
        ("k_c", 1e4, 1e9, "log"), ("c_c", 1.0, 1e6, "log")]
    assert _pinned(form, {"k_c": k_c, "c_c": c_c}) == pinned


@pytest.mark.parametrize("inside_cost, kept", [(0.31, True), (0.50, False)])
def test_a_form_the_final_search_took_to_a_bound_is_refitted_from_the_rounds_values(inside_cost, kept):
    # truth by construction (the logic only; the refits are stand-ins): red team 21's E3, where the backlash's
    # impact form fitted 98.6 % in its round with k_c 7.3e6 N m/rad and the final search ended at k_c 1.31e4,
    # within 5 % of the lower bound 1e4 (ln(1.31) = 0.27 < 0.05 ln(1e5) = 0.58).  From the rounds' values the
    # form is refitted on the whole record; it is kept when it fits at least as well as the effect in its own
    # form (the own form's refit here at cost 0.40), else the effect goes back to its own form with a caution
    from kilnctl.measure.checks import _pinned
    from kilnctl.measure.effects import CATALOGUE

    form = CATALOGUE["backlash"].form("impact")
    assert _pinned(form, {"C_e": 1e8, "k_c": 1.31e4, "c_c": 200.0}) == ["k_c"]
    assert _pinned(form, {"C_e": 1e9, "k_c": 7.3e6, "c_c": 2e5}) == []  # teeth stopping dead: a limit of the form
    d = Diagnosis(SETUP, model="micro")
    d._forms = {"backlash": "impact"}
    base = {"mu_c": 0.38, "mu_s": 0.57, "m_v": 7.8e5, "J_v": 2.9e6, "delta_x": 0.0098}
    final = SimpleNamespace(values_=dict(base, C_e=1e9, k_c=1.31e4, c_c=200.0), fit_percent_={"current_A": 98.6},
                            cost_=0.30)
    current = SimpleNamespace(values_=dict(base, C_e=1.2e8, k_c=7.3e6, c_c=2e5))
    seen = []

    def calibrate(m, params, effects, scales, mask, init, *a):
        seen.append((dict(d._forms), dict(init)))
        in_form = "C_e" in init
        return SimpleNamespace(values_=dict(init), cost_=inside_cost if in_form else 0.40,
                               fit_percent_={"current_A": 98.6 if in_form else 92.5})

    d._calibrate = calibrate
    out, notes = d._final_forms(None, SETUP, ("backlash",), final, None, lambda s: None, current)
    (forms_in, init_in), (forms_own, init_own) = seen
    assert forms_in == {"backlash": "impact"} and init_in["k_c"] == 7.3e6 and init_in["C_e"] == 1.2e8
    assert forms_own == {} and "k_c" not in init_own and init_own["delta_x"] == 0.0098
    if kept:
        assert out.values_["k_c"] == 7.3e6 and d._forms == {"backlash": "impact"} and notes == []
    else:
        assert out.fit_percent_["current_A"] == 92.5 and d._forms == {}
        (note,) = notes
        assert note.startswith("backlash was selected in its impact form, but at the final fit its k_c = 1.31e+04")


def test_a_soft_drive_train_is_found_where_the_base_values_made_up_for_it():
    # truth: the benchmark's independent plant (benchmarks/diagnose_records.py, its own two-mass drive train
    # with stiffness-proportional damping) with a drive train of k_po 2e7 N m/rad, 35 x softer than Table 1's
    # (a mode near 0.3 Hz), and C_po 4e5 N m s/rad.  The base calibration makes up for it (mu_c 0.69 where the
    # plant has 0.42, J_v -49 %), and about those values every start of the stiffness grid within 8 % of the
    # mode fitted worse than a rigid drive train: the two local fits went to the best-ranked, stiff starts and
    # the compliance ended rigid (dBIC +16), while a kiln unbalance took its place.  One local fit from the
    # best start of each decade of k_po (Effect.spread) ends at the plant's stiffness.
    import benchmarks.diagnose_records as dr

    spec = dr.RecordSpec("mag:compliance_soft/s1", "foreign", "plant", 1, plant={"k_tw": 2e7, "beta_tw": 0.02})
    m, truth = dr.make(spec)
    d = Diagnosis(SETUP, candidates=["drivetrain_compliance"]).fit(m)
    assert d.selected_ == ["drivetrain_compliance"]
    values = d.final_calibration_.values_
    assert values["k_po"] == pytest.approx(2e7, rel=0.05)
    assert values["mu_c"] == pytest.approx(truth["base"]["mu_c"], rel=0.05)


def test_an_effect_that_narrowly_won_its_round_is_swapped_for_the_better_rival():
    # truth: the benchmark's independent plant with a kiln unbalance (2.5e5 N m, its own eccentric-mass form)
    # and a viscous drag (B_o 5.3e6 N m s/rad at the kiln).  Over 40 s (0.31 of a revolution) the unbalance's
    # phase makes its torque nearly constant, and a motor Coulomb friction won the first round (whitened dBIC
    # -161 against -155); with the drag added next, the unbalance no longer earned its place and the selection
    # ended 0.14 points below the true structure.  The swap check puts the unbalance in the friction's place.
    import benchmarks.diagnose_records as dr

    spec = dr.RecordSpec("pair:drag+unbalance/s1", "foreign", "plant", 1,
                         plant={"B_kiln": 3e6, "B_motor": 2.0, "T_ecc": 2.5e5, "phi_ecc": 0.5})
    m, truth = dr.make(spec)
    d = Diagnosis(SETUP, candidates=["kiln_unbalance", "viscous_drag", "motor_coulomb_friction"]).fit(m)
    assert sorted(d.selected_) == ["kiln_unbalance", "viscous_drag"]
    assert d.swaps_ == {"kiln_unbalance": "motor_coulomb_friction"}
    assert any(r.effect == "motor_coulomb_friction" and "swap check" in r.reason for r in d.removed_)
    assert d.final_calibration_.values_["B_o"] == pytest.approx(truth["catalogue_values"]["B_o"], rel=0.2)
    # the report's round table says how the unbalance came in, and no rival caution has a negative gap
    from kilnctl.measure.report import candidate_verdict
    r0 = next(r for r in d.rounds_[0] if r.effect == "kiln_unbalance")
    assert candidate_verdict(d, 0, r0)[0] == "added by the swap check"
    assert not any("difference of only -" in c for c in d.caveats_)


def test_a_second_motor_below_the_usual_range_is_still_a_second_motor():
    # truth: the plant has a second motor of 8 kg m^2, below the catalogue's usual 10-45 kg m^2 (issue 12: it was
    # read as drive-train compliance).  The usual range may only be reported, never decide.
    m, truth = make_record(("second_motor",), seed=12, magnitudes={"J_m2": 8.0}, mismatch=("mu_c", "m_v"),
                           t_end=20.0)
    d = Diagnosis(SETUP, candidates=["second_motor", "drivetrain_compliance"]).fit(m)
    assert d.selected_ == ["second_motor"]
    # the ramp shows the total inertia it accelerates, J_m + J_m2 + kiln and burden referred to the motor
    # (21.5 + 8 + 7.5 = 37 kg m^2): J_m2 within 5 % of that
    assert d.final_calibration_.values_["J_m2"] == pytest.approx(8.0, abs=0.05 * 37.0)
    assert any("below the usual 10-45 kg*m^2" in c for c in d.caveats_)


def test_final_refit_reaches_the_structures_optimum_in_the_stick_slip_regime():
    # truth: the plant has the torque friction law (stick-slip cycles at steady speed) and a second motor of
    # 24.3 kg m^2; the oracle is the true structure fitted from the plant's own values.  A single local fit from
    # the setup's values stops in a valley far below it; the final refit (starts spread over the friction
    # regimes, growing horizons, the best kept) must reach it.
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.effects import effect_components
    from kilnctl.simulate import resolve_gains

    hidden = ("torque_friction_law", "second_motor")
    m, truth = make_record(hidden, seed=101, t_end=30.0)
    params = resolve_gains(SETUP)
    comps, p = effect_components(hidden, params)
    d = Diagnosis(SETUP)
    free = list(d.calibrate) + ["J_m2"]
    oracle_init = dict(truth["magnitudes"], **{k: v for k, v in truth["plant"].items() if k in d.calibrate})
    oracle = Calibration(p, free, effects=comps, max_nfev=d.max_nfev).fit(m, init=oracle_init, starts=[], n_local=1)
    setup_vals = {k: float(params[k]) for k in d.calibrate}
    single = Calibration(p, free, effects=comps, max_nfev=d.max_nfev).fit(
        m, init=dict(setup_vals, J_m2=0.0), starts=[], n_local=1)
    current = SimpleNamespace(values_=dict(setup_vals, J_m2=0.0), run_=single.run_)
    final = d._final_fit(m, params, hidden, current, m.experiment(params))
    best = oracle.fit_percent_["current_A"]
    assert single.fit_percent_["current_A"] < best - 5.0  # the record is a hard one
    assert final.fit_percent_["current_A"] > best - 0.5
    assert final.cost_ <= min(f["cost"] for f in final.local_fits_)  # the best refit is the one kept
    assert final.n_starts_ > 10 and len(final.local_fits_) >= 2


def test_no_weak_evidence_caution_when_the_held_out_gain_is_significant():
    # truth: the caution says the evidence is weak once autocorrelation is allowed for; a held-out gain of more
    # than holdout_z standard errors (which allow for it) confirms the effect, whatever the whitened BIC says
    # (it takes a poor model's misfit for noise: +1544 for the torque law on torque law + compliance)
    m, _ = make_record((), seed=0, t_end=4.0)
    d = _selected("torque_friction_law", +1544.0)
    assert len(effect_cautions(d, m, _exp(), SETUP)) == 1
    d.rounds_[0][0].holdout_z = d.holdout_z + 0.5
    assert effect_cautions(d, m, _exp(), SETUP) == []


def test_a_breakaway_a_few_milliseconds_off_is_timing_not_a_failure():
    """Truth by construction: a measured current that steps at t = 2.000 s and a model that steps at 2.010 s
    differ by the whole step on the samples in between, yet the model has the event; a pulse the model lacks
    altogether is a failure whatever the shift."""
    import numpy as np

    from kilnctl.measure.signature import EVENT_TIMING_S, _timing_only

    t = np.arange(0.0, 4.0, 0.005)
    measured = np.where(t >= 2.0, 800.0, 600.0)
    model = np.where(t >= 2.01, 800.0, 600.0)
    where = np.abs(measured - model) > 50.0
    assert where.sum() == 2  # two samples 200 A apart
    assert _timing_only(t, measured, model, where, limit=30.0)
    late = np.where(t >= 2.0 + 3 * EVENT_TIMING_S, 800.0, 600.0)  # 60 ms late: beyond the tolerance
    assert not _timing_only(t, measured, late, np.abs(measured - late) > 50.0, limit=30.0)
    pulse = measured + np.where((t >= 3.0) & (t < 3.05), 200.0, 0.0)
    assert not _timing_only(t, pulse, measured, np.abs(pulse - measured) > 50.0, limit=30.0)


@pytest.mark.parametrize("dip, words", [(-30.0, "falls behind the model's for"),
                                        (30.0, "runs ahead of the model's for")])
def test_a_speed_away_from_the_models_for_seconds_is_named_as_a_torque_the_model_lacks(dip, words):
    """Truth by construction: the generator's record with its measured speed moved by 30 rpm for 2.5 s
    (22-24.5 s, after the ramp) and compared with the plant's own values: the hint names that stretch, and a
    torque the model lacks; the untouched record names nothing of the kind."""
    import numpy as np

    from kilnctl.measure import Measurement, compare
    from kilnctl.measure.signature import residual_signature

    m0, truth = make_record((), seed=4, t_end=30.0)
    plant = SETUP.replace(**truth["plant"])
    exp = m0.experiment(SETUP)
    bump = dip * np.clip(np.minimum(m0.t - 22.0, 24.5 - m0.t) / 0.2, 0.0, 1.0)
    m = Measurement.from_arrays(m0.t, m0.current, m0.speed + bump, m0.speed_ref, source="speed moved",
                                params=SETUP)
    sig = residual_signature(compare(m, plant), SETUP.n, steady_from=exp.steady_from)
    assert sig["structured"] and sig["hint"].startswith(f"the measured speed {words}")
    assert "from t = 22." in sig["hint"] and ("less torque" if dip < 0 else "more torque") in sig["hint"]
    clean = residual_signature(compare(m0, plant), SETUP.n, steady_from=exp.steady_from)
    assert "measured speed" not in clean["hint"]


def test_an_oscillation_the_model_lacks_is_given_as_multiples_of_the_shafts_speeds():
    """Truth by construction: the generator's record with a 40 A ripple at 240 times the kiln's rotation added
    to the measured current after the ramp (the tooth passing of Table 1's girth gear, 2 R_o / module = 240
    teeth: 1.86 Hz at 500 rpm and n = 1076.5); the hint gives the order (within the spectrum's 0.1 Hz) and the
    motor's multiple."""
    import numpy as np

    from kilnctl.measure import Measurement, compare
    from kilnctl.measure.signature import residual_signature

    m0, truth = make_record((), seed=4, t_end=40.0)
    plant = SETUP.replace(**truth["plant"])
    exp = m0.experiment(SETUP)
    f_kiln = 500.0 / 60.0 / SETUP.n
    ripple = 40.0 * np.sin(2 * np.pi * 240 * f_kiln * m0.t) * (m0.t >= exp.steady_from)
    m = Measurement.from_arrays(m0.t, m0.current + ripple, m0.speed, m0.speed_ref, source="ripple", params=SETUP)
    hint = residual_signature(compare(m, plant), SETUP.n, steady_from=exp.steady_from)["hint"]
    assert hint.startswith("an oscillation near 1.8") or hint.startswith("an oscillation near 1.9"), hint
    order = float(hint.split("and about ")[1].split(" ")[0])
    assert abs(order - 240) <= 8
    assert float(hint.split("; it is ")[1].split(" ")[0]) == pytest.approx(240 / SETUP.n, abs=0.01)
    assert "(129 s a turn)" in hint
    # 0.22 of the motor's turn, resolved to a few hundredths: no whole multiple; the kiln's order, +-6 on this
    # record, is given as a tooth count to compare, not called whole (red team 9: a loop's ringing was said to
    # come from the kiln's shaft at 1602 +- 6 times its speed)
    assert "motor's rotation (8.3" in hint and "no whole multiple" in hint
    assert "cannot tell from a whole multiple" in hint and "it comes from that shaft" not in hint


def test_fit_points_of_an_interval_equal_the_fit_gained_by_removing_it():
    """Truth: fit % computed from its definition (kilnctl.measure.stats.fit_percent) with and without the
    interval's residual."""
    import numpy as np

    from kilnctl.measure.signature import fit_points
    from kilnctl.measure.stats import fit_percent

    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 10.0, 1001)
    y = 500.0 * np.minimum(t / 7.0, 1.0)
    model = y - rng.normal(0.0, 0.5, t.size)
    where = (t > 4.0) & (t < 6.0)
    model[where] -= 3.0
    e = y - model
    repaired = np.where(where, y, model)
    expected = fit_percent(y, repaired) - fit_percent(y, model)
    assert fit_points(y, e, where) == pytest.approx(expected, rel=1e-9)
    assert fit_points(y, e, np.zeros(t.size, bool)) == 0.0


@pytest.mark.slow  # two refits of a two-effect structure on top of the shared diagnosis
def test_backward_check_removes_an_effect_the_plant_does_not_have(second_motor_case):
    """Truth: the plant that made the record has a second motor and no viscous drag.  A selection of both
    (as a greedy search could end with, the drag added first) loses the drag in the backward check, and
    the second motor stays."""
    from kilnctl.simulate import resolve_gains

    m, truth, d = second_motor_case
    params = resolve_gains(d.params)
    exp = d.experiment_
    init = dict(d.final_calibration_.values_, B_o=2e5)
    both = d._calibrate(m, params, ("viscous_drag", "second_motor"), d.scales_, d.train_, init,
                        [dict(init, B_o=b) for b in (1e4, 1e6)], experiment=exp, n_local=2)
    selected, current, removed = d._backward(m, params, ["viscous_drag", "second_motor"], both, {}, d.scales_,
                                             d.train_, d.test_, exp, None, lambda s: None)
    assert selected == ["second_motor"]
    assert [r.effect for r in removed] == ["viscous_drag"]
    assert "backward check" in removed[0].reason
    assert "J_m2" in current.values_ and "B_o" not in current.values_


def test_backward_check_starts_each_smaller_structure_at_the_current_values():
    """Truth: the current model's values, given.  The structure without one effect is refitted from all of them
    that it has, the other effects' parameters included (they were once left out: the refit then began at
    the catalogue's default stiffness and damping, and a stand-in beside them looked needed)."""
    d = Diagnosis(SETUP)
    values = {"mu_c": 0.39, "mu_s": 0.49, "m_v": 5.6e5, "J_v": 1.6e6, "k_po": 8.2e7, "C_po": 6.4e5, "B_o": 8.0}
    seen = []

    def calibrations(args, pool):
        seen.extend(args)
        return [None] * len(args)  # none can be fitted: every effect stays, and the check ends

    d._first_failure = lambda *a: None
    d._run_calibrations = calibrations
    current = SimpleNamespace(values_=values)
    selected, kept, removed = d._backward(None, SETUP, ["drivetrain_compliance", "viscous_drag"], current, {},
                                          None, None, None, None, None, lambda s: None)
    assert selected == ["drivetrain_compliance", "viscous_drag"] and kept is current and removed == []
    inits = {a[2]: a[5] for a in seen}
    base = {k: values[k] for k in ("mu_c", "mu_s", "m_v", "J_v")}
    assert inits[("viscous_drag",)] == dict(base, B_o=8.0)
    assert inits[("drivetrain_compliance",)] == dict(base, k_po=8.2e7, C_po=6.4e5)
    # an amplitude fitted with its phase: the phase is kept too (it was reset to 0, 1.85 rad off on the hard
    # set's torque law + unbalance s2, and a stiff, heavily damped compliance beside the unbalance looked needed)
    seen.clear()
    current = SimpleNamespace(values_=dict(values, T_unb=2.2e5, phi_unb=1.85))
    d._backward(None, SETUP, ["drivetrain_compliance", "kiln_unbalance"], current, {}, None, None, None, None,
                None, lambda s: None)
    inits = {a[2]: a[5] for a in seen}
    assert inits[("kiln_unbalance",)] == dict(base, T_unb=2.2e5, phi_unb=1.85)


@pytest.mark.slow  # two evaluations and a refit of a two-effect structure on top of the shared diagnosis
def test_final_check_removes_an_effect_left_at_its_null_value(second_motor_case):
    """Truth: the plant has a second motor of 30 kg m^2 and no drag.  A final model holding a drag at its lower
    bound (1000 N m s/rad, a thousandth of the usual) beside the second motor loses the drag in the final
    check; the second motor, which the record needs, stays, and the rest is refitted from the final values."""
    from kilnctl.simulate import resolve_gains

    m, truth, d = second_motor_case
    params = resolve_gains(d.params)
    exp = d.experiment_
    init = dict(d.final_calibration_.values_, B_o=1e3)
    both = d._calibrate(m, params, ("second_motor", "viscous_drag"), "std", None, init, (), exp, None, None, 0,
                        True)
    assert both.values_ == pytest.approx(init, rel=1e-12)
    selected, final, dropped = d._final_check(m, params, ["second_motor", "viscous_drag"], both, d.scales_,
                                              d.train_, d.test_, exp, lambda s: None)
    assert selected == ["second_motor"]
    assert [r.effect for r in dropped] == ["viscous_drag"] and not dropped[0].supported
    assert "final check" in dropped[0].reason and dropped[0].delta_bic > -d.min_delta_bic
    assert dropped[0].to_dict()["holdout_gain_percent"] is None  # the final fit held nothing out
    start = {k: v for k, v in init.items() if k != "B_o"}
    without = d._calibrate(m, params, ("second_motor",), "std", None, start, (), exp, None, None, 0, True)
    assert "B_o" not in final.values_ and final.cost_ <= without.cost_
    assert final.values_["J_m2"] == pytest.approx(truth["magnitudes"]["J_m2"], rel=0.2)


def test_a_current_offset_at_standstill_is_reported_and_a_clean_record_says_nothing():
    """Truth by construction: 2 s at rest (white noise of 4 A on the current) put before a synthetic start-up,
    once with +25 A added to every current sample (a sensor offset) and once without."""
    import numpy as np

    from kilnctl.measure.standstill import standstill_offsets
    from kilnctl.measure.io import Measurement

    m, _ = make_record((), seed=1, t_end=12.0)
    rng = np.random.default_rng(7)
    t_rest = np.arange(-2.0, 0.0, 0.02)
    found = {}
    for offset in (0.0, 25.0):
        cur = np.concatenate([rng.normal(0.0, 4.0, t_rest.size), m.current]) + offset
        spd = np.concatenate([rng.normal(0.0, 0.3, t_rest.size), m.speed])
        ref = np.concatenate([np.zeros(t_rest.size), m.speed_ref])
        rec = Measurement.from_arrays(np.concatenate([t_rest, m.t]) + 2.0, cur, spd, ref)
        found[offset] = standstill_offsets(rec, rec.experiment(SETUP))
    assert found[0.0] == []
    (only,) = found[25.0]
    assert only["channel"] == "current_A"
    assert only["offset"] == pytest.approx(25.0, abs=2.0)  # 100 samples of 4 A noise: standard error 0.4 A
    assert f"{only['offset']:+.3g} A at standstill" in only["text"] and "sensor offset" in only["text"]


def test_coloured_noise_at_standstill_is_not_an_offset_once_the_residual_shows_its_spread():
    """Red team 6 (r3, r6): current noise of 4 A white plus 4 A AR(1) with tau = 0.4 s read as offsets of +8 and
    +4.5 A at standstill, judged on 48 samples at rest whose own autocorrelation cannot show a 0.4 s memory.
    Truth by construction: the same noise process at rest and in the model's residual over the record (the model
    exact), the rest's mean set to +8 A (about 2.7 standard errors of a 1 s mean of this noise, 2.9 A by
    the AR(1) formula), then +25 A (a sensor offset, about 9 of them)."""
    import numpy as np

    from kilnctl.measure.io import Measurement
    from kilnctl.measure.standstill import standstill_offsets, window_mean_spread

    m, _ = make_record((), seed=1, t_end=40.0)
    dt, tau = 0.02, 0.4
    rng = np.random.default_rng(17)  # a draw whose 50 samples at rest show little of the correlation (most do)
    n_rest = 50
    phi = math.exp(-dt / tau)
    ar = np.zeros(n_rest + m.t.size)
    w = rng.normal(0.0, 4.0 * math.sqrt(1.0 - phi ** 2), ar.size)
    for k in range(1, ar.size):
        ar[k] = phi * ar[k - 1] + w[k]
    noise = ar + rng.normal(0.0, 4.0, ar.size)
    rest, resid = noise[:n_rest] - noise[:n_rest].mean(), noise[n_rest:]
    # the standard error of a 1 s mean of this noise, from the AR(1) formula (white part: 4 / sqrt(50) A)
    T = n_rest * dt
    se = math.hypot(4.0 * math.sqrt(2 * tau / T - 2 * (tau / T) ** 2 * (1 - math.exp(-T / tau))), 4.0 / math.sqrt(n_rest))
    assert 2.6 < se < 3.2
    assert window_mean_spread(resid, n_rest - 2) == pytest.approx(se, rel=0.35)
    t_rest = np.arange(-n_rest * dt, 0.0, dt)[:n_rest]
    found = {}
    for mean in (8.0, 25.0):
        cur = np.concatenate([rest + mean, m.current + resid])
        spd = np.concatenate([np.zeros(n_rest), m.speed])
        ref = np.concatenate([np.zeros(n_rest), m.speed_ref])
        rec = Measurement.from_arrays(np.concatenate([t_rest, m.t]) - t_rest[0], cur, spd, ref)
        exp = rec.experiment(SETUP)
        found[mean] = (standstill_offsets(rec, exp), standstill_offsets(rec, exp, residuals={"current_A": resid}))
    assert [o["channel"] for o in found[8.0][0]] == ["current_A"]  # judged on the samples at rest alone: reported
    assert found[8.0][1] == []
    (only,) = found[25.0][1]
    assert only["channel"] == "current_A" and only["offset"] == pytest.approx(25.0, abs=3.0)


def test_a_current_logged_in_per_cent_of_its_rating_is_named_before_the_diagnosis():
    """Truth by construction: a synthetic start-up (the setup's own model, a second motor hidden) with its
    current divided by 16 (per cent of a 1600 A rating).  The base calibration papers over such a slip (on the
    shipped example: a fit of 0.3 %, then a kiln unbalance of 4.4e5 N m selected), so the setup's own model is
    compared first."""
    from kilnctl.measure.io import Measurement
    from kilnctl.simulate import resolve_gains

    m, _ = make_record(("second_motor",), seed=1, t_end=12.0)
    params = resolve_gains(SETUP)
    assert setup_cautions(m, params, m.experiment(params)) == []
    pct = Measurement.from_arrays(m.t, m.current / 16.0, m.speed, m.speed_ref)
    (only,) = setup_cautions(pct, params, pct.experiment(params))
    assert only.startswith("the setup's model before calibration, current_A: fit ")
    assert float(only.split("signal spans ")[1].split(" times")[0]) == pytest.approx(16.0, rel=0.15)
    assert "per cent of the rating" in only and "not evidence of an effect" in only


def test_caution_when_a_rival_explains_the_record_about_as_well():
    # truth: constructed rounds.  The winner's dBIC -500; a second supported candidate at -495 lies within the
    # BIC threshold (10) of it -> one caution naming both; at -400 (100 apart) or not supported -> none
    from kilnctl.measure.diagnose import CandidateResult

    m, _ = make_record((), seed=0, t_end=4.0)

    def diag(rival_dbic, rival_supported=True):
        d = _selected("viscous_drag", -300.0)
        win = d.rounds_[0][0]
        rival = CandidateResult("motor_coulomb_friction", rival_dbic, 15.0, {}, {}, {}, [], [], rival_supported,
                                "", 0.0, delta_bic_corrected=-250.0)
        d.rounds_ = [[win, rival]]
        d._added = {"viscous_drag": win}
        return effect_cautions(d, m, _exp(), SETUP)

    close = diag(-495.0)
    assert len(close) == 1
    assert "viscous_drag was preferred to motor_coulomb_friction by a BIC difference of only 5.0" in close[0]
    assert "-500.0 against -495.0" in close[0]
    assert diag(-400.0) == []
    assert diag(-495.0, rival_supported=False) == []


def test_caution_when_a_rival_is_as_good_once_the_noise_correlation_is_modelled():
    # truth: constructed rounds (the numbers of an independent plant's record with a second motor of 4 kg m^2,
    # where a motor Coulomb friction won: dBIC -282.5 against -223.3, whitened -13.9 against -15.6).  The plain
    # gap (59) is beyond the threshold, the whitened one (-1.7) within it -> one caution saying both, and that
    # the swap check refitted the rival in the winner's place; a rival whitened 30 worse -> none; a rival the
    # swap check did not refit (a pair) is not said to have been tried
    from kilnctl.measure.diagnose import CandidateResult

    m, _ = make_record((), seed=0, t_end=4.0)

    def texts(win_name, rival_name, rival_corr):
        d = _selected(win_name, -13.9)
        win = d.rounds_[0][0]
        win.delta_bic = -282.5
        rival = CandidateResult(rival_name, -223.3, 15.0, {}, {}, {}, [], [], True, "", 0.0,
                                delta_bic_corrected=rival_corr)
        d.rounds_ = [[win, rival]]
        d._added = {win_name: win}
        d.swap_tried_ = {("motor_coulomb_friction", "second_motor")}  # the pair refitted in the swap check
        return [t for t in effect_cautions(d, m, _exp(), SETUP) if "was preferred to" in t]

    (one,) = texts("motor_coulomb_friction", "second_motor", -15.6)
    assert one.startswith("motor_coulomb_friction was preferred to second_motor by BIC (dBIC -282.5 against "
                          "-223.3), but with the noise's correlation modelled second_motor is the better by 1.7 "
                          "(whitened dBIC -13.9 against -15.6")
    (close,) = texts("motor_coulomb_friction", "second_motor", -8.9)
    assert "with the noise's correlation modelled the two differ by only 5.0 (whitened" in close
    # red team 4 (f26): the rival far better once the correlation is modelled is said so, not "differ by only"
    (far,) = texts("motor_coulomb_friction", "second_motor", -1230.7)
    assert "second_motor is the better by 1216.8" in far and "differ by only" not in far
    assert "second_motor in its place did not fit better by every test" in one
    assert texts("motor_coulomb_friction", "second_motor", 16.1) == []
    (pair,) = texts("motor_coulomb_friction", "torque_friction_law+second_motor", -15.6)
    assert "in its place" not in pair and "either may be the cause" in pair


def test_rival_caution_of_a_pair_is_given_once():
    # truth: constructed round of pairs.  The winning pair added two effects; a rival pair within the threshold
    # differs in one effect -> one caution (not one per added effect); a rival made of selected effects only is
    # no rival
    from kilnctl.measure.diagnose import CandidateResult

    m, _ = make_record((), seed=0, t_end=4.0)

    def result(effect, dbic):
        return CandidateResult(effect, dbic, 15.0, {}, {}, {}, [], [], True, "", 0.0, delta_bic_corrected=-250.0)

    d = _selected("torque_friction_law", -300.0)
    win = result("torque_friction_law+second_motor", -900.0)
    d.selected_ = ["torque_friction_law", "second_motor"]
    d.rounds_ = [[win, result("torque_friction_law+viscous_drag", -893.0), result("second_motor", -895.0)]]
    d._added = {"torque_friction_law": win, "second_motor": win}
    texts = effect_cautions(d, m, _exp(), SETUP)
    assert len(texts) == 1
    assert texts[0].startswith("torque_friction_law+second_motor was preferred to torque_friction_law+viscous_drag "
                               "by a BIC difference of only 7.0")
    # the second motor removed later by the backward check (red team 13's torque_B: a current limit so): the
    # rival pair was a rival of what is gone, and nothing is said of it
    d.selected_ = ["torque_friction_law"]
    assert not any("preferred" in t for t in effect_cautions(d, m, _exp(), SETUP))


def test_base_values_far_from_the_setup_are_named_and_near_ones_are_not():
    # truth: two plants of the generator without any effect; one with its burden 40 % heavier than the setup
    # says (m_v), one with the usual few per cent off.  The calibrated m_v follows the plant, and only the first
    # diagnosis says that the final model lies far from the setup (the caution's threshold is 25 %).
    from kilnctl.measure.cautions import SETUP_DRIFT

    heavy, truth = make_record((), seed=4, mismatch=("m_v",), mismatch_frac=0.4, t_end=16.0)
    plant_m_v = truth["plant"]["m_v"]
    assert abs(plant_m_v / SETUP.m_v - 1.0) == pytest.approx(0.4)
    d = Diagnosis(SETUP, candidates=()).fit(heavy)
    far = [c for c in d.caveats_ if c.startswith("The final model's")]
    assert d.final_calibration_.values_["m_v"] == pytest.approx(plant_m_v, rel=0.05)
    assert len(far) == 1 and "m_v = " in far[0] and "40 % " in far[0] and f"{SETUP.m_v:.3g} kg" in far[0]
    near, _ = make_record((), seed=4, mismatch=("m_v",), mismatch_frac=0.05, t_end=16.0)
    assert 0.05 < SETUP_DRIFT
    assert not [c for c in Diagnosis(SETUP, candidates=()).fit(near).caveats_ if c.startswith("The final model's")]


def test_the_caution_on_base_values_far_from_the_setup_reads_for_two_values():
    # truth: constructed final values, m_v 49 % and J_v 36 % above the setup (the red team's field-weakening
    # record), and mu_c 40 % below with m_v 49 % above
    d = Diagnosis(SETUP)
    d.final_calibration_ = SimpleNamespace(values_={"mu_c": SETUP.mu_c, "m_v": SETUP.m_v * 1.49,
                                                    "J_v": SETUP.J_v * 1.36})
    (text,) = drift_texts(d, SETUP)
    assert "m_v = 8.64e+05 kg and J_v = 2.28e+06 kg*m^2 lie 49 % and 36 % above the setup's (5.8e+05 kg, " in text
    d.final_calibration_ = SimpleNamespace(values_={"mu_c": SETUP.mu_c * 0.6, "m_v": SETUP.m_v * 1.49,
                                                    "J_v": SETUP.J_v})
    (text,) = drift_texts(d, SETUP)
    assert "mu_c = 0.24 and m_v = 8.64e+05 kg lie 40 % below and 49 % above the setup's (0.4, 5.8e+05 kg)" in text
    assert "motors" not in text


@pytest.mark.parametrize("stick_slip", [True, False])
def test_a_static_friction_far_from_the_setup_is_named_where_the_model_has_stick_slip_cycles(stick_slip):
    # truth: constructed final values, red team 19's P1 (mu_s 0.89 against the setup's 0.57, the paper law
    # imitating the plant's torque law); the rest at the setup's.  With stick-slip cycles in the final model mu_s
    # sets every breakaway and is named (56 % above); without them it is fitted loosely and left out
    p = SETUP.replace(mu_s=0.57)
    d = Diagnosis(p, calibrate=("mu_c", "mu_s", "m_v", "J_v"))
    d.stick_slip_ = stick_slip
    d.final_calibration_ = SimpleNamespace(values_={"mu_c": p.mu_c, "mu_s": 0.8903, "m_v": p.m_v, "J_v": p.J_v})
    texts = drift_texts(d, p)
    if stick_slip:
        (text,) = texts
        assert "The final model's mu_s = 0.89 lies 56 % above the setup's (0.57)." in text
    else:
        assert texts == []


def test_a_burden_at_half_the_setups_points_to_a_drive_of_two_motors():
    # truth: red team 10's dual drive (two powered motors, one motor's current logged, one motor's nameplate in
    # the setup): its burden calibrated to m_v 49 % and J_v 48 % below the setup's, as the fold predicts (1/2)
    d = Diagnosis(SETUP)
    d.final_calibration_ = SimpleNamespace(values_={"mu_c": SETUP.mu_c, "m_v": SETUP.m_v * 0.51,
                                                    "J_v": SETUP.J_v * 0.52})
    (text,) = drift_texts(d, SETUP)
    assert "near 1/2 of the setup's" in text and "motors = 2 in [motor]" in text
    d.final_calibration_ = SimpleNamespace(values_={"mu_c": SETUP.mu_c, "m_v": SETUP.m_v * 0.51,
                                                    "J_v": SETUP.J_v})  # the burden's mass alone: another story
    (text,) = drift_texts(d, SETUP)
    assert "motors" not in text


def test_several_rivals_by_the_whitened_bic_share_one_caution():
    # truth: constructed round with the numbers of red team 4's ovality record (f24): the unbalance won by plain
    # dBIC (-699.7) over a second motor, a motor Coulomb friction and a sensor lag (-246.4, -188.9, -25.2), each
    # of which the whitened dBIC prefers (-202.4, -124.4, -282.2 against -47.1).  Three cautions of the same
    # story became one that names all three with their numbers; the swap check had refitted two of them
    from kilnctl.measure.diagnose import CandidateResult

    m, _ = make_record((), seed=0, t_end=4.0)
    d = _selected("kiln_unbalance", -47.1)
    win = d.rounds_[0][0]
    win.delta_bic = -699.7
    rivals = [CandidateResult(n, b, 15.0, {}, {}, {}, [], [], True, "", 0.0, delta_bic_corrected=w)
              for n, b, w in (("second_motor", -246.4, -202.4), ("motor_coulomb_friction", -188.9, -124.4),
                              ("speed_sensor_lag", -25.2, -282.2))]
    d.rounds_ = [[win] + rivals]
    d._added = {"kiln_unbalance": win}
    d.swap_tried_ = {("kiln_unbalance", "second_motor"), ("kiln_unbalance", "speed_sensor_lag")}
    (one,) = [t for t in effect_cautions(d, m, _exp(), SETUP) if "was preferred" in t]
    assert one.startswith("kiln_unbalance was preferred by BIC (dBIC -699.7) to second_motor, "
                          "motor_coulomb_friction and speed_sensor_lag (dBIC -246.4, -188.9 and -25.2), but with "
                          "the noise's correlation modelled each of them is about as good or better (whitened dBIC "
                          "-47.1 against -202.4, -124.4 and -282.2; the threshold is 10), and second_motor and "
                          "speed_sensor_lag, each in its place, did not fit better by every test: ")
    assert "any of them may be the cause" in one
    # the two of lowest dBIC refitted together too, then all three alone, then the pair only
    d.swap_tried_.add(("kiln_unbalance", ("second_motor", "motor_coulomb_friction")))
    (one,) = [t for t in effect_cautions(d, m, _exp(), SETUP) if "was preferred" in t]
    assert ("and second_motor and speed_sensor_lag, each in its place, did not fit better by every test, nor "
            "second_motor and motor_coulomb_friction together: ") in one
    d.swap_tried_.add(("kiln_unbalance", "motor_coulomb_friction"))
    (one,) = [t for t in effect_cautions(d, m, _exp(), SETUP) if "was preferred" in t]
    assert ("and each in its place did not fit better by every test, nor second_motor and "
            "motor_coulomb_friction together: ") in one
    d.swap_tried_ = {("kiln_unbalance", ("second_motor", "motor_coulomb_friction"))}
    (one,) = [t for t in effect_cautions(d, m, _exp(), SETUP) if "was preferred" in t]
    assert "and second_motor and motor_coulomb_friction together in its place did not fit better by every" in one


@pytest.mark.parametrize("pair_better, chosen", [(True, ("speed_sensor_lag", "second_motor")), (False, None)])
def test_swap_check_refits_the_two_closest_rivals_together_in_the_winners_place(pair_better, chosen):
    # truth: the round of red team 4's f26 (a rigid second rotor and a 25 ms speed-sensor delay): a compliance
    # won (dBIC -2215.2, whitened -1175.6) against the lag in its second-order form (-2047.0, -2237.1) and the
    # second motor (-1527.9, -2534.2); a motor friction (-165.9) was no close rival.  The refits and verdicts
    # are hand-made (only the logic is tested): each rival alone, and the two together, in the compliance's
    # place, each rival in the form its round judged it in; the pair is kept only when better by every test
    from types import SimpleNamespace

    from kilnctl.measure.diagnose import CandidateResult

    d = Diagnosis(SETUP)
    d._forms = {}
    current = SimpleNamespace(values_={"mu_c": 0.39, "k_po": 9e9, "C_po": 3e7, "T_unb": 2e5, "phi_unb": 0.6})
    seen = []

    def run_calibrations(args, pool, forms):
        seen.extend((a[2], f, a[5]) for a, f in zip(args, forms))
        return [SimpleNamespace(values_=dict(a[5]), effects=a[2]) for a in args]

    def evidence(m, name, cal, against, *a):
        better = "+" in name and pair_better
        return CandidateResult(name, -50.0 if better else 30.0, 3.0 if better else -1.0, {}, {}, {}, [], [],
                               better, "", 0.0, delta_bic_corrected=-40.0 if better else 20.0, calibration=cal)

    def result(name, dbic, whitened, values, form=None):
        cal = SimpleNamespace(values_=dict(values, mu_c=0.4))
        return CandidateResult(name, dbic, 10.0, {}, {}, {}, [], [], True, "", 1.0, delta_bic_corrected=whitened,
                               calibration=cal, form=form)

    won = result("drivetrain_compliance", -2215.2, -1175.6, {"k_po": 9e9, "C_po": 3e7})
    lag = result("speed_sensor_lag", -2047.0, -2237.1, {"tau_s": 0.02, "zeta_s": 0.6}, form="second_order")
    j2 = result("second_motor", -1527.9, -2534.2, {"J_m2": 21.0})
    fr = result("motor_coulomb_friction", -165.9, -150.0, {"T_cm": 100.0})
    unb = result("kiln_unbalance", -516.4, -400.0, {"T_unb": 2e5, "phi_unb": 0.6})
    d._run_calibrations = run_calibrations
    d._evidence = evidence
    d._first_failure = lambda *a: None
    added = {"drivetrain_compliance": won, "kiln_unbalance": unb}
    sel, cal, removed, swaps = d._swap(None, SETUP, ["drivetrain_compliance", "kiln_unbalance"], current, added,
                                       [[won, lag, j2, fr], [unb]], None, None, None, None, None, lambda s: None)
    structs = [s for s, _, _ in seen]
    assert structs == [("speed_sensor_lag", "kiln_unbalance"), ("second_motor", "kiln_unbalance"),
                       ("speed_sensor_lag", "second_motor", "kiln_unbalance")]
    # the lag in its round's form, with that form's parameter; the compliance's parameters left out
    assert [f.get("speed_sensor_lag") for _, f, _ in seen] == ["second_order", None, "second_order"]
    pair_init = seen[2][2]
    assert pair_init["zeta_s"] == 0.6 and pair_init["J_m2"] == 21.0 and pair_init["T_unb"] == 2e5
    assert "k_po" not in pair_init
    assert d.swap_tried_ == {("drivetrain_compliance", "speed_sensor_lag"), ("drivetrain_compliance", "second_motor"),
                             ("drivetrain_compliance", ("speed_sensor_lag", "second_motor"))}
    if chosen is None:
        assert sel == ["drivetrain_compliance", "kiln_unbalance"] and removed == [] and swaps == {}
        return
    assert sel == ["speed_sensor_lag", "second_motor", "kiln_unbalance"]
    assert swaps == {"speed_sensor_lag": "drivetrain_compliance", "second_motor": "drivetrain_compliance"}
    assert d._forms == {"speed_sensor_lag": "second_order"}
    (gone,) = removed
    assert gone.effect == "drivetrain_compliance" and not gone.supported
    assert gone.reason.startswith("replaced by speed_sensor_lag and second_motor in the swap check")
    assert "with speed_sensor_lag and second_motor together in its place" in gone.reason


def test_final_check_removes_a_compliance_whose_final_values_cannot_ring():
    # truth: the damping ratio worked out by hand, zeta = C_po / (2 sqrt(k_po J)), J the two-mass mode's inertia
    # at the kiln axis (motor side (J_m + J_m2) n^2 in series with J_kiln + J_v).  Red team 4's second-order
    # speed filter (f22) ended with a compliance of k_po 9.23e6, C_po 7.86e9 (zeta about 480) that the final fit
    # reached from other starts; the rounds refuse such a refit (from zeta 0.7 a step overshoots by < 5 %), the
    # final check now does too, however much it lowers the BIC (dBIC -182 here).  The same compliance at a
    # ringing stiffness and damping stays.  The calibrations are stand-ins: only the check's logic is tested
    import math

    from kilnctl.measure.evidence import CandidateResult

    j_motor = (SETUP.J_m + SETUP.J_m2) * SETUP.n ** 2
    j_kiln = SETUP.J_kiln + SETUP.J_v
    j_mode = j_motor * j_kiln / (j_motor + j_kiln)
    zeta = 7.86e9 / (2.0 * math.sqrt(9.23e6 * j_mode))
    assert zeta > 100

    def check(k_po, C_po):
        d = Diagnosis(SETUP)
        base = {"mu_c": 0.39, "mu_s": 0.52, "m_v": 6.0e5, "J_v": 1.6e6}
        final = SimpleNamespace(values_=dict(base, tau_s=0.0156, k_po=k_po, C_po=C_po), params_=SETUP,
                                cost_=1.0)
        # every refit without the compliance ends alike (the lag in its own form or in another: the first,
        # its own, is kept)
        d._calibrate = lambda m, params, rest, *a: SimpleNamespace(values_=dict(a[2]), params_=SETUP, cost_=1.1,
                                                                    bic_=0.0)
        d._evidence = lambda m, e, cal, without, *a: CandidateResult(e, -182.0, 0.0, {}, {}, {}, [], [], True,
                                                                     "", 0.0, delta_bic_corrected=-418.0)
        return d._final_check(None, SETUP, ["speed_sensor_lag", "drivetrain_compliance"], final, None, None, None,
                              None, lambda s: None)

    selected, _, dropped = check(9.23e6, 7.86e9)
    assert selected == ["speed_sensor_lag"]
    (r,) = dropped
    assert r.effect == "drivetrain_compliance" and not r.supported and r.stand_in
    assert f"a damping ratio of {zeta:.2g} at its" in r.reason and "keeping it: dBIC -182.0" in r.reason
    selected, _, dropped = check(2.0e8, 2.0e6)  # zeta 0.017: a drive train that rings
    assert selected == ["speed_sensor_lag", "drivetrain_compliance"] and dropped == []


def test_final_check_judges_at_the_final_values_when_the_refit_without_an_effect_fails():
    # truth by construction: the refit of the structure without the drag fails (KilnctlError, as when the model
    # cannot be run where a local fit went); the structure without it is then judged at the final values, as
    # before the final check refitted, and the drag, which changes the BIC there by +3 only, is removed.  The
    # calibrations and the evidence are stand-ins: only the check's logic is tested
    from kilnctl.errors import KilnctlError
    from kilnctl.measure.evidence import CandidateResult

    d = Diagnosis(SETUP)
    base = {"mu_c": 0.39, "mu_s": 0.52, "m_v": 6.0e5, "J_v": 1.6e6}
    final = SimpleNamespace(values_=dict(base, J_m2=30.0, B_o=1e3), params_=SETUP, cost_=1.0)
    calls = []

    def calibrate(m, params, rest, *a):
        calls.append((rest, a[-2]))
        if a[-2] == 1 and rest == ("second_motor",):
            raise KilnctlError("the model cannot be run at the fitted values")
        return SimpleNamespace(values_=dict(a[2]), params_=SETUP, cost_=1.0, effects=rest)

    d._calibrate = calibrate
    d._evidence = lambda m, e, cal, without, *a: CandidateResult(e, 3.0 if e == "viscous_drag" else -500.0, 0.0, {},
                                                                 {}, {}, [], [], True, "", 0.0)
    selected, kept, dropped = d._final_check(None, SETUP, ["second_motor", "viscous_drag"], final, None, None, None,
                                             None, lambda s: None)
    assert selected == ["second_motor"] and [r.effect for r in dropped] == ["viscous_drag"]
    # the refit failed, then the structure was judged at the final values (and, once chosen, evaluated there)
    assert [n for rest, n in calls if rest == ("second_motor",)] == [1, 0, 0]
    assert "B_o" not in kept.values_ and kept.values_["J_m2"] == 30.0


@pytest.mark.parametrize("T_unb2, replaced", [(1.5e5, True), (1.99e7, False)])
def test_final_check_removes_an_effect_that_another_effects_other_form_replaces(T_unb2, replaced):
    # truth by construction (red team 6's r5: a motor Coulomb friction stood in for the second harmonic of a
    # two-harmonic kiln load).  Without the friction, the unbalance refitted in its own form has a BIC 100 above
    # the final model's, in its two_harmonic form 50 below it: the friction goes, and the unbalance takes the
    # form.  A form whose added amplitude ends at its upper bound (2e7 N m) stands in for something else and is
    # not used: the friction then stays.  The calibrations and the evidence are stand-ins: only the check's logic
    from kilnctl.measure.evidence import CandidateResult

    d = Diagnosis(SETUP)
    base = {"mu_c": 0.39, "mu_s": 0.52, "m_v": 6.0e5, "J_v": 1.6e6}
    final = SimpleNamespace(values_=dict(base, T_unb=2e5, phi_unb=0.6, T_cm=244.0), params_=SETUP, bic_=0.0)
    seen = []

    def calibrate(m, params, rest, scales, mask, init, starts, *a):
        form = d._forms.get("kiln_unbalance")
        seen.append((rest, form, a[-2]))
        if rest == ("motor_coulomb_friction",):
            return SimpleNamespace(values_=dict(init), params_=SETUP, bic_=500.0)
        if form == "two_harmonic":
            if a[-2] == 1:  # the check's refit, from no second harmonic and from half the first in four phases
                assert init["T_unb2"] == 0.0 and {s["T_unb2"] for s in starts} == {1e5}
            return SimpleNamespace(values_=dict(init, T_unb2=T_unb2), params_=SETUP, bic_=-50.0)
        return SimpleNamespace(values_=dict(init), params_=SETUP, bic_=100.0)

    d._calibrate = calibrate
    d._evidence = lambda m, e, cal, without, *a: CandidateResult(e, cal.bic_ - without.bic_, 0.0, {}, {}, {}, [],
                                                                 [], True, "", 0.0)
    d._offset_at_rest = lambda *a: None  # no record here: the current at rest is not weighed
    selected, kept, dropped = d._final_check(None, SETUP, ["kiln_unbalance", "motor_coulomb_friction"], final,
                                             None, None, None, None, lambda s: None)
    # each effect checked with the others in their own form, and each of the others in its other forms too (the
    # friction in its falling form, with its three local fits, and in its building form, with two)
    assert [(rest, form, n) for rest, form, n in seen][:5] == [
        (("motor_coulomb_friction",), None, 1), (("motor_coulomb_friction",), None, 3),
        (("motor_coulomb_friction",), None, 2),
        (("kiln_unbalance",), None, 1), (("kiln_unbalance",), "two_harmonic", 1)]
    if not replaced:
        assert selected == ["kiln_unbalance", "motor_coulomb_friction"] and dropped == [] and d._forms == {}
        return
    assert selected == ["kiln_unbalance"] and d._forms == {"kiln_unbalance": "two_harmonic"}
    (r,) = dropped
    assert r.effect == "motor_coulomb_friction" and not r.supported and r.stand_in
    assert "without it with kiln_unbalance in its two_harmonic form" in r.reason and "+50.0" in r.reason
    assert kept.values_["T_unb2"] == T_unb2 and "T_cm" not in kept.values_


@pytest.mark.slow  # about a minute: seven local fits of stick-slip structures on a 40 s record at 50 Hz
def test_final_check_refits_the_others_and_removes_an_effect_they_replace(tmp_path):
    # truth: red team 5's g8 (benchmarks/foreign_records.py, the independently written plant): a motor Coulomb
    # friction of 100 N m and a 15 ms speed lag, no second motor, no drag.  Its diagnosis at 9eee3bb ended with
    # the values below: the lag in its second-order form, a Coulomb friction, a drag and a second motor of
    # 1.2 kg m^2.  At those values the model without the second motor fits worse (the check without a refit
    # kept it); refitted from them it fits better (BIC 103 lower, measured), so the final check removes it.
    # What the plant has, the lag and the Coulomb friction, must stay
    from benchmarks import foreign_records as fr
    from kilnctl.measure import holdout_masks, load_setup, read_record
    from kilnctl.simulate import resolve_gains

    spec = next(s for s in fr.RECORDS if s.name == "g8_coulomb_lag")
    truth = fr.write_record(spec, tmp_path)
    params = resolve_gains(load_setup(tmp_path / f"{spec.name}.toml").params)
    m = read_record(truth["csv"], params, columns=truth["columns"])
    d = Diagnosis(params)
    d._forms = {"speed_sensor_lag": "second_order"}
    exp = m.experiment(params, t0=d.t0)
    selected = ["speed_sensor_lag", "motor_coulomb_friction", "viscous_drag", "second_motor"]
    values = {"mu_c": 0.38784, "mu_s": 0.52519, "m_v": 6.0277e5, "J_v": 1.58986e6, "tau_s": 0.013664,
              "zeta_s": 1.4317, "T_cm": 72.05, "B_o": 6.9152e5, "J_m2": 1.184}

    def at(effects, v):  # the structure evaluated at the given values, no fit
        names = d._free_names(params, tuple(effects))
        return d._calibrate(m, params, tuple(effects), "std", None, {k: x for k, x in v.items() if k in names}, (),
                            exp, None, None, 0, True)

    final = at(selected, values)
    assert final.bic_ - at(selected[:3], values).bic_ < -d.min_delta_bic  # no refit: the second motor matters
    scales = {"current_A": 8.0, "speed_rpm": 1.0}
    train, test = holdout_masks(m, d.holdout, d.holdout_fraction, t0=exp.t0)
    kept, refit, dropped = d._final_check(m, params, selected, final, scales, train, test, exp, lambda s: None)
    assert "second_motor" not in kept
    assert {"speed_sensor_lag", "motor_coulomb_friction"} <= set(kept)
    gone = next(r for r in dropped if r.effect == "second_motor")
    assert gone.delta_bic > -d.min_delta_bic and "refitted on the whole record" in gone.reason
    assert refit.bic_ < final.bic_ and "J_m2" not in refit.values_


@pytest.mark.parametrize("mu_s, cycles", [(0.51, False), (0.62, False), (0.67, True), (0.80, True)])
def test_a_setup_whose_paper_law_makes_stick_slip_cycles_is_searched_as_one_with_cycles(mu_s, cycles):
    # truth (hand, the paper's friction law; red team 19's note): at the set speed the burden slides steadily when
    # mu_s < mu_c R/L and sticks and breaks away again and again when mu_s > mu_c R/L; Table 1's mu_c R/L is
    # 0.4 x 2.17 / 1.353 = 0.642.  The schedule of every structure then includes the torque law's (its
    # horizons and smoothing), as when the setup states that law
    p = SETUP.replace(mu_s=mu_s)
    assert p.mu_c * p.R / p.L == pytest.approx(0.6415, abs=1e-4)
    m, _ = make_record((), seed=2, params=p, t_end=30.0)
    d = Diagnosis(p)
    exp = m.experiment(p, t0=d.t0)
    assert d._cycles_at_setup(m, p, exp) is cycles
    d._setup_cycles = cycles
    assert ("torque_friction_law" in d._cyclic(())) is cycles and d._rugged(()) is cycles


def test_diagnosis_given_a_file_name_says_to_read_it_first():
    # truth: a file name typed by hand where the record belongs (was "'str' object has no attribute 'experiment'")
    from kilnctl.errors import ParameterError

    with pytest.raises(ParameterError, match=r"Diagnosis.fit: measurement must be .*read_record\('rec.csv'\)"):
        Diagnosis(candidates=["second_motor"]).fit("rec.csv")


def test_diagnosis_given_one_string_of_candidates_or_calibrate_names_the_argument():
    # truth: names typed by hand as one string (were read letter by letter: "unknown candidate effect 's'")
    from kilnctl.errors import KilnctlError

    with pytest.raises(KilnctlError, match=r"candidates = 'second_motor' must be a list of names"):
        Diagnosis(candidates="second_motor")
    with pytest.raises(KilnctlError, match=r"calibrate = 'mu_c' must be a list of names"):
        Diagnosis(calibrate="mu_c")


def _speed_comparison(shift_samples, seed=0):
    """A comparison stand-in: a 74 rpm/s ramp to 500 rpm and its hold at 50 Hz as the model's speed, the
    measured one the same signal ``shift_samples`` later (earlier when negative) plus 0.3 rpm of white noise."""
    t = np.arange(0.0, 30.0, 0.02)
    model = np.clip(74.0 * (t - 1.0), 0.0, 500.0)
    measured = np.clip(74.0 * (t - 1.0 - 0.02 * shift_samples), 0.0, 500.0) \
        + np.random.default_rng(seed).normal(0.0, 0.3, t.size)
    return SimpleNamespace(t=t, channels={"speed_rpm": SimpleNamespace(measured=measured, model=model)})


@pytest.mark.parametrize("shift_samples", [2, -3])
def test_a_speed_logged_later_or_earlier_than_the_model_is_named_with_its_shift(shift_samples):
    # truth by construction: the measured speed is the model's shifted by whole samples of 20 ms; unshifted,
    # the residual on the ramp is 74 rpm/s x the shift (1.48 rpm for 20 ms) over 7 s of the 30, its RMS
    # sqrt(7/30) x 74 x 0.02 k plus the noise; at the shift, the noise's 0.3 rpm
    from kilnctl.measure.cautions import best_shift, skew_texts

    comp = _speed_comparison(shift_samples)
    shift, rms_best, rms_0 = best_shift(comp.t, comp.channels["speed_rpm"].measured,
                                        comp.channels["speed_rpm"].model)
    assert shift == pytest.approx(0.02 * shift_samples)
    assert rms_best == pytest.approx(0.3, rel=0.1)
    ramp = math.sqrt(7.0 / 30.0) * 74.0 * 0.02 * abs(shift_samples)
    assert rms_0 == pytest.approx(math.hypot(ramp, 0.3), rel=0.1)
    (text,) = skew_texts(comp, ())
    ms = 20 * abs(shift_samples)
    if shift_samples > 0:
        assert text.startswith(f"the measured speed trails the final model's by {ms} ms") and \
            f"the speed logged {ms} ms after the current" in text and "speed_sensor_lag (not selected)" in text
        (text,) = skew_texts(comp, ("speed_sensor_lag",))
        assert "the speed_sensor_lag selected does not account for it" in text
    else:
        assert text.startswith(f"the measured speed leads the final model's by {ms} ms") and \
            f"the speed logged {ms} ms before the current" in text and "speed_sensor_lag" not in text
        # red team 9: a filter only in the controller's path leaves the logged speed ahead of kilnctl's lag,
        # which delays both: with the lag selected, that reading is named beside a skew
        (text,) = skew_texts(comp, ("speed_sensor_lag",))
        assert "filters only the speed the controller sees, not the speed logged" in text


def test_no_skew_caution_when_the_speed_matches_unshifted():
    # truth by construction: the same signals without a shift; and a 1-sample shift under 3 rpm of noise,
    # which moves the RMS by under a per cent, is not worth a caution either
    from kilnctl.measure.cautions import skew_texts

    assert skew_texts(_speed_comparison(0), ()) == []
    noisy = _speed_comparison(1)
    noisy.channels["speed_rpm"].measured = noisy.channels["speed_rpm"].model + \
        np.random.default_rng(1).normal(0.0, 3.0, noisy.t.size)
    assert skew_texts(noisy, ()) == []


@pytest.mark.parametrize("costs, refits", [
    ([729.0, 526.5, 526.4], 2),   # red team 5's g3: the refitted round moved the model far again, then stayed
    ([729.0, 728.9], 1),          # a move too small to count: one refit, as before
    ([479.66, 477.64, 400.0], 1),  # 0.4 % of the cost, though 16.9 by the BIC rule: not refitted again
    ([700.0, 600.0, 500.0, 400.0, 300.0], 3),  # at most REANCHOR_ROUNDS refits
])
def test_a_round_is_refitted_while_re_anchoring_moves_the_model_far(costs, refits):
    # truth by construction, worked out by hand: a refit is repeated when the refitted round moved the model by
    # more than 5 % of its cost (729 / 526.5 = 1.385, 526.5 / 526.4 = 1.0002, 479.66 / 477.64 = 1.0042,
    # 700 / 600 = 1.167), not by the BIC rule of the first refit (decided by the caller: n ln(cost ratio) above
    # 10; for n = 1000, 1021.6 -> 729 is 337).  The stand-ins have 4000 samples, as the record of the 0.4 %
    # move, where n ln(ratio) = 16.9 would have counted under that rule.  The round's candidates are each time
    # refitted from the latest model, and the results returned are the last re-anchoring's.  The calibrations
    # are stand-ins: only the loop's logic is tested
    import math

    from kilnctl.measure.diagnose import REANCHOR_AGAIN, REANCHOR_ROUNDS

    assert REANCHOR_ROUNDS == 3 and REANCHOR_AGAIN == 0.05
    d = Diagnosis(SETUP)
    d.reanchor_rounds_ = 0
    models = [SimpleNamespace(cost_=c, n_={"current_A": 4000}) for c in costs]
    refitted_from = []

    def result(text):
        return SimpleNamespace(text=text, supported=True, delta_bic=-20.0)

    def try_all(m, params, selected, names, current, *a):
        refitted_from.append(current.cost_)
        return [result(f"results from {current.cost_}")]

    def reanchor(m, params, selected, current, results, *a):
        i = models.index(current)
        nxt = models[i + 1] if i + 1 < len(models) else current
        return nxt, results + [result(f"judged against {nxt.cost_}")]

    d._try_all = try_all
    d._in_best_form = lambda m, params, selected, results, *a: results
    d._reanchor = reanchor
    assert d._moved_far(SimpleNamespace(cost_=1021.6, n_={"current_A": 1000}), models[0])
    current, results = d._round_from_anchor(None, SETUP, [], [], models[0], None, None, None, None, None,
                                            lambda s: None, {})
    assert refitted_from == costs[:refits] and d.reanchor_rounds_ == refits
    assert current is models[min(refits, len(costs) - 1)]
    assert [r.text for r in results] == [f"results from {costs[refits - 1]}", f"judged against {current.cost_}"]
    assert 1000 * math.log(1021.6 / 729.0) > 10 and 4000 * math.log(479.66 / 477.64) > 10


@pytest.mark.parametrize("J_v, again_cost, kept", [
    (1.0e4, 0.36, "again"),     # base values far from the setup's (J_v 99 % off), the search from it fits better
    (1.0e4, 70.0, "found"),     # far, but the search from the setup fits worse: the greedy one is kept
    (1.70e6, 0.36, "found"),    # within 10 % of the setup's values: no second search at all
])
def test_the_final_stick_slip_search_is_run_again_from_the_setup_when_it_ends_far_from_it(J_v, again_cost, kept):
    # truth by construction: the setup's J_v is 1.678e6, so 1.0e4 lies 99 % from it (beyond SETUP_FAR = 10 %)
    # and 1.70e6 1.3 %; the kept calibration is the one of lower cost, counting both searches' starts.  The
    # calibrations are stand-ins: only the rule is tested (plant:torque_law+compliance/s1 in docs/benchmarks.md)
    d = Diagnosis(SETUP)
    params = d.params
    ended = {"mu_c": 0.409, "mu_s": 0.49, "m_v": 5.6e5, "J_v": J_v, "k_po": 8.1e7, "C_po": 1.05e6}
    found = SimpleNamespace(cost_=66.2, local_fits_=["f1", "f2"], n_starts_=21, values_=ended)
    calls = []

    def from_setup(m, params, effects, eff, p, init, setup_base, scales, train, exp, ff, n_local):
        calls.append((effects, eff.name, setup_base["J_v"], scales, init["k_po"]))
        return SimpleNamespace(cost_=again_cost, local_fits_=["a1"], n_starts_=30)

    d._refit_from_setup = from_setup
    # nothing selected (a stick-slip base under the law the setup states): no effect to search with
    assert d._final_from_setup(None, params, [], None, None, found) is found and calls == []
    out = d._final_from_setup(None, params, ["torque_friction_law", "drivetrain_compliance"], None, None, found)
    if J_v > 1e6:
        assert calls == [] and out is found
        return
    assert calls == [(("torque_friction_law", "drivetrain_compliance"), "drivetrain_compliance", params.J_v, "std",
                      8.1e7)]
    if kept == "found":
        assert out is found
    else:
        assert out.cost_ == 0.36 and out.local_fits_ == ["f1", "f2", "a1"] and out.n_starts_ == 51


def test_a_selection_on_marginal_evidence_is_cautioned():
    # truth: red team 13's dfilt_A at 155d980 (its diagnose.json): a speed-sensor lag of 2.8 ms added at dBIC
    # -10.6, whitened -28.5, held-out +0.3 % (0.4 standard errors), where the plant has none (its derivative acts
    # through a 0.1 s filter); strong evidence, or a held-out gain beyond its threshold or one standard error,
    # gets no such caution
    from kilnctl.measure.cautions import marginal_texts
    from kilnctl.measure.diagnose import CandidateResult

    (text,) = marginal_texts("speed_sensor_lag", -10.6, 0.3, 0.42, 10.0, 2.0)
    assert text.startswith("speed_sensor_lag: the evidence is marginal: BIC falls by 10.6, within twice the "
                           "threshold of 10, and the held-out part is predicted no better (+0.3 %, +0.4 standard "
                           "errors)")
    for args in ((-25.0, 0.3, 0.42), (-10.6, 2.5, 0.42), (-10.6, 0.3, 1.2)):
        assert marginal_texts("speed_sensor_lag", *args, 10.0, 2.0) == []
    d = _selected("speed_sensor_lag", -28.5, {"tau_s": 0.0028})
    d.rounds_[0][0] = CandidateResult("speed_sensor_lag", -10.6, 0.3, {}, {}, {}, [], [], True, "", 0.0,
                                      delta_bic_corrected=-28.5, holdout_z=0.42)
    m, _ = make_record((), seed=0, t_end=4.0)
    assert effect_cautions(d, m, _exp(), SETUP) == [text]


def test_a_held_out_z_does_not_silence_a_rising_whitened_bic_where_the_model_fits_within_noise():
    # truth: red team 14's C5 at bc7bd79 (its diagnose.json): no effect, AR(1) noise of 6 A over 1 s; a kiln
    # unbalance added at dBIC -293.8, whitened +5.2, held-out +21.3 % at 3.0 standard errors, fit 97.7 %.  The
    # held-out z had silenced the weak-evidence caution; where the model with the effect still misses much
    # (80 %), the whitened BIC is no test and the z keeps it silent
    from kilnctl.measure.diagnose import CandidateResult

    m, _ = make_record((), seed=0, t_end=4.0)
    for fit, said in ((97.7, True), (80.0, False)):
        d = _selected("second_motor", 5.2)
        d.rounds_[0][0] = CandidateResult("second_motor", -293.8, 21.3, {"current_A": fit}, {}, {}, [], [], True,
                                          "", 0.0, delta_bic_corrected=5.2, holdout_z=3.0)
        texts = effect_cautions(d, m, _exp(), SETUP)
        assert any(t.startswith("second_motor: the evidence is weak") and "+5.2" in t for t in texts) == said


@pytest.mark.parametrize("again_cost, kept", [(486.28, "again"), (501.5, "refit")])
def test_a_stick_slip_refit_that_kept_its_start_is_restarted_at_the_effect_value_it_found(again_cost, kept):
    # truth by construction, from pair:torque_friction_law+viscous_drag/s2 at 2038231 (docs/benchmarks.md): the
    # drag's refit after the torque law kept the current model (cost 501.23), its best local fit ended at B_o
    # 1.51e6 N*m*s with the base moved (cost 505.78); one more local fit from the current model's base with
    # that B_o ended at 486.28.  The restart starts there (the other local fit's B_o is not taken), counts both
    # searches' local fits and starts, and is kept only when it ends lower.  The calibrations are stand-ins:
    # only the rule is tested
    from kilnctl.measure.effects import CATALOGUE

    d = Diagnosis(SETUP)
    init = {"mu_c": 0.3799, "mu_s": 0.4848, "m_v": 6.265e5, "J_v": 1.799e6, "B_o": 1000.0}
    ends = [{"start": {}, "end": dict(init, m_v=6.15e5, B_o=1.51e6), "cost": 505.78},
            {"start": {}, "end": dict(init, m_v=6.16e5, B_o=1.56e6), "cost": 548.94}]
    refit = SimpleNamespace(cost_=501.23, kept_start_=True, local_fits_=ends, n_starts_=363)
    calls = []

    def calibrate(m, params, effects, scales, mask, start, starts=(), **kw):
        calls.append((effects, start, tuple(starts), kw["n_local"]))
        return SimpleNamespace(cost_=again_cost, local_fits_=[{"cost": again_cost}], n_starts_=1)

    d._calibrate = calibrate
    effects = ("torque_friction_law", "viscous_drag")
    out = d._restart_at_effect(None, SETUP, effects, CATALOGUE["viscous_drag"], init, refit, None, None, None, None)
    assert calls == [(effects, dict(init, B_o=1.51e6), (), 1)]
    if kept == "refit":
        assert out is refit
    else:
        assert out.cost_ == 486.28 and out.n_starts_ == 364 and len(out.local_fits_) == 3
    # a refit whose local fits all left the effect at the current value: nothing to restart from
    calls.clear()
    same = SimpleNamespace(cost_=501.23, kept_start_=True, local_fits_=[{"end": dict(init), "cost": 510.0}],
                           n_starts_=3)
    assert d._restart_at_effect(None, SETUP, effects, CATALOGUE["viscous_drag"], init, same, None, None, None,
                                None) is same and calls == []


@pytest.mark.parametrize("stick_slip, whitened, gain_sign, supported", [
    (True, -29.3, -1, False),   # red team 15's C3: no effect, a motor friction of 11 N m, held-out 6.6 % worse
    (True, -128.4, -1, True),   # pair:torque_friction_law+kiln_unbalance/s1: the true unbalance, held-out worse
    (True, -29.3, +1, True),    # held-out better: the rule does not apply
    (False, -29.3, -1, True)])  # no stick-slip in the model: the whitened BIC's threshold of 10 as before
def test_a_refit_of_a_stick_slip_model_predicting_the_held_out_part_worse_needs_a_larger_whitened_fall(
        monkeypatch, stick_slip, whitened, gain_sign, supported):
    # truth by construction, with the numbers of those runs (docs/benchmarks.md): the current model fits within
    # noise (98.3 %), the candidate lowers the plain BIC by 181 and the whitened BIC by 29.3 or 128.4, and the
    # held-out part is predicted 6.6 % worse or better (1.1 standard errors).  Where the model has stick-slip
    # cycles a refit with any added parameter can tune their phase (refits that only did so lowered the whitened
    # BIC by up to 29 on the benchmark): predicting the held-out part worse, the candidate needs a whitened fall
    # of more than STICK_SLIP_FALL times the threshold.  The calibrations are stand-ins: only the rule is tested
    from kilnctl.measure import evidence

    monkeypatch.setattr(evidence, "whitened_delta_bic", lambda *a, **k: whitened)
    monkeypatch.setattr(evidence, "holdout_z", lambda *a, **k: gain_sign * 1.06)
    t = np.arange(200) * 0.05
    y = {"current_A": 800.0 + 10.0 * np.sin(t), "speed_rpm": 5.0 * t}
    test = np.arange(200) % 4 == 0
    noise = np.where(test, 1.0, 0.5)
    m = SimpleNamespace(t=t, channels=y)

    def cal(bic, scale):
        out = {c: v + scale * noise for c, v in y.items()}
        return SimpleNamespace(bic_=bic, run_=SimpleNamespace(outputs=out), fit_percent_={"current_A": 98.3},
                               values_={"T_cm": 11.4}, names_=["T_cm"], stderr_={"T_cm": 1.0}, on_bound_=[],
                               not_identifiable_=[], params_=SETUP)
    current = cal(0.0, 1.0)
    # the candidate's error on the held-out samples 6.6 % above (below) the current model's
    cand = cal(-180.9, 1.0)
    cand.run_.outputs = {c: v + np.where(test, np.sqrt(1.0 - gain_sign * 0.066), 0.5) for c, v in y.items()}
    r = evidence.judge(m, "motor_coulomb_friction", cand, current, {"current_A": 1.0, "speed_rpm": 1.0},
                       ~test, test, SimpleNamespace(t0=0.0), 0.0, stick_slip=stick_slip)
    assert r.holdout_gain == pytest.approx(gain_sign * 6.6, abs=0.01)
    assert r.supported is supported, r.reason
    if stick_slip and gain_sign < 0 and not supported:
        assert "stick-slip cycles shift with any added parameter" in r.reason and "more than 50" in r.reason


@pytest.mark.parametrize("stick_slip, whitened, supported", [
    (True, -4499.0, True),    # red team 19's E4: a backlash of 10 mm on a kiln whose paper law cycles
    (True, -45.0, False),     # a whitened fall under 5 x the threshold: the held-out part's 2.5 se still refuse it
    (False, -4499.0, False)])  # no stick-slip in the model: the held-out part's 2.5 standard errors refuse it
def test_a_refit_of_a_stick_slip_model_with_a_large_whitened_fall_is_not_refused_for_the_held_out_part(
        monkeypatch, stick_slip, whitened, supported):
    # truth by construction, with E4's numbers (docs/benchmarks.md, red team 19): a backlash lowered the plain BIC
    # by 3750 and the whitened BIC by 4499 and predicted the held-out blocks 12.8 % worse, -2.5 standard errors
    # (the model's stick-slip cycles there a sample off).  Where the model has stick-slip cycles a whitened fall
    # beyond STICK_SLIP_FALL x the threshold (50) is not refused for the held-out part; without cycles, or with a
    # smaller fall, -2.5 standard errors refuse it as before.  The calibrations are stand-ins: only the rule is
    # tested
    from kilnctl.measure import evidence

    monkeypatch.setattr(evidence, "whitened_delta_bic", lambda *a, **k: whitened)
    monkeypatch.setattr(evidence, "holdout_z", lambda *a, **k: -2.5)
    t = np.arange(200) * 0.05
    y = {"current_A": 350.0 + 10.0 * np.sin(t), "speed_rpm": 5.0 * t}
    test = np.arange(200) % 4 == 0
    m = SimpleNamespace(t=t, channels=y)

    def cal(bic, held_out_error):
        out = {c: v + np.where(test, held_out_error, 0.5) for c, v in y.items()}
        return SimpleNamespace(bic_=bic, run_=SimpleNamespace(outputs=out), fit_percent_={"current_A": 92.3},
                               values_={"delta_x": 0.007}, names_=["delta_x"], stderr_={"delta_x": 1e-4},
                               on_bound_=[], not_identifiable_=[], params_=SETUP)
    current = cal(0.0, 1.0)
    cand = cal(-3750.2, np.sqrt(1.128))  # the held-out squared error 12.8 % above the current model's
    r = evidence.judge(m, "backlash", cand, current, {"current_A": 1.0, "speed_rpm": 1.0},
                       ~test, test, SimpleNamespace(t0=0.0), 0.0, stick_slip=stick_slip)
    assert r.holdout_gain == pytest.approx(-12.8, abs=0.01)
    assert r.supported is supported, r.reason


@pytest.mark.parametrize("speed_fit, supported", [
    (11.3, True),    # red team 16's E5: the base model's speed 150 rpm off the record's: not within its noise
    (99.9, False)])  # the same numbers with the speed fitted: the whitened rise vetoes the held-out gain
def test_a_model_whose_speed_misses_the_record_does_not_fit_within_its_noise(monkeypatch, speed_fit, supported):
    # truth by construction, with E5's numbers (docs/benchmarks.md): a current limit lowered the plain BIC by
    # 4681 and predicted the held-out part 84 % better (4.4 standard errors); the whitening filter, fitted to the
    # current model's residual, took the speed's misfit for noise (whitened dBIC +507).  The veto "rises where
    # the model already fits within its noise" holds only when every channel fits (evidence.within_noise).  The
    # calibrations are stand-ins: only the rule is tested
    from kilnctl.measure import evidence

    assert evidence.within_noise({"current_A": 92.7, "speed_rpm": 99.9})
    assert not evidence.within_noise({"current_A": 92.7, "speed_rpm": 11.3})
    assert not evidence.within_noise({"current_A": 89.0, "speed_rpm": 99.9})
    assert evidence.within_noise({"current_A": 92.7})  # a record without the channel is judged on the current
    monkeypatch.setattr(evidence, "whitened_delta_bic", lambda *a, **k: 507.1)
    monkeypatch.setattr(evidence, "holdout_z", lambda *a, **k: 4.4)
    t = np.arange(200) * 0.05
    y = {"current_A": 480.0 + 10.0 * np.sin(t), "speed_rpm": 5.0 * t}
    test = np.arange(200) % 4 == 0
    m = SimpleNamespace(t=t, channels=y)

    def cal(bic, held_out_error):
        out = {c: v + np.where(test, held_out_error, 0.5) for c, v in y.items()}
        return SimpleNamespace(bic_=bic, run_=SimpleNamespace(outputs=out),
                               fit_percent_={"current_A": 92.7, "speed_rpm": speed_fit},
                               values_={"I_max": 498.7}, names_=["I_max"], stderr_={"I_max": 1.0}, on_bound_=[],
                               not_identifiable_=[], params_=SETUP)
    current = cal(0.0, 1.0)
    cand = cal(-4680.7, np.sqrt(1.0 - 0.841))  # the held-out squared error 84.1 % below the current model's
    r = evidence.judge(m, "current_limit", cand, current, {"current_A": 1.0, "speed_rpm": 1.0},
                       ~test, test, SimpleNamespace(t0=0.0), 0.0)
    assert r.holdout_gain == pytest.approx(84.1, abs=0.01)
    assert r.supported is supported, r.reason
    if not supported:
        assert "already fits within its noise" in r.reason


def test_a_speed_fit_of_ninety_percent_twenty_rpm_off_is_not_within_noise():
    """Truth by construction, with red team 20's E2 numbers (a current limit falling with speed: the kiln 20 rpm
    below its set speed for 30 s, the speed's noise 0.13 rpm): the base model fitted the current at 95.5 % and
    the speed at 90.5 %, and a speed fit of 90 % had counted as within noise, so the current limit (dBIC -186,
    held-out +2.1 %) was refused for a whitened rise.  Given the speed residual, a model whose speed misses by
    more than ten times the speed's sample-to-sample noise (and fits it below 99 %) does not fit within noise;
    the same fits with a residual that is the noise do."""
    from kilnctl.measure import evidence

    rng = np.random.default_rng(20)
    t = np.arange(2000) * 0.02
    noise = 0.13 * rng.standard_normal(t.size)
    behind = -20.0 * np.clip((t - 10.0) / 5.0, 0.0, 1.0)  # 20 rpm behind from 15 s on
    fits = {"current_A": 95.5, "speed_rpm": 90.5}
    assert evidence.within_noise(fits)  # the fits alone: as before
    assert not evidence.within_noise(fits, behind + noise)
    assert evidence.within_noise(fits, noise)
    assert evidence.within_noise({"current_A": 95.5, "speed_rpm": 99.5}, behind + noise)  # a speed fit of 99.5 %


@pytest.mark.parametrize("selected, times_top, said", [
    (("second_motor", "drivetrain_compliance"), 12.9, True),   # red team 16's E3: k_po 2.96e9 for a top of 2.3e8
    (("second_motor", "drivetrain_compliance"), 0.5, False),   # a stiffness a drive train has: no other place
    (("drivetrain_compliance",), 12.9, False)])                # no second motor: the range caution alone
def test_a_stiff_compliance_beside_a_second_motor_names_the_second_motors_shaft(selected, times_top, said):
    # truth by construction: the caution is written when both effects are selected and k_po lies above the
    # catalogue's usual range for this drive (red team 16's E3 and P1, a second motor on a shaft of its own,
    # had k_po 13 and 42 times its top); the diagnosis is a stand-in with the final values
    from kilnctl.measure.cautions import mode_place_texts
    from kilnctl.measure.effects import CATALOGUE

    lo, hi = CATALOGUE["drivetrain_compliance"].usual("k_po", SETUP)
    d = SimpleNamespace(selected_=list(selected), final_calibration_=SimpleNamespace(
        values_={"J_m2": 14.2, "k_po": times_top * hi, "C_po": 5.3e6}))
    out = mode_place_texts(d, SETUP)
    assert len(out) == int(said)
    if said:
        assert out[0].startswith("drivetrain_compliance with second_motor:") and "13 times the top" in out[0]
        assert "second motor's shaft or coupling" in out[0] and "nan" not in out[0]


@pytest.mark.parametrize("check, dbic, whitened, gain, said", [
    ("backward", -383.4, 14.3, 17.4, True),   # red team 17's E5
    ("backward", -383.4, -14.3, 17.4, False),  # whitened falls too: removed otherwise
    ("backward", -383.4, 14.3, 1.0, False),    # held-out gain below 2 %: noise
    ("backward", -5.0, 14.3, 17.4, False),     # plain BIC within the threshold
    ("swap", -383.4, 14.3, 17.4, False)])      # the swap check's replacement tells its own story
def test_an_effect_removed_on_the_whitened_bic_alone_is_named(check, dbic, whitened, gain, said):
    # truth by construction: the caution is written for a removal the backward check judged (its judgement kept
    # in checks_) where the plain BIC (below -10) and the held-out gain (above 2 %) favoured keeping the effect
    # and the whitened BIC alone did not (red team 17's E5: second_motor removed beside viscous_drag at dBIC
    # -383.4, whitened +14.3, held-out +17.4 % at 1.5 standard errors); the diagnosis is a stand-in with E5's
    # numbers
    from kilnctl.measure.cautions import removed_texts

    r = SimpleNamespace(effect="second_motor", reason="...", delta_bic=dbic, delta_bic_corrected=whitened,
                        holdout_gain=gain, holdout_z=1.46)
    d = SimpleNamespace(selected_=["viscous_drag"], removed_=[r], checks_=[(check, r)], min_delta_bic=10.0,
                        min_holdout_gain=2.0)
    out = removed_texts(d)
    assert len(out) == int(said)
    # no selection and nothing removed (most diagnoses of a record with no effect): nothing, and no error
    assert removed_texts(SimpleNamespace(selected_=[], removed_=[], checks_=[], min_delta_bic=10.0,
                                         min_holdout_gain=2.0)) == []
    if said:
        assert out[0].startswith("second_motor was removed in the backward check")
        assert "(whitened dBIC +14.3)" in out[0] and "(dBIC -383.4)" in out[0]
        assert "(gain +17.4 %, 1.5 standard errors)" in out[0]
        assert "viscous_drag and second_motor change the current alike" in out[0]


@pytest.mark.parametrize("far", [True, False])
def test_forms_are_not_fitted_for_a_round_that_is_refitted(far):
    # truth by construction: the re-anchoring is tried before the forms; when it moves the model so far that
    # the caller refits the round (the round is thrown away), the forms are
    # not fitted and its lines are said; otherwise the forms are fitted against the current model and the
    # re-anchoring runs again on their results, its refits shared through one ``done`` dict, as before the
    # shortcut.  Stand-ins: only the order of the steps is tested
    d = Diagnosis(SETUP)
    current, anchored = SimpleNamespace(cost_=700.0), SimpleNamespace(cost_=500.0)
    calls, said, dones = [], [], []
    r, judged, form = (SimpleNamespace(name=n, supported=True, delta_bic=b)
                       for n, b in (("r", -20.0), ("judged", -10.0), ("form", -30.0)))

    def reanchor(m, params, selected, cur, results, scales, train, test, exp, say, done):
        calls.append(("reanchor", [x.name for x in results]))
        dones.append(done)
        say("moved")
        return anchored, results + [judged]

    def in_best_form(m, params, selected, results, *a):
        calls.append(("forms", [x.name for x in results]))
        return results + [form]

    d._reanchor, d._in_best_form = reanchor, in_best_form
    model, results = d._forms_then_anchor(None, SETUP, [], current, [r], None, None, None, None, None,
                                          said.append, lambda a: far)
    assert model is anchored
    if far:
        assert calls == [("reanchor", ["r"])] and results == [r, judged] and said == ["moved"]
    else:
        # the forms' results sorted by dBIC before the second re-anchoring (form -30 before r -20)
        assert calls == [("reanchor", ["r"]), ("forms", ["r"]), ("reanchor", ["form", "r"])]
        assert results == [form, r, judged] and said == ["moved"] and dones[0] is dones[1]


def test_re_anchoring_twice_on_a_round_refits_the_structure_once():
    # truth by construction: the second re-anchoring of a round (after its forms) starts from the same
    # candidates' base values as the first, whose refits of the current structure it reuses (one refit per
    # starting point, counted); it judges them and moves the model as the first did
    d = Diagnosis(SETUP)
    current = SimpleNamespace(cost_=700.0, values_={"mu_c": 0.4})
    refit = SimpleNamespace(cost_=500.0, values_={"mu_c": 0.45})
    cand = SimpleNamespace(effect="second_motor", supported=True, stand_in=False, delta_bic=-50.0,
                           calibration=SimpleNamespace(values_={"mu_c": 0.45, "J_m2": 3.0}), wall_s=0.0)
    starts = []

    def calibrate(m, params, effects, scales, mask, init, **kw):
        starts.append(dict(init))
        return refit

    d._calibrate = calibrate
    d._first_failure = lambda m, cur, exp: None
    d._evidence = lambda m, effect, cal, cur, *a: SimpleNamespace(effect=effect, supported=False, stand_in=False,
                                                                  delta_bic=-5.0, calibration=cal, form=None)
    done = {}
    for _ in range(2):
        model, results = d._reanchor(None, SETUP, [], current, [cand], None, None, None, None, lambda s: None, done)
        assert model is refit and not results[0].supported
    assert starts == [{"mu_c": 0.45}]


@pytest.mark.parametrize("rival_dbic, anchored", [(-219.8, True), (-205.0, False)])
def test_a_rival_about_as_good_is_tried_when_the_best_candidates_base_values_do_not_help(rival_dbic, anchored):
    # truth by construction, with red team 19's E2 numbers (docs/benchmarks.md): in round 2 the torque law
    # gained dBIC -221.4 (a structure of its own: from its base values the current structure fits no better) and a
    # speed-sensor lag at its null value -219.8 (from its base values the current structure fits as well: its
    # gain was the structure's own).  A rival within min_delta_bic (10) of the best is tried and re-anchors the
    # model; one 16.4 below it is not tried.  The calibrations are stand-ins: only the procedure is tested
    d = Diagnosis(SETUP)
    current = SimpleNamespace(cost_=0.62, values_={"mu_c": 0.333, "k_pl": 0.93})
    law_values = {"mu_c": 0.333, "k_pl": 0.4, "mu_s": 0.36}
    lag_values = {"mu_c": 0.333, "k_pl": 0.001, "tau_s": 1e-4}
    results = [SimpleNamespace(effect="torque_friction_law", supported=True, stand_in=False, delta_bic=-221.4,
                               calibration=SimpleNamespace(values_=law_values), wall_s=0.0, form=None),
               SimpleNamespace(effect="speed_sensor_lag", supported=True, stand_in=False, delta_bic=rival_dbic,
                               calibration=SimpleNamespace(values_=lag_values), wall_s=0.0, form=None)]
    refits = {0.4: SimpleNamespace(cost_=0.62, values_={"mu_c": 0.333, "k_pl": 0.4}),
              0.001: SimpleNamespace(cost_=0.49, values_={"mu_c": 0.333, "k_pl": 0.001})}
    starts = []

    def calibrate(m, params, effects, scales, mask, init, **kw):
        starts.append(dict(init))
        return refits[init["k_pl"]]

    d._calibrate = calibrate
    d._first_failure = lambda m, cur, exp: None
    d._evidence = lambda m, effect, cal, cur, *a: SimpleNamespace(effect=effect, supported=False, stand_in=False,
                                                                  delta_bic=-2.0, calibration=cal, form=None)
    model, out = d._reanchor(None, SETUP, ["current_limit"], current, results, None, None, None, None,
                             lambda s: None)
    assert starts[0] == {"mu_c": 0.333, "k_pl": 0.4}  # the best first (its base values, the current's names)
    if anchored:
        assert model is refits[0.001] and starts[1] == {"mu_c": 0.333, "k_pl": 0.001}
        assert not any(r.supported for r in out)
    else:
        assert model is current and len(starts) == 1 and out[0].supported


@pytest.mark.parametrize("offset, T_cm_amps, fires", [(0.8, 0.95, True), (0.0, 0.95, False), (0.8, 10.0, False)])
def test_a_friction_whose_current_the_record_shows_at_rest_is_a_sensor_offset(offset, T_cm_amps, fires):
    """Red team 18's N2: no effect, a current sensor 0.8 A off; a motor friction of 0.95 A (3.0 N m) was
    selected.  Truth by construction: 75 samples at rest (white noise of 1.5 A) with the given offset put before
    a synthetic start-up whose model current is known (the stand-in final model reproduces it, so the residual
    is the added noise), and a friction adding ``T_cm_amps`` in motion; the decision worked out by hand from the
    samples' mean m and standard error s: 2 ln LR = (m^2 - (m - c)^2) / s^2 > 2 with |m| > 2 s.  A friction of
    10 A with the current at 0.8 A at rest: nearer zero than 10 A, so the friction stays."""
    from kilnctl.measure.checks import REST_EVIDENCE
    from kilnctl.measure.io import Measurement
    from kilnctl.simulate import resolve_gains

    m, _ = make_record((), seed=3, t_end=12.0)
    rng = np.random.default_rng(11)
    n_rest, dt = 75, m.t[1] - m.t[0]
    rest = rng.normal(offset, 1.5, n_rest)
    noise = rng.normal(0.0, 1.5, m.t.size)
    cur = np.concatenate([rest, m.current + offset + noise])
    spd = np.concatenate([np.zeros(n_rest), m.speed])
    ref = np.concatenate([np.zeros(n_rest), m.speed_ref])
    t = np.concatenate([np.arange(n_rest) * dt, m.t + n_rest * dt])
    rec = Measurement.from_arrays(t, cur, spd, ref)
    params = resolve_gains(SETUP)
    exp = rec.experiment(params)
    active = rec.t >= exp.t0 - 1e-9
    final = SimpleNamespace(values_={"T_cm": T_cm_amps * params.k_i}, params_=params,
                            run_=SimpleNamespace(outputs={"current_A": rec.current[active] - noise[-active.sum():]}))
    d = Diagnosis(SETUP)
    text = d._offset_at_rest("motor_coulomb_friction", final, rec, exp)
    at_rest = (rec.t < exp.t0 - 0.05)
    x = float(np.mean(rec.current[at_rest]))
    s = 1.5 / math.sqrt(at_rest.sum())  # white noise; the code's estimate allows for correlation, about this
    lr2 = (x ** 2 - (x - T_cm_amps) ** 2) / s ** 2
    assert (lr2 > REST_EVIDENCE and abs(x) > 2 * s) == fires  # the hand decision
    assert (text is not None) == fires
    if fires:
        assert f"reads {x:+.2f} A" in text and f"adds {T_cm_amps:+.2f} A" in text and "sensor offset" in text
    d._forms = {"motor_coulomb_friction": "falling"}  # a falling friction is no constant current: not weighed
    assert d._offset_at_rest("motor_coulomb_friction", final, rec, exp) is None
