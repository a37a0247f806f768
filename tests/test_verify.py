"""`kilnctl verify`: linear prediction against the nonlinear run.

Truths: the linear load-free prediction's final current is the viscous-friction
current B_m*omega/k_i (hand value); the nonlinear final current carries the
burden torque; the ramp figures of an analytic signal are computed by hand.
"""

import json
import math

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.verify import ramp_figures, verify


def test_ramp_figures_of_an_analytic_signal():
    # speed lags the ramp by 10 rpm, then w - ref = 20 e^-x - 30 e^-2x (x = t - t_r): continuous at t_r,
    # peak where e^-x = 1/3: 20/3 - 30/9 = 10/3 rpm over 500 rpm; inside the 2 % band (10 rpm) from t_r on
    p = Parameters()
    t = np.linspace(0, 20, 20001)
    t_r = p.omega_ref / p.ramp_rate
    x = np.maximum(t - t_r, 0.0)
    w = np.where(t < t_r, p.ramp_rate * t - 10.0, p.omega_ref + 20.0 * np.exp(-x) - 30.0 * np.exp(-2 * x))
    i = np.full_like(t, 100.0)
    f = ramp_figures(t, w, i, p)
    assert f["overshoot_pct"] == pytest.approx(10.0 / 3.0 / 5.0, rel=1e-4)
    assert f["ramp_lag_rpm"] == pytest.approx(10.0, abs=0.02)  # interpolated at the kink on a 1 ms grid
    assert f["settle_time_s"] == pytest.approx(t_r, abs=2e-3)
    assert f["final_current_A"] == pytest.approx(100.0)


def test_verify_macro_reasons_and_linear_hand_value():
    p = Parameters(gains="given", k_p=0.08, k_I=2.2, k_D=0.014)
    v = verify(p, "macro", 30.0)
    # hand value: steady state of the load-free loop, k_i i = B_m omega
    w = p.omega_ref / p.K_fb
    assert v.linear["stick"]["figures"]["final_current_A"] == pytest.approx(p.B_m * w / p.k_i, rel=1e-3)
    assert v.figures["final_current_A"] > 500  # the burden torque the linear model leaves out
    assert any(r.startswith("inertia: the burden breaks away") for r in v.reasons)
    assert any(r.startswith("current:") for r in v.reasons)


def test_verify_cli_json(capsys, tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("gains = 'given'\nk_p = 0.08\nk_I = 2.2\nk_D = 0.014\n")
    assert main(["verify", "--config", str(f), "--t-end", "20", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["gains"]["kp"] == 0.08 and {r["quantity"] for r in out["table"]} >= {"peak_current_A"}
    assert main(["verify", "--config", str(f), "--t-end", "3"]) == 2  # shorter than the 6.76 s ramp
    assert "ramp time" in capsys.readouterr().err


def test_verify_on_a_learned_structure(capsys):
    # truth: the same start-up simulated directly with the effect added (kilnctl.simulate), and the second
    # motor's inertia raises the start-up current (it must be accelerated with the first)
    import json

    from kilnctl import Parameters
    from kilnctl.cli import main
    from kilnctl.simulate import resolve_gains, simulate

    assert main(["verify", "--effects", "second_motor", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    row = next(r for r in out["table"] if r["quantity"] == "peak_current_A")
    direct = simulate(resolve_gains(Parameters()), "macro", 40.0, effects=["second_motor"])
    assert row["nonlinear"] == pytest.approx(float(abs(direct["i_a"]).max()), rel=1e-9)
    plain = simulate(resolve_gains(Parameters()), "macro", 40.0)
    assert row["nonlinear"] > float(abs(plain["i_a"]).max())
