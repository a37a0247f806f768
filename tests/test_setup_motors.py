"""A drive of several identical motors (``motors = N`` in a setup's [motor] section) folded into the model's one.

Truth: red team 10's independent plant (benchmarks/red10_plant.py) of a 5.2 m cement kiln driven by two
powered motors on one converter, each carrying the logged current, written with each motor's own state; it
has no notion of kilnctl's fold.  Given one motor's nameplate and ``motors = 2``, kilnctl's model follows it
to a few hundredths of an ampere (0.0019 A rms measured when written); given one motor's nameplate alone, it
misses by tens of amperes (the red team's R11, whose burden then calibrated 49 % low).
"""

import numpy as np
import pytest

from benchmarks.red10_plant import Plant, kiln_B
from kilnctl.errors import ConfigFileError
from kilnctl.measure import compare, load_setup
from kilnctl.measure.io import Measurement
from kilnctl.params import Parameters

MOTOR = ("R_a", "L_a", "k_i", "k_b", "J_m", "B_m")
CONTROLLER = ("k_p", "k_I", "k_D")
KILN = ("J_o", "J_v", "m_v", "L", "R", "mu_c", "mu_s", "mu_brg", "P", "l_brg", "k_brg")


def _setup(path, p, motors=None):
    lines = ["[motor]"] + [f"{k} = {float(p[k])!r}" for k in MOTOR]
    if motors is not None:
        lines.append(f"motors = {motors}")
    lines += ["[controller]", 'gains = "given"'] + [f"{k} = {float(p[k])!r}" for k in CONTROLLER]
    lines += ["[drive]", "ramp_rate = 50.0", "omega_ref = 750.0", f"V_max = {p['V_max']!r}", f"I_max = {p['I_max']!r}"]
    lines += ["[kiln]"] + [f"{k} = {float(p[k])!r}" for k in KILN] + ["[gear]", f"n = {p['n']!r}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_two_motors_follow_the_red_teams_dual_drive(tmp_path):
    p = kiln_B()
    p["n_mot"] = 2  # both motors powered, equal share; the plant logs motor 1's current
    out = Plant(p).run(30.0, 1e-3)
    t = np.arange(0.0, 30.0, 0.02)
    m = Measurement.from_arrays(t, current_A=np.interp(t, out["t"], out["i"]),
                                speed_rpm=np.interp(t, out["t"], out["w"]),
                                speed_ref_rpm=np.interp(t, *zip(*p["ref"])))
    two = load_setup(_setup(tmp_path / "two.toml", p, motors=2))
    assert (two.params.k_i, two.params.J_m, two.params.k_b) == (2 * p["k_i"], 2 * p["J_m"], p["k_b"])
    c = compare(m, two.params)
    assert c.channels["current_A"].rms < 0.05, c.channels["current_A"].rms
    one = load_setup(_setup(tmp_path / "one.toml", p))
    assert compare(m, one.params).channels["current_A"].rms > 20.0
    # the same fold for every command that reads the file as parameters (design, verify, simulate)
    assert Parameters.from_toml(tmp_path / "two.toml").k_i == two.params.k_i


def test_one_motor_is_the_file_without_the_key(tmp_path):
    p = kiln_B()
    assert load_setup(_setup(tmp_path / "a.toml", p, motors=1)).params == load_setup(_setup(tmp_path / "b.toml", p)).params


@pytest.mark.parametrize("bad", ["0", "1.5", "true", '"two"'])
def test_a_bad_number_of_motors_is_refused_by_name(tmp_path, bad):
    with pytest.raises(ConfigFileError, match=r"\[motor\] motors = .* must be a whole number"):
        load_setup(_setup(tmp_path / "bad.toml", kiln_B(), motors=bad))
    with pytest.raises(ConfigFileError, match=r"\[motor\] motors"):
        Parameters.from_toml(tmp_path / "bad.toml")


def test_params_says_what_the_fold_did(tmp_path, capsys):
    from kilnctl.cli import main

    path = _setup(tmp_path / "two.toml", kiln_B(), motors=2)
    assert main(["params", "--config", str(path)]) == 0
    out = capsys.readouterr().out
    assert "motors = 2 in [motor]: k_i, J_m, B_m above are 2 times one motor's" in out
    assert main(["params", "--config", str(_setup(tmp_path / "one.toml", kiln_B()))]) == 0
    assert "motors =" not in capsys.readouterr().out
