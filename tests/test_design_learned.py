"""Gains checked and retuned on a learned structure (kilnctl.design.learned, kilnctl design --effects/--model-from).

Truth: the hand-derived eq. 21 model of kilnctl.linear (python-control interconnect), which covers a second
motor exactly (its rotor inertia adds to J_m on the motor shaft): the damping the check reports, before and
after retuning, must be the hand model's. The learned check itself comes from the exact Jacobian of the
compiled nonlinear plant (kilnctl.linearize), a different path.
"""

import json
import re

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.cli import main
from kilnctl.design import Requirements, design_pid
from kilnctl.design.learned import check_gains, gain_change, retune
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


# the shipped example's diagnosis (kilnctl/data/example_record.csv), as in tests/test_close_the_loop.py
EXAMPLE = Parameters(J_m2=20.7, m_v=610e3, mu_c=0.419, mu_s=0.498)
EXAMPLE_COMPS = component_names("macro", ["second_motor"])


def _direct(p, comps, gains, condition):
    """Poles of a fresh linearization with the gains set in the parameters (not via with_gains), by
    control.damp, and the speed's step information by control.step_response: (wn, zeta, step_info)."""
    import control as ct

    from kilnctl.linearize import linearize

    lin = linearize(p.replace(gains="given", k_p=gains.k_p, k_I=gains.k_I, k_D=gains.k_D), components=comps,
                    burden=condition)
    with np.errstate(invalid="ignore", divide="ignore"):
        wn, zeta, _ = ct.damp(lin.sys, doprint=False)
    keep = wn > 1e-6  # the kinematic angles' poles at zero have no dynamics
    speed = lin.sys[list(lin.sys.output_labels).index("speed_rpm"), 0]
    resp = ct.step_response(speed, T=np.linspace(0.0, 6.0, 6001))
    return wn[keep], zeta[keep], ct.step_info(resp.outputs, timepts=resp.time)


def test_the_example_redesign_meets_damping_and_wn_max_by_python_control():
    # truth: control.damp on a fresh exact linearization with the redesigned gains, both burden conditions;
    # the sliding burden's pendulum (eq. 25, undamped, at the same frequency whatever the gains, within 0.01 %:
    # the operating point of a fresh start-up moves it by ~2e-6) stays out
    req = Requirements().resolve(EXAMPLE)
    g = design_pid(EXAMPLE, req).gains
    r = retune(EXAMPLE, EXAMPLE_COMPS, g, req)
    assert not r.before.ok and r.after.ok and r.after is not r.before
    a = r.after.gains
    for cond in ("stick", "slip"):
        wn_a, z_a, info = _direct(EXAMPLE, EXAMPLE_COMPS, a, cond)
        wn_b, z_b, _ = _direct(EXAMPLE, EXAMPLE_COMPS, g, cond)
        pend = np.abs(z_a) < 1e-6
        if cond == "slip":  # the pendulum: undamped, and not moved by the gains
            assert pend.sum() == 2 and np.allclose(wn_a[pend], wn_b[np.abs(z_b) < 1e-6], rtol=1e-4)
        else:
            assert not pend.any()
        wn, z = wn_a[~pend], z_a[~pend]
        assert z.min() >= req.zeta_min - 1e-3
        # dominant: the slowest of the loop's poles (largest real part); the rigid gains put it above wn_max
        dom = int(np.argmin(wn * z))
        assert wn[dom] <= req.wn_max * (1 + 2e-3)
        assert wn_b[~(np.abs(z_b) < 1e-6)][int(np.argmin((wn_b * z_b)[~(np.abs(z_b) < 1e-6)]))] > req.wn_max * 1.03
        assert info["SettlingTime"] <= req.settling_time_max and info["Overshoot"] <= req.overshoot_max
    # the smallest change: no larger than the setting the loop helper measured to meet both (gains x 0.92 after
    # k_D x 1.24), which python-control confirms here
    helper = PIDGains(0.92 * g.k_p, 0.92 * g.k_I, 0.92 * 1.24 * g.k_D)
    for cond in ("stick", "slip"):
        wn, z, _ = _direct(EXAMPLE, EXAMPLE_COMPS, helper, cond)
        loop = np.abs(z) > 1e-6
        assert z[loop].min() >= 0.7 and wn[loop][int(np.argmin((wn * z)[loop]))] <= req.wn_max
    assert gain_change(r.kappa, r.kd_factor) <= gain_change(0.92, 1.24) + 1e-9
    assert "meets every requirement" in r.after.verdict() or "every requirement met" in r.after.verdict()


