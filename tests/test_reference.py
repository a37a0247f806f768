"""The shape of a recorded speed reference: straight ramp or S-curve (kilnctl/measure/reference.py)."""

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.measure import Measurement
from kilnctl.measure.reference import fit_scurve
from kilnctl.measure.synthetic import DEFAULT_GAINS

SETUP = Parameters(DEFAULT_GAINS)


def _integrated_scurve(t, t0, a, t_j, top):
    """A drive's jerk-limited reference built by integrating its acceleration numerically (independent of the
    closed form in kilnctl.model.ramps): the acceleration rises linearly to a over t_j, holds, and falls to 0
    over t_j; the hold lasts until the reference reaches top."""
    h = 1e-4
    hold = top / a - t_j  # the area of the trapezoid a*(hold + t_j) is top
    tau = np.arange(0.0, 2 * t_j + hold + h, h)
    acc = a * np.clip(np.minimum(tau / t_j, (2 * t_j + hold - tau) / t_j), 0.0, 1.0)
    ref = np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * h)])
    return np.interp(t - t0, tau, ref, left=0.0, right=ref[-1])


def _straight_fit(t, ref, top):
    rising = (ref > 0.1 * top) & (ref < 0.9 * top)
    rate, icpt = np.polyfit(t[rising], ref[rising], 1)
    return rate, -icpt / rate


@pytest.mark.parametrize("t_j", [0.5, 1.85, 3.0])
def test_an_s_curve_reference_is_fitted_to_its_start_acceleration_and_rounding(t_j):
    """Truth: the numerically integrated reference above (start 1.5 s, 74 rpm/s, rounding t_j, 500 rpm),
    logged at 50 Hz to 0.01 rpm."""
    t = np.arange(0.0, 30.0, 0.02)
    ref = np.round(_integrated_scurve(t, 1.5, 74.0, t_j, 500.0), 2)
    rate, start = _straight_fit(t, ref, 500.0)
    fit = fit_scurve(t, ref, 500.0, rate, start)
    assert fit is not None
    assert fit.t0 == pytest.approx(1.5, abs=0.01)
    assert fit.a == pytest.approx(74.0, rel=2e-3)
    assert fit.rounding_s == pytest.approx(t_j, rel=0.02)
    assert fit.rms < 0.05 < fit.rms_straight


def test_a_straight_ramp_stays_straight_with_noise_or_resolution():
    """Truth: straight ramps (74 rpm/s from 1.5 s to 500 rpm), logged to 0.5 rpm, or with 0.3 rpm of noise,
    or with a rounding of one sample step: no S-curve."""
    t = np.arange(0.0, 30.0, 0.02)
    straight = np.clip(74.0 * (t - 1.5), 0.0, 500.0)
    noisy = straight + 0.3 * np.random.default_rng(0).standard_normal(t.size)
    for ref in (np.round(straight * 2) / 2, noisy, _integrated_scurve(t, 1.5, 74.0, 0.02, 500.0)):
        rate, start = _straight_fit(t, ref, 500.0)
        assert fit_scurve(t, ref, 500.0, rate, start) is None


def test_the_experiment_of_an_s_curve_record_follows_it_and_says_so():
    """Truth: the integrated reference (rounding 1.85 s) in a record: the experiment starts at its start, not
    where the straight ramp through its middle would (0.93 s later), ends the ramp when the reference reaches
    500 rpm, and a note says the model follows the S-curve.  A straight record's experiment is unchanged."""
    t = np.arange(0.0, 30.0, 0.02)
    ref = _integrated_scurve(t, 1.5, 74.0, 1.85, 500.0)
    m = Measurement.from_arrays(t, 300.0 + 0.0 * t, ref, ref)
    exp = m.experiment(SETUP)
    assert exp.jerk == pytest.approx(74.0 / 1.85, rel=0.02)
    assert exp.t0 == pytest.approx(1.5, abs=0.01)
    assert exp.ramp_end == pytest.approx(1.5 + 500.0 / 74.0 + 1.85, abs=0.02)
    assert any("S-curve" in n and "the model follows it" in n for n in exp.notes)
    assert exp.to_dict()["jerk_rpm_per_s2"] == exp.jerk
    straight = np.clip(74.0 * (t - 1.5), 0.0, 500.0)
    plain = Measurement.from_arrays(t, 300.0 + 0.0 * t, straight, straight).experiment(SETUP)
    assert plain.jerk is None and plain.t0 == pytest.approx(1.5, abs=1e-6)


def test_the_model_of_an_s_curve_record_runs_on_its_reference():
    """Truth: the integrated reference (rounding 1.85 s).  The model run on the record's experiment logs that
    reference (to the integration's accuracy), where a straight ramp through its middle misses it by up to
    a T_j / 8 = 17 rpm at the corners."""
    from kilnctl.measure.runner import run_model
    from kilnctl.simulate import resolve_gains

    t = np.arange(0.0, 16.0, 0.02)
    ref = _integrated_scurve(t, 1.5, 74.0, 1.85, 500.0)
    m = Measurement.from_arrays(t, 300.0 + 0.0 * t, ref, ref)
    run = run_model(resolve_gains(SETUP), m, m.experiment(SETUP))
    active = t >= m.experiment(SETUP).t0 - 1e-9
    assert np.max(np.abs(run.outputs["speed_ref_rpm"] - ref[active])) < 0.05
    rate, start = _straight_fit(t, ref, 500.0)
    assert np.max(np.abs(np.clip(rate * (t - start), 0, 500.0) - ref)) == pytest.approx(74.0 * 1.85 / 8, rel=0.02)
