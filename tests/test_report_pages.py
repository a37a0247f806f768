"""The report pages: plain headline, how-to-read box, uncertainties in words, settings as a table;
each loaded in headless Chromium (no console errors, every image decodes, fits a 1300 px window).

Truths: a page made broken on purpose must be caught by the browser check (else the check proves
nothing); hand values for the number formatting; the verification's own numbers for its page.
"""

import json
import math
import re

import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.measure.report import page, uncertainty_words, value_pair

GAINS = {"gains": "given", "k_p": 0.085, "k_I": 2.17, "k_D": 0.0142}
LAPTOP_PX = 1300


def test_the_browser_check_catches_a_broken_page(load_in_chromium, tmp_path):
    # truth: this page has a script error, a console error and an image that cannot decode
    bad = tmp_path / "bad.html"
    bad.write_text(page("broken", '<img alt="nothing" src="data:image/png;base64,AAAA">'
                                  "<script>console.error('boom'); undefined_function();</script>"))
    out = load_in_chromium(bad)
    assert out["broken_images"] == ["nothing"]
    assert any("boom" in e for e in out["errors"]) and any("undefined_function" in e for e in out["errors"])


def _clean(out, n_images):
    assert out["errors"] == [] and out["broken_images"] == []
    assert out["images"] == n_images
    assert out["page_width"] <= LAPTOP_PX  # no horizontal scrolling in a laptop window


def test_number_and_uncertainty_formatting():
    # hand: the standard error sets the decimals (two significant digits of it)
    assert value_pair(579912.3, 183.0) == ("579910", "180")
    assert value_pair(20.7412, 0.1344) == ("20.74", "0.13")
    assert value_pair(5309316.0, 2072959.0) == ("5300000", "2100000")  # red team 16's E3: C_po
    assert value_pair(2.9552e9, 2.6e7) == ("2.955e+09", "2.6e+07")  # and k_po
    assert value_pair(0.0, 0.004) == ("0.0000", "0.0040")
    assert value_pair(-3.0, 200.0) == ("0", "200")  # a value within its error of zero: not "-0"
    assert value_pair(0.4208, float("inf")) == ("0.4208", "")
    assert "not identifiable" in uncertainty_words(math.inf) and "inf" not in uncertainty_words(math.inf)
    assert "on its bound" in uncertainty_words(0.1, on_bound=True)


def test_verify_report(load_in_chromium, tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    Parameters(GAINS).to_toml(cfg)
    assert main(["verify", "--config", str(cfg), "--t-end", "20", "--report", str(tmp_path / "rep"), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    text = (tmp_path / "rep" / "verify.html").read_text()
    # truth: the verification's own numbers appear in the headline
    peak = next(r["nonlinear"] for r in data["table"] if r["quantity"] == "peak_current_A")
    head = re.search(r'<p class="big">(.*?)</p>', text, re.S).group(1)
    assert f"{peak:.0f} A" in head
    assert "How to read this" in text and "<th" in text.split("Settings")[-1]
    _clean(load_in_chromium(tmp_path / "rep" / "verify.html"), 1)


def test_compare_report(load_in_chromium, tmp_path, capsys):
    from kilnctl.measure import example_paths

    record, setup = example_paths()
    rep = tmp_path / "rep"
    assert main(["compare", "--data", str(record), "--config", str(setup), "--report", str(rep)]) == 0
    capsys.readouterr()
    text = (rep / "compare.html").read_text()
    assert "example_record.csv" in text and "/example_record.csv" not in text  # file name, not path
    assert "How to read this" in text and "fit %" in text
    _clean(load_in_chromium(rep / "compare.html"), 1)


def test_optimize_ramp_report(load_in_chromium, tmp_path, capsys):
    cfg = tmp_path / "kiln.toml"
    Parameters(GAINS).to_toml(cfg)
    rep = tmp_path / "rep"
    rc = main(["optimize-ramp", "--config", str(cfg), "--t-max", "4", "--horizon", "5", "--objective", "dynamic",
               "--report", str(rep), "--json"])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0, out["flags"]
    text = (rep / "optimize_ramp.html").read_text()
    # truth: the JSON of the same run; the objective's row comes first and carries the verified value
    first_row = re.search(r'<tr class="sel">(.*?)</tr>', text, re.S).group(1)
    assert "dynamic stress" in first_row and f"{out['dynamic_stress_verified_Pa'] / 1e6:.1f}" in first_row
    assert "0.0 % below" not in text
    _clean(load_in_chromium(rep / "optimize_ramp.html"), 1)
