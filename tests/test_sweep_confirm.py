"""A sweep's worst point is re-run on the CVODES engine (kilnctl.sweep.confirm) and can be reproduced.

Truths: the CVODES engine at rtol 1e-10 (a second integrator), and `kilnctl simulate` run on the setup the
confirmation prints (an independent path through the CLI and the TOML reader).
"""

import json

import pytest

from kilnctl.cli import main
from kilnctl.sweep import Study
from kilnctl.sweep.confirm import confirm_worst
from kilnctl.sweep.space import Grid

SPEC = """
model = "macro"
t_end = 20.0
outputs = ["peak_stress_Pa", "final_current_A"]

[parameters.m_v]
min = 300123.456789
max = 900987.654321
num = 3
"""


def test_worst_point_is_confirmed_and_reproducible(tmp_path, capsys):
    spec = tmp_path / "spec.toml"
    spec.write_text(SPEC)
    assert main(["sweep", str(spec), "--executor", "serial", "--no-cache", "--json", "--quiet"]) == 0
    s = json.loads(capsys.readouterr().out)
    w = s["worst_point"]
    assert w["confirmed"] and w["point"] == 2
    assert w["cvodes_rtol_1e-10"] == pytest.approx(w["value"], rel=2e-4)
    assert w["variables"] == {"m_v": 900987.654321}  # full precision, not 900988
    setup = tmp_path / "worst.toml"
    setup.write_text(w["setup_toml"])
    argv = w["command"].split()[1:]
    argv[argv.index("worst.toml")] = str(setup)
    assert main(argv) == 0
    r = json.loads(capsys.readouterr().out)
    peak = r["summary"]["peak_stress_Pa"] if "summary" in r else r["peak_stress_Pa"]
    assert peak == pytest.approx(w["value"], rel=1e-9)


def test_a_worst_point_the_second_engine_does_not_confirm_is_flagged():
    study = Study(Grid({"m_v": [400e3, 800e3]}), model="macro", t_end=15.0, outputs=("peak_stress_Pa",))
    res = study.run("serial", progress=False)
    true_peak = res.table["peak_stress_Pa"].max()
    res.table.loc[1, "peak_stress_Pa"] = 2.3 * true_peak  # what a missed event did in issue 11
    w = confirm_worst(study, res)
    assert not w.agree and w.reference == pytest.approx(true_peak, rel=2e-4)
    assert "DISAGREE" in w.describe()
