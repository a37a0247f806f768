"""The detector of a sustained oscillation (a speed loop hunting), on constructed signals.

Independent truth: signals built here with a known frequency and size, and signals
that hold no loop oscillation (stick-slip saw teeth of a few seconds, white noise,
too few periods).
"""

import numpy as np
import pytest

from kilnctl.measure.oscillation import MIN_HZ, Oscillation, dominant_oscillation, matching_value


def _signal(f_hz, amp, t_end=40.0, fs=50.0, noise=20.0, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, t_end, 1.0 / fs)
    ramp = np.where(t < 7.0, 900.0, 400.0)  # a start-up's level: the ramp's current, then the steady one
    y = ramp + amp * np.sin(2 * np.pi * f_hz * t + 0.3) * (t >= 8.0) + noise * rng.standard_normal(t.size)
    return t, y


@pytest.mark.parametrize("f_hz", [2.3, 8.246, 13.1])
def test_frequency_and_size_of_a_constructed_hunting(f_hz):
    """A sine of known frequency and amplitude after the ramp, in white noise: the frequency within 0.5 % (the
    periodogram's bin is 1/32 Hz; the refinement between bins does the rest) and the RMS within 5 % of
    amp/sqrt(2)."""
    t, y = _signal(f_hz, 700.0)
    osc = dominant_oscillation(t, y, t_from=9.0)
    assert osc is not None
    assert osc.f_hz == pytest.approx(f_hz, rel=5e-3)
    assert osc.rms == pytest.approx(700.0 / np.sqrt(2), rel=0.05)
    assert osc.share > 0.9


def test_uneven_samples_are_put_on_an_even_grid():
    """A logger's jittered time stamps (+-20 % of the step) give the same frequency."""
    t, y = _signal(8.246, 700.0)
    rng = np.random.default_rng(3)
    tj = t + rng.uniform(-0.2, 0.2, t.size) / 50.0
    tj.sort()
    yj = 400.0 + 700.0 * np.sin(2 * np.pi * 8.246 * tj + 0.3)
    osc = dominant_oscillation(tj, yj, t_from=9.0)
    assert osc is not None and osc.f_hz == pytest.approx(8.246, rel=5e-3)


def test_no_oscillation_in_stick_slip_saw_teeth_noise_or_short_records():
    """What is not a loop hunting: torque-law stick-slip (a saw tooth of period 2.5 s, below MIN_HZ), white noise
    alone (no band holds half the variance), a sine of too few periods (2 Hz over 5 s), a small sine buried in
    noise, and a constant signal."""
    t = np.arange(0.0, 40.0, 0.02)
    saw = 400.0 + 150.0 * ((t / 2.5) % 1.0)
    assert 1 / 2.5 < MIN_HZ
    assert dominant_oscillation(t, saw, t_from=8.0) is None
    noise = 400.0 + 30.0 * np.random.default_rng(1).standard_normal(t.size)
    assert dominant_oscillation(t, noise, t_from=8.0) is None
    short = np.arange(0.0, 13.0, 0.02)
    assert dominant_oscillation(short, 400.0 + 300 * np.sin(2 * np.pi * 2.0 * short), t_from=8.0) is None
    _, weak = _signal(8.0, 10.0, noise=40.0)
    assert dominant_oscillation(t, weak, t_from=9.0) is None
    assert dominant_oscillation(t, np.full(t.size, 400.0), t_from=8.0) is None


@pytest.mark.slow
def test_a_hunting_loop_is_fitted_by_the_lag_that_matches_its_frequency(tmp_path):
    """Independent truth: the benchmark's scipy plant (``benchmarks/baselines.py``, written apart from
    kilnctl.model) with a 30 ms speed-sensor lag, whose loop hunts at about 8 Hz against its current limit;
    its first 20 s.  The ordinary refit of the lag finds no valley (the cycle's phase fits only within about
    a millisecond of lag); started from the frequency match it fits the current and finds the plant's lag."""
    from benchmarks.diagnose_records import find, write
    from kilnctl import Parameters
    from kilnctl.measure import Calibration, Measurement, read_csv
    from kilnctl.measure.calibrate import holdout_masks
    from kilnctl.measure.diagnose import Diagnosis
    from kilnctl.measure.synthetic import DEFAULT_GAINS

    p = Parameters(DEFAULT_GAINS)
    csv, _, truth = write(find("plant:sensor_lag_30ms/s1"), tmp_path)
    full = read_csv(csv, p)
    k = full.t <= 20.0
    m = Measurement.from_arrays(full.t[k], full.current[k], full.speed[k], full.speed_ref[k])
    exp = m.experiment(p)
    osc = dominant_oscillation(m.t, m.current, exp.steady_from)
    assert osc is not None and 7.5 < osc.f_hz < 9.0
    d = Diagnosis(p)
    base = Calibration(p, d.calibrate).fit(m, experiment=exp, n_local=1)
    train, _ = holdout_masks(m, "blocks", 0.3, t0=exp.t0)
    scales = {"current_A": float(np.std(m.current)), "speed_rpm": float(np.std(m.speed))}
    plain, _, _ = d._refit(m, p, (), "speed_sensor_lag", dict(base.values_), None, scales, train, exp)
    matched, _, _ = d._refit(m, p, (), "speed_sensor_lag", dict(base.values_), None, scales, train, exp, None, osc)
    assert plain.fit_percent_["current_A"] < 20.0
    assert matched.fit_percent_["current_A"] > 90.0
    assert matched.values_["tau_s"] == pytest.approx(truth["catalogue_values"]["tau_s"], rel=0.02)


def test_the_text_a_user_reads_about_a_hunting_loop():
    """The summary's and the HTML page's sentence, from a constructed oscillation, and its JSON form."""
    from kilnctl.measure.report import oscillation_dict, oscillation_text

    osc = Oscillation(8.2463, 715.2, 0.912)
    assert oscillation_text(osc) == (
        "The record's current oscillates at 8.25 Hz after the ramp (715 A RMS, 91 % of its variance): a loop "
        "hunting. Each candidate with one parameter was also started where the model oscillates at that frequency.")
    assert oscillation_dict(osc) == {"f_hz": 8.2463, "rms_A": 715.2, "share": 0.912}
    assert oscillation_dict(None) is None


def test_the_value_whose_oscillation_matches_the_record_is_found_between_the_grid_values():
    """Truth: a constructed model whose signal oscillates at 100/v Hz with amplitude 1000 for v >= 5 and holds no
    oscillation below (a loop stable for short lags); the record's 8.25 Hz is matched at v = 100/8.25 = 12.1212...,
    between the grid values 10 and 20.  A grid that does not bracket it, or whose neighbours do not both
    oscillate, gives None."""
    t = np.arange(0.0, 40.0, 0.02)

    def signal_at(v):
        if v < 5.0:
            return 400.0 + 0.0 * t
        return 400.0 + 1000.0 * np.sin(2 * np.pi * (100.0 / v) * t) * (t >= 8.0)

    target = Oscillation(8.25, 1000.0 / np.sqrt(2), 0.99)
    v = matching_value(signal_at, [1.0, 10.0, 20.0, 40.0], target, t, 9.0)
    assert v == pytest.approx(100.0 / 8.25, rel=1e-3)
    assert matching_value(signal_at, [20.0, 40.0], target, t, 9.0) is None  # 5-2.5 Hz: no crossing
    assert matching_value(signal_at, [1.0, 40.0], target, t, 9.0) is None  # one neighbour without a cycle
    assert matching_value(lambda v: None, [10.0, 20.0], target, t, 9.0) is None  # the model cannot be run
