"""Gains checked and retuned on a learned structure (kilnctl.design.learned, kilnctl design --effects/--model-from).

Truth: the hand-derived eq. 21 model of kilnctl.linear (python-control interconnect), which covers a second
motor exactly (its rotor inertia adds to J_m on the motor shaft): the damping the check reports, before and
after retuning, must be the hand model's. The learned check itself comes from the exact Jacobian of the
compiled nonlinear plant (kilnctl.linearize), a different path.
"""

import json

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.design import design_pid
from kilnctl.design.learned import check_gains, retune
from kilnctl.gains import PIDGains
from kilnctl.linear import closed_loop_ss
from kilnctl.model import component_names


def _hand_zeta(p, gains, condition):
    poles = np.asarray(closed_loop_ss(p, gains, condition).poles(), dtype=complex)
    osc = poles[poles.imag > 1e-9]
    return float(np.min(-osc.real / np.abs(osc))) if len(osc) else 1.0


def test_the_rigid_design_is_kept_on_the_rigid_structure():
    p = Parameters()
    d = design_pid(p)
    r = retune(p, component_names("macro"), d.gains)
    assert r.after is r.before and r.kappa == 1.0 and r.before.ok
    assert r.before.zeta_min == pytest.approx(_hand_zeta(p, d.gains, "stick"), abs=2e-3)


def test_a_second_motor_is_found_unsafe_and_retuned_by_more_derivative():
    p = Parameters(J_m2=21.5)
    g = design_pid(Parameters()).gains  # designed without the second motor
    hand = p.replace(J_m=p.J_m + p.J_m2)  # the second motor's rotor on the motor shaft
    r = retune(p, component_names("macro", ["second_motor"]), g)
    assert not r.before.ok and "UNSAFE" in r.before.verdict()
    assert r.before.zeta_min == pytest.approx(_hand_zeta(hand, g, "stick"), abs=3e-3)
    assert r.after.ok and r.kappa <= 1.0
    assert _hand_zeta(hand, r.after.gains, "stick") >= 0.7 - 3e-3
    assert _hand_zeta(hand, r.after.gains, "slip") >= 0.7 - 3e-3


def test_a_lagging_speed_sensor_is_reported_and_the_gains_kept():
    p = Parameters(tau_s=0.05)
    g = design_pid(p).gains
    r = retune(p, component_names("macro", ["speed_sensor_lag"]), g)
    assert not r.before.ok and r.after is r.before and r.best_found is not None
    assert "NOT changed" in r.summary() and "faster speed sensor" in r.summary()


def test_cli_effects_json_and_a_bad_model_file(tmp_path, capsys):
    assert main(["design", "--effects", "second_motor", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["learned"]["before"]["ok"] is False and out["learned"]["after"]["ok"] is True
    bad = tmp_path / "d.json"
    bad.write_text('{"x": 1}')
    assert main(["design", "--model-from", str(bad)]) == 2
    assert "not a diagnosis" in capsys.readouterr().err
