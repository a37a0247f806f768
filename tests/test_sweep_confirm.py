"""A sweep's worst point is re-run on the CVODES engine (kilnctl.sweep.confirm) and can be reproduced.

Truths: the CVODES engine at rtol 1e-10 (a second integrator), and `kilnctl simulate` run on the setup the
confirmation prints (an independent path through the CLI and the TOML reader).
"""

import json

import pytest

from kilnctl import Parameters
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


def test_the_reproduce_command_carries_the_removed_components(tmp_path, capsys):
    # truth: kilnctl simulate run with the printed arguments gives the sweep's peak current; without the current
    # limit the peak (about 750 A) is above this drive's I_max = 600 A, so a command that dropped --remove would
    # give another number
    base = Parameters(I_max=600.0)
    study = Study(Grid({"m_v": [500e3, 700e3]}), model="macro", t_end=12.0, outputs=("peak_current_A",),
                  remove=("current_limit",), base=base)
    res = study.run("serial", progress=False)
    w = confirm_worst(study, res)
    assert w.agree and "--remove current_limit" in w.command
    setup = tmp_path / "worst.toml"
    setup.write_text(w.setup_toml)
    argv = w.command.split()[1:]
    argv[argv.index("worst.toml")] = str(setup)
    assert main(argv) == 0
    peak = json.loads(capsys.readouterr().out)["peak_current_A"]
    assert peak == pytest.approx(w.value, rel=1e-9)
    with_limit = Study(Grid({"m_v": [700e3]}), model="macro", t_end=12.0, outputs=("peak_current_A",), base=base)
    limited = with_limit.run("serial", progress=False).table["peak_current_A"].iloc[0]
    assert peak > 1.05 * limited


def test_study_options_the_cli_cannot_take_are_named():
    from kilnctl.sweep.confirm import reproduce_command

    study = Study(Grid({"m_v": [500e3]}), model="micro", t_end=12.5, options={"dt": 2e-3, "max_samples": 50000})
    cmd = reproduce_command(study)
    assert cmd.startswith("kilnctl simulate --model micro --t-end 12.5 --max-samples 50000 --config worst.toml")
    assert "dt=0.002" in cmd and "pass them to kilnctl.simulate.simulate" in cmd
