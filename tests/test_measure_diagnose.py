"""Diagnosis on small synthetic records with a known hidden effect (deterministic, seeded).

Truth for every check: the plant that generated the record (its hidden effect
and the value of the effect's parameter).  The full statistical version is
``benchmarks/diagnose_confusion.py``.
"""

import argparse
import json

import pytest

from kilnctl import Parameters
from kilnctl.errors import ModelError, NotFittedError
from kilnctl.measure.diagnose import Diagnosis, variance_inflation
from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

SETUP = Parameters(DEFAULT_GAINS)
FEW = ("second_motor", "viscous_drag", "kiln_unbalance", "speed_sensor_lag")


@pytest.fixture(scope="module")
def second_motor_case():
    m, truth = make_record(("second_motor",), seed=3, magnitudes={"J_m2": 30.0}, mismatch=("mu_c", "J_o"),
                           t_end=24.0)
    return m, truth, Diagnosis(SETUP, candidates=FEW).fit(m)


def test_hidden_second_motor_is_found_and_its_inertia_recovered(second_motor_case):
    m, truth, d = second_motor_case
    assert d.selected_ == ["second_motor"]
    assert d.ranking_[0].effect == "second_motor" and d.ranking_[0].supported
    # truth: J_m2 = 30 kg m^2 in the generating plant
    assert d.final_calibration_.values_["J_m2"] == pytest.approx(30.0, rel=0.10)
    assert d.final_["current_A"] > d.baseline_["current_A"] + 3.0
    assert "current fit rose from" in d.headline() and "J_m2" in d.headline()


def test_json_has_the_documented_keys(second_motor_case):
    _, _, d = second_motor_case
    out = json.loads(json.dumps(d.to_dict(), allow_nan=False))
    for key in ("baseline", "ranking", "selected", "final", "unexplained"):
        assert key in out
    r = out["ranking"][0]
    for key in ("effect", "delta_bic", "fit_percent", "parameters", "on_bound"):
        assert key in r
    assert r["parameters"]["J_m2"]["stderr"] is not None


def test_report_is_one_self_contained_page(second_motor_case, tmp_path):
    _, _, d = second_motor_case
    files = d.report(tmp_path / "rep")
    html = (tmp_path / "rep" / "diagnose.html").read_text()
    assert html.count("data:image/png;base64,") == 2 and 'src="http' not in html
    assert {p.name for p in files} >= {"diagnose.html", "diagnose.json"}


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


def test_unfitted_and_unknown_candidate():
    with pytest.raises(NotFittedError):
        Diagnosis(SETUP).to_dict()
    with pytest.raises(ModelError, match="second_motor"):
        Diagnosis(SETUP, candidates=["second_motr"])


def test_diagnose_cli_json(tmp_path, capsys):
    from kilnctl.cli import diagnose_cmd

    m, _ = make_record(("viscous_drag",), seed=8, magnitudes={"B_o": 6e6}, t_end=20.0)
    data = tmp_path / "rec.csv"
    m.to_csv(data)
    cfg = tmp_path / "setup.toml"
    cfg.write_text('[controller]\ngains = "given"\nk_p = 2.0\nk_I = 5.0\nk_D = 0.01\n'
                   '[measurement]\ncandidates = ["viscous_drag", "second_motor"]\n')
    ap = argparse.ArgumentParser()
    diagnose_cmd.register(ap.add_subparsers())
    args = ap.parse_args(["diagnose", "--data", str(data), "--config", str(cfg), "--json"])
    assert args.func(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["selected"] == ["viscous_drag"]
    # truth: B_o = 6e6 N m s/rad in the plant
    assert out["final_parameters"]["B_o"]["value"] == pytest.approx(6e6, rel=0.10)
