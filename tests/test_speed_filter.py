"""The second-order speed filter (component ``speed_sensor_filter``, the ``second_order`` form of
``speed_sensor_lag``), checked against independent truths: scipy.signal's simulation of the documented
transfer function applied to the plant's own motor speed (a second method), and the ramp response of any
filter with unit DC gain and denominator a s^2 + tau_s s + 1 (by hand: it trails a ramp of slope r by r tau_s,
as the first-order lag of time constant tau_s does)."""

import numpy as np
import pytest
from scipy import signal

from kilnctl import Parameters
from kilnctl.measure.effects import CATALOGUE
from kilnctl.simulate import resolve_gains, simulate

# gains under which a 10 Hz filter with zeta_s 0.5 leaves the loop stable (the paper's gains then diverge)
SOFT = dict(gains="given", k_p=0.22, k_I=1.5, k_D=0.0)


def _filter_run(tau_s, zeta_s):
    p = resolve_gains(Parameters(tau_s=tau_s, zeta_s=zeta_s, **SOFT))
    run = simulate(p, "macro", 12.0, effects=["speed_sensor_filter"], dt=1e-3)
    # on a uniform grid (an event repeats its time: the state after it is kept)
    tt = np.asarray(run.t, float)
    _, idx = np.unique(tt[::-1], return_index=True)
    keep = tt.size - 1 - idx
    t = np.arange(0.0, 12.0, 1e-3)
    motor = np.interp(t, tt[keep], run.outputs["kiln_rpm"][keep] * p.n)  # the macro model's reducer is rigid
    return t, motor, np.interp(t, tt[keep], run.outputs["speed_rpm"][keep])


@pytest.mark.parametrize("zeta_s", [0.5, 0.87, 5.0])
def test_the_logged_speed_is_the_motor_speed_through_the_documented_filter(zeta_s):
    tau_s = 0.016  # s: with zeta_s 0.5 a 10 Hz filter (omega_n = 2 zeta_s / tau_s = 62.5 rad/s)
    t, motor, logged = _filter_run(tau_s, zeta_s)
    _, y, _ = signal.lsim(signal.lti([1.0], [tau_s ** 2 / (4 * zeta_s ** 2), tau_s, 1.0]), motor, t)
    assert np.max(np.abs(logged - y)) < 2e-3 * np.max(motor)
    # on the ramp (3-6 s) the filter trails the motor by slope * tau_s, whatever zeta_s
    mid = (t > 3.0) & (t < 6.0)
    slope = np.median(np.gradient(motor, t)[mid])
    assert np.median(motor[mid] - logged[mid]) == pytest.approx(slope * tau_s, rel=0.05)


def test_it_is_the_lags_second_order_form_and_adds_its_damping_ratio():
    # the catalogue: one effect (the controller sees the speed late), the filter a form of it, never a
    # candidate of its own; near zeta_s 5 it is the first-order lag (poles 97 times apart)
    forms = CATALOGUE["speed_sensor_lag"].forms
    assert [f.name for f in forms] == ["second_order"]
    assert forms[0].components == ("speed_sensor_filter",)
    assert [fp.name for fp in forms[0].parameters] == ["zeta_s"]
    assert "speed_sensor_filter" not in CATALOGUE
    z = forms[0].near["zeta_s"]
    fast, slow = z + np.sqrt(z * z - 1), z - np.sqrt(z * z - 1)
    assert fast / slow > 90


@pytest.mark.slow  # about a minute: a diagnosis of a stick-slip record with one candidate
def test_a_second_order_filters_record_keeps_the_lag_in_its_second_order_form(tmp_path):
    # truth: the independently written plant's own speed filter (benchmarks/foreign_records.py, red team 4's
    # f22: 10 Hz, zeta 0.5, fed back and logged; its low-frequency delay 2 zeta / w_n = 15.9 ms), on a
    # record of 20 s at 50 Hz.  In its first-order form the lag fitted 13 ms and the diagnosis of the whole
    # record then added a micrometre backlash beside it (89.6 %); the filter at the plant's values gives 95 %.
    import dataclasses

    from benchmarks import foreign_records as fr
    from kilnctl.measure import load_setup, read_record
    from kilnctl.measure.diagnose import Diagnosis

    spec = next(s for s in fr.RECORDS if s.name == "f22_filter2")
    spec = dataclasses.replace(spec, t_end=20.0, fs=50.0, layout="plain", h=1e-3)
    truth = fr.write_record(spec, tmp_path)
    params = load_setup(tmp_path / f"{spec.name}.toml").params
    m = read_record(truth["csv"], params, columns=truth["columns"])
    d = Diagnosis(params, candidates=("speed_sensor_lag",)).fit(m)
    assert d.selected_ == ["speed_sensor_lag"]
    assert d.forms_ == {"speed_sensor_lag": "second_order"}
    w_n, zeta = spec.effects["filter2"]["w_n"], spec.effects["filter2"]["zeta"]
    v = d.final_calibration_.values_
    assert v["zeta_s"] == pytest.approx(zeta, rel=0.15)
    assert v["tau_s"] == pytest.approx(2 * zeta / w_n, rel=0.1)
    assert "second_order form" in d.summary()
    assert d.to_dict()["forms"] == {"speed_sensor_lag": "second_order"}


def test_a_diagnosis_file_with_the_form_gives_the_filters_structure():
    # truth: the JSON as `kilnctl diagnose --json` writes it (selected, forms); design and verify then run the
    # filter that was fitted, not the first-order lag
    from kilnctl.structure import Structure

    d = {"selected": ["speed_sensor_lag", "second_motor"], "forms": {"speed_sensor_lag": "second_order"},
         "final_parameters": {}, "settings": {"model": "macro"}}
    assert Structure.from_diagnosis(d).effects == ("speed_sensor_filter", "second_motor")
    assert Structure.from_diagnosis(dict(d, forms={})).effects == ("speed_sensor_lag", "second_motor")