def test_no_gains_meet_a_50_ms_sensor_lag_and_the_unmet_requirement_is_named():
    # truth: control.damp on a fresh linearization with the closest setting's gains gives the damping the
    # report names; the rigid gains are kept
    p = Parameters(tau_s=0.05)
    comps = component_names("macro", ["speed_sensor_lag"])
    g = design_pid(p).gains
    r = retune(p, comps, g)
    assert r.after is r.before and r.best_found is not None
    k, d, best = r.best_found
    names = {n for n, _, _ in best.unmet()}
    assert "zeta_min" in names
    text = r.summary()
    assert "NOT changed" in text and "still misses" in text
    m = re.search(r"still misses: damping ratio (0\.\d{3}) < zeta_min = 0\.7 \((stick|slip)\)", text)
    assert m is not None
    wn, z, _ = _direct(p, comps, PIDGains(k * g.k_p, k * g.k_I, k * d * g.k_D), m.group(2))
    loop = np.abs(z) > 1e-6
    assert float(m.group(1)) == pytest.approx(z[loop].min(), abs=6e-4) and z[loop].min() < 0.7


@pytest.mark.parametrize("command", [["design"], ["verify", "--t-end", "10"]])
def test_a_learned_model_comes_with_what_its_diagnosis_said(tmp_path, capsys, command):
    # truth: a diagnosis written by hand with one caution and an unexplained interval (red team 6's r5 and r4:
    # a stand-in far outside its usual range, impacts the catalogue's backlash could not make); the commands
    # that act on its model must repeat both, and say nothing of the kind for a diagnosis without them
    said = {"selected": [], "final_parameters": {}, "settings": {"model": "macro"},
            "caveats": ["motor_coulomb_friction: T_cm = 244 N*m, above the usual 10-100 N*m"],
            "unexplained": {"hint": "a local failure: 2.2-6.4 s (ramp)"}}
    path = tmp_path / "diagnose.json"
    path.write_text(json.dumps(said))
    assert main(command + ["--model-from", str(path)]) == 0
    out = capsys.readouterr().out
    assert "Read what the diagnosis that learned this model" in out
    assert "- motor_coulomb_friction: T_cm = 244 N*m, above the usual 10-100 N*m" in out
    assert "- unexplained: a local failure: 2.2-6.4 s (ramp)" in out
    path.write_text(json.dumps(dict(said, caveats=[], unexplained=None)))
    assert main(command + ["--model-from", str(path)]) == 0
    assert "Read what the diagnosis" not in capsys.readouterr().out
    if command == ["design"]:
        path.write_text(json.dumps(said))
        assert main(["design", "--model-from", str(path), "--json"]) == 0
        cautions = json.loads(capsys.readouterr().out)["learned"]["diagnosis_cautions"]
        assert cautions == said["caveats"] + ["unexplained: a local failure: 2.2-6.4 s (ramp)"]


def test_the_verify_page_of_a_learned_model_shows_what_its_diagnosis_said(tmp_path, capsys):
    # truth: the hand-written diagnosis of the test above; its caution reaches the --report page too
    said = {"selected": [], "final_parameters": {}, "settings": {"model": "macro"},
            "caveats": ["motor_coulomb_friction: T_cm = 244 N*m, above the usual 10-100 N*m"], "unexplained": None}
    path = tmp_path / "diagnose.json"
    path.write_text(json.dumps(said))
    report = tmp_path / "report"
    assert main(["verify", "--t-end", "10", "--model-from", str(path), "--report", str(report)]) == 0
    page = (report / "verify.html").read_text()
    assert "Diagnosis caution:" in page and "T_cm = 244 N*m, above the usual 10-100 N*m" in page
