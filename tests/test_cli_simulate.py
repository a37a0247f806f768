"""The `kilnctl simulate` command, run in-process, against independent truths.

Truths used: the static equilibrium of the sliding burden (hand calculation,
NOTES.md "Worked steady state": about 840 A), the Lewis bending stress of that
torque (hand calculation), the set point reached by an integrating controller,
and the breakaway angles of the two friction laws (NOTES.md: 27 deg printed,
39 deg torque-consistent).
"""

import csv
import io
import json
import math

import pytest

from kilnctl import Parameters
from kilnctl.cli import main

P = Parameters()


def _steady_kiln_torque(p):
    """Kiln torque [N*m] with the burden sliding at tan(psi*) = mu_c*R/L, plus bearing friction (eq. 17)."""
    psi = math.atan(p.mu_c * p.R / p.L)
    return p.m_v * p.g * p.L * math.sin(psi) + p.T_brg


def _run_json(capsys, *argv):
    assert main(["simulate", "--json", *argv]) == 0
    return json.loads(capsys.readouterr().out)


def test_macro_json_final_current_is_the_sliding_equilibrium(capsys):
    s = _run_json(capsys, "--model", "macro", "--t-end", "40")
    for key in ("peak_current_A", "final_current_A", "settle_time_s", "burden_mode_final", "n_events"):
        assert key in s
    # truth: hand calculation; the motor carries the kiln torque through n plus its viscous loss at 500 rpm
    omega_m = P.omega_ref / P.K_fb
    i_hand = _steady_kiln_torque(P) / (P.n * P.k_i) + P.B_m * omega_m / P.k_i
    assert i_hand == pytest.approx(840, rel=0.01)  # NOTES.md, worked steady state
    assert s["final_current_A"] == pytest.approx(i_hand, rel=0.01)
    assert s["burden_mode_final"] == "slip_pos"
    assert s["peak_current_A"] >= s["final_current_A"]
    assert s["friction_law"] == "paper"


def test_micro_json_final_stress_is_the_lewis_stress_of_the_running_torque(capsys):
    s = _run_json(capsys, "--model", "micro", "--t-end", "30")
    # truth: Lewis form sigma = W_t/(b*m*Y), W_t = kiln torque / R_o (hand calculation)
    sigma_hand = _steady_kiln_torque(P) / P.R_o / (P.face_width * P.module * P.Y_lewis)
    assert s["final_stress_Pa"] == pytest.approx(sigma_hand, rel=0.01)
    assert s["peak_stress_Pa"] >= s["final_stress_Pa"]
    assert s["model"] == "micro" and "mesh" in s["components"]


def _read_csv(path):
    rows = list(csv.DictReader(io.StringIO(path.read_text())))
    assert rows
    return rows


@pytest.mark.parametrize("law, tan_breakaway", [
    ("paper", P.mu_s),                # eq. 3 as printed: F_t > F_bf at tan psi = mu_s (27 deg)
    ("torque", P.mu_s * P.R / P.L),   # torque-consistent: tan psi = mu_s*R/L (39 deg), NOTES.md
])
def test_law_option_sets_the_breakaway_angle(tmp_path, capsys, law, tan_breakaway):
    out = tmp_path / "run.csv"
    assert main(["simulate", "--law", law, "--t-end", "25", "--csv", str(out)]) == 0
    text = capsys.readouterr().out
    assert f"friction law '{law}'" in text and str(out) in text
    rows = _read_csv(out)
    modes = [r["mode_burden"] for r in rows]
    k = next(i for i in range(1, len(rows)) if modes[i - 1] == "stick" and modes[i] != "stick")
    assert math.tan(float(rows[k]["psi"])) == pytest.approx(tan_breakaway, abs=1e-5)
    # truth: the integrating speed controller holds the set point
    assert float(rows[-1]["speed_rpm"]) == pytest.approx(P.omega_ref, rel=5e-3)
    assert float(rows[-1]["time_s"]) == pytest.approx(25.0)
    assert set(modes) <= {"stick", "slip_pos", "slip_neg", "held"}


def test_plot_written_whole(tmp_path, capsys):
    out = tmp_path / "sub" / "fig.png"
    assert main(["simulate", "--t-end", "5", "--plot", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in out.parent.iterdir()) == ["fig.png"]  # no temporary file left


def test_effects_add_components(capsys):
    s = _run_json(capsys, "--t-end", "3", "--effects", "second_motor, speed_sensor_lag")
    assert {"second_motor", "speed_sensor_lag"} <= set(s["components"])
    assert s["effects"] == ["second_motor", "speed_sensor_lag"]


@pytest.mark.parametrize("argv, needle", [
    (["--t-end", "0"], "t_end"),
    (["--t-end", "-3"], "t_end"),
    (["--t-end", "nan"], "t_end"),
    (["--t-end", "inf"], "t_end"),
    (["--effects", "second_motr"], "did you mean 'second_motor'"),
    (["--effects", "second_motor,,x"], "empty name"),
    (["--plot", "fig.xyz"], "unknown figure format"),
])
def test_bad_input_is_a_clear_error(tmp_path, monkeypatch, capsys, argv, needle):
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", *argv]) == 2
    err = capsys.readouterr().err
    assert needle in err and "Traceback" not in err
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("flag", ["--csv", "--plot"])
def test_never_overwrites_the_config(tmp_path, capsys, flag):
    cfg = tmp_path / "kiln.toml"
    P.to_toml(cfg)
    before = cfg.read_bytes()
    other = "--plot" if flag == "--csv" else "--csv"
    argv = ["simulate", "--config", str(cfg), flag, str(tmp_path / "." / "kiln.toml")]
    assert main(argv + [other, str(tmp_path / "x.other")]) == 2
    assert "--config file" in capsys.readouterr().err
    assert cfg.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["kiln.toml"]


def test_csv_and_plot_must_differ(tmp_path, capsys):
    f = tmp_path / "out.png"
    assert main(["simulate", "--csv", str(f), "--plot", str(f)]) == 2
    assert "same file" in capsys.readouterr().err
    assert not f.exists()


def test_bad_config_value_is_a_clear_error(tmp_path, capsys):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[kiln]\nm_v = -1.0\n")
    assert main(["simulate", "--config", str(cfg)]) == 2
    err = capsys.readouterr().err
    assert "m_v" in err and "Traceback" not in err
