"""``kilnctl optimize-ramp``, run in-process on short start-ups.

Truths used: the hybrid plant re-run by the test for the reported ramp and for
the baseline (the JSON must report what the plant gives), and the problem's
own constraint (95 % of omega_ref by t_max).
"""

import json

import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.optimize import Profile
from kilnctl.optimize.verify import measure_hybrid

GAINS = {"gains": "given", "k_p": 0.085, "k_I": 2.17, "k_D": 0.0142}
KEYS = ("profile", "ramp", "peak_stress_predicted_Pa", "peak_stress_verified_Pa", "baseline_ramp",
        "baseline_peak_stress_Pa", "reduction_pct", "time_to_speed_s", "solver_status", "iterations")


@pytest.fixture()
def config(tmp_path):
    path = tmp_path / "kiln.toml"
    Parameters(GAINS).to_toml(path)
    return path


def test_json_reports_what_the_hybrid_plant_gives(config, capsys, tmp_path):
    plot = tmp_path / "ramp.png"
    rc = main(["optimize-ramp", "--config", str(config), "--t-max", "4", "--horizon", "5", "--json",
               "--plot", str(plot)])
    out = json.loads(capsys.readouterr().out)
    assert rc == 0, out["flags"]
    for k in KEYS:
        assert k in out
    assert plot.stat().st_size > 10_000
    p = Parameters(GAINS)
    # truth: the hybrid plant, re-run here for the reported ramp and for the baseline
    m, _ = measure_hybrid(p, Profile.parse("constant"), [out["ramp"]["rate_rpm_s"]], horizon=5.0)
    b, _ = measure_hybrid(p, Profile.parse("constant"), [p.ramp_rate], horizon=5.0)
    assert out["peak_stress_verified_Pa"] == pytest.approx(m.peak_stress_Pa, rel=1e-9)
    assert out["baseline_peak_stress_Pa"] == pytest.approx(b.peak_stress_Pa, rel=1e-9)
    assert out["reduction_pct"] == pytest.approx(100 * (1 - m.peak_stress_Pa / b.peak_stress_Pa))
    assert out["time_to_speed_s"] <= 4.0 * (1 + 1e-3)
    assert out["baseline_ramp"] == 74.0


def test_errors_exit_2_with_a_message(config, capsys):
    assert main(["optimize-ramp", "--config", str(config), "--t-max", "0.1", "--horizon", "1"]) == 2
    assert "infeasible" in capsys.readouterr().err
    assert main(["optimize-ramp", "--config", str(config), "--profile", "spline"]) == 2
    assert "pwl:N" in capsys.readouterr().err
    assert main(["optimize-ramp", "--config", str(config), "--plot", str(config)]) == 2
    assert "refusing" in capsys.readouterr().err


def test_optimize_ramp_with_an_effect(capsys):
    # truth: the hybrid micro model with the second motor measured directly (measure_hybrid) at the optimum the
    # CLI reports; and the added rotor inertia must raise the dynamic start-up stress of the 74 rpm/s baseline
    import json

    from kilnctl import Parameters
    from kilnctl.cli import main
    from kilnctl.optimize import measure_hybrid
    from kilnctl.optimize.problem import Profile

    assert main(["optimize-ramp", "--objective", "dynamic", "--effects", "second_motor", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    p = Parameters()
    m, _ = measure_hybrid(p, Profile.parse("constant"), [out["ramp"]["rate_rpm_s"]], out["horizon_s"],
                          effects=("second_motor",))
    assert out["dynamic_stress_verified_Pa"] == pytest.approx(m.peak_dynamic_stress_Pa, rel=1e-6)
    plain, _ = measure_hybrid(p, Profile.parse("constant"), [74.0], out["horizon_s"])
    assert out["baseline_dynamic_stress_Pa"] > plain.peak_dynamic_stress_Pa
    assert main(["optimize-ramp", "--effects", "drivetrain_compliance"]) == 2
    assert "mode-free effects" in capsys.readouterr().err
