"""The `kilnctl design` command, run in-process.

Independent truth: the closed-loop poles in the JSON are checked against
``control.feedback`` of the printed gains on the hand-written motor transfer
function, not against kilnctl's own closed loop.
"""

import json

import control as ct
import numpy as np
import pytest

from kilnctl.cli import main
from kilnctl.params import Parameters


def _json(capsys, *args):
    assert main(["design", "--json", *args]) == 0
    return json.loads(capsys.readouterr().out)


def _feedback_poles(p, d, condition):
    J = p.J_stick if condition == "stick" else p.J_slip
    G = ct.tf([p.k_i], [p.L_a * J, p.L_a * p.B_m + p.R_a * J, p.R_a * p.B_m + p.k_i * p.k_b])
    C = ct.tf([d["kd"], d["kp"], d["ki"]], [1, 0])
    return np.sort_complex(ct.feedback(C * G, p.K_fb).poles())


def test_design_json_keys_and_poles(capsys):
    d = _json(capsys)
    p = Parameters()
    keys = {"kp", "ki", "kd", "closed_loop_poles", "dominant_zeta", "dominant_wn", "settling_time_s",
            "overshoot_pct", "gain_margin_db", "phase_margin_deg"}
    assert keys <= set(d)
    assert d["meets_requirements"] is True and d["unmet"] == []
    for cond in ("stick", "slip"):
        c = d["conditions"][cond]
        assert keys - {"kp", "ki", "kd"} <= set(c)
        got = np.sort_complex(np.array([complex(re, im) for re, im in c["closed_loop_poles"]]))
        np.testing.assert_allclose(got, _feedback_poles(p, d, cond), rtol=1e-7)
        assert c["settling_time_s"] <= d["requirements"]["settling_time_max"]
        assert c["overshoot_pct"] <= d["requirements"]["overshoot_max"]
    assert d["closed_loop_poles"] == d["conditions"]["stick"]["closed_loop_poles"]  # top level = design condition


def test_design_options_change_the_requirements(capsys, tmp_path):
    d = _json(capsys, "--zeta", "0.9", "--settling-time", "3", "--overshoot", "1", "--wn-max", "3")
    assert d["requirements"] == {"zeta_min": 0.9, "settling_time_max": 3.0, "overshoot_max": 1.0, "wn_max": 3.0}
    for c in d["conditions"].values():
        assert c["zeta_min_all"] >= 0.9 - 1e-9 and c["dominant_wn"] <= 3.0 * (1 + 1e-6)
    # a config file changes the plant: a larger armature inductance gives other gains
    cfg = tmp_path / "c.toml"
    cfg.write_text("[motor]\nL_a = 1.0e-3\n")
    d2 = _json(capsys, "--config", str(cfg))
    assert d2["conditions"]["stick"]["inertia_kg_m2"] == pytest.approx(Parameters().J_stick)
    assert d2["kd"] != pytest.approx(_json(capsys)["kd"], rel=1e-3)


def test_design_text_table_shows_both_conditions(capsys):
    assert main(["design"]) == 0
    out = capsys.readouterr().out
    header = next(line for line in out.splitlines() if "stick" in line and "slip" in line)
    assert header.split() == ["stick", "slip"]
    assert "k_p = " in out and "V/rpm" in out and "meets all requirements" in out


@pytest.mark.parametrize("args, match", [
    (["--settling-time", "0.3"], "settling_time_max = 0.3 s: best achieved"),
    (["--zeta", "-0.2"], "zeta_min = -0.2 is negative"),
    (["--zeta", "1.5"], "zeta_min = 1.5 exceeds 1"),
    (["--settling-time", "0"], "settling_time_max = 0.0 s must be > 0"),
    (["--overshoot", "-3"], "overshoot_max = -3.0 % must be >= 0"),
])
def test_design_bad_or_impossible_requirements_exit_2(capsys, args, match):
    assert main(["design", *args]) == 2
    err = capsys.readouterr().err
    assert match in err and "Traceback" not in err


def test_design_plot_written_whole_and_guarded(capsys, tmp_path):
    out = tmp_path / "design.svg"  # svg: the cheapest format to write; png goes through the same save_figure
    out.write_text("stale")
    assert main(["design", "--plot", str(out)]) == 0
    assert "<svg" in out.read_text()[:500]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["design.svg"]
    cfg = tmp_path / "c.toml"
    cfg.write_text("mu_c = 0.4\n")
    assert main(["design", "--config", str(cfg), "--plot", str(cfg)]) == 2
    assert "refusing to overwrite" in capsys.readouterr().err and cfg.read_text() == "mu_c = 0.4\n"
    assert main(["design", "--plot", str(tmp_path / "x.doc")]) == 2
    assert "unknown figure format 'doc'" in capsys.readouterr().err
