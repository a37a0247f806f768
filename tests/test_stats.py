"""Residual statistics on the uneven time base of a historian record (jitter, dropped samples).

Truths: the frequency of a sinusoid; the autocorrelation cos(2 pi f tau) of a sinusoid at a lag tau in
seconds (analytic); white noise, whose autocorrelation is zero at every lag; a delayed copy, whose
cross-correlation peaks at the delay.
"""

import math

import numpy as np
import pytest

from kilnctl.errors import ParameterError
from kilnctl.measure.stats import autocorr, crosscorr, median_step, residual_spectrum


def historian_times(n=4000, dt=0.02, spread=0.4, dropped=0.03, seed=0):
    """Times of a 50 Hz logger whose steps vary at random by +-spread of dt, with a share of samples dropped."""
    rng = np.random.default_rng(seed)
    t = np.cumsum(dt * rng.uniform(1.0 - spread, 1.0 + spread, n))
    return t[rng.random(n) > dropped]


def test_the_time_base_is_uneven_and_has_gaps():
    # the fixture itself: not a grid (so no statistic may treat it as one) and with dropped samples
    t = historian_times()
    steps = np.diff(t) / median_step(t)
    assert steps.min() < 0.7 and steps.max() > 1.9  # a dropped sample: two steps in one
    assert np.sum(steps > 1.5) > 50


def test_dominant_frequency_of_a_sinusoid_on_a_jittered_grid_with_dropped_samples():
    # truth: the sinusoid's frequency (0.7 Hz: a burden oscillation; 4.3 Hz: a torsional mode), neither on a bin
    t = historian_times()
    rng = np.random.default_rng(1)
    for f in (0.7, 4.3):
        e = 3.0 * np.sin(2 * np.pi * f * t + 0.4) + rng.standard_normal(t.size)
        s = residual_spectrum(e, t=t, seconds=20.0)
        resolution = s["f"][1] - s["f"][0]
        assert resolution == pytest.approx(1.0 / (1024 * median_step(t)))  # 2^10 samples of the median step
        assert abs(s["dominant_hz"] - f) <= resolution
        assert s["narrowband_ratio"] > 20  # a line, not coloured noise
    # with 10 % of the samples dropped, taking the samples as evenly spaced at the median step shortens the
    # record's time (by 5 %: the median step grows too) and puts the 4.3 Hz line at 4.54 Hz: the time base matters
    t = historian_times(dropped=0.10, seed=7)
    e = 3.0 * np.sin(2 * np.pi * 4.3 * t + 0.4) + rng.standard_normal(t.size)
    assert abs(residual_spectrum(e, t=t, seconds=20.0)["dominant_hz"] - 4.3) <= resolution
    assert abs(residual_spectrum(e, 1.0 / median_step(t), seconds=20.0)["dominant_hz"] - 4.3) > 3 * resolution


def test_autocorrelation_of_a_sinusoid_at_lags_in_seconds():
    # truth: for x = cos(2 pi f t) the biased autocorrelation estimate is cos(2 pi f tau) (1 - tau / T), T the
    # record's length (averages of cos(4 pi f t + ...) over many periods vanish); lags are tau = k dt
    t = historian_times(seed=2)
    f = 0.7
    w = autocorr(np.cos(2 * np.pi * f * t), 250, t=t)
    dt = median_step(t)
    tau = w["lags"] * dt
    analytic = np.cos(2 * np.pi * f * tau) * (1.0 - tau / (t[-1] - t[0] + dt))
    assert np.max(np.abs(w["r"] - analytic)) < 0.02
    # at the half period, tau = 1 / (2 f) = 0.714 s, the correlation is -1 (less the 1.8 % of the overlap lost)
    k = int(round(1.0 / (2 * f) / dt))
    assert w["r"][k] == pytest.approx(math.cos(2 * np.pi * f * k * dt) * (1 - k * dt / (t[-1] - t[0])), abs=0.02)


def test_white_noise_on_an_uneven_time_base_stays_white():
    # truth: independent samples are uncorrelated at every lag, so about 1 % of lags fall outside the 99 % band.
    # Interpolating them onto a grid would mix neighbours and correlate them at the first lag (r = 0.27).
    t = historian_times(seed=3)
    e = np.random.default_rng(4).standard_normal(t.size)
    w = autocorr(e, 200, t=t)
    assert abs(w["r"][1]) < w["band"]
    assert w["fraction_outside"] < 0.03
    grid = t[0] + median_step(t) * np.arange(int((t[-1] - t[0]) / median_step(t)) + 1)
    assert autocorr(np.interp(grid, t, e), 5)["r"][1] > 0.2  # what interpolation would have reported


def test_cross_correlation_peaks_at_the_delay_in_seconds():
    # truth: e(t) = u(t - 0.30 s) for a smooth signal u: the cross-correlation peaks at lag +0.30 s
    t = historian_times(seed=5)

    def u(x):
        return np.sin(2 * np.pi * 0.9 * x) + 0.6 * np.sin(2 * np.pi * 2.3 * x + 1.0) + 0.4 * np.sin(2 * np.pi * 0.17 * x)

    c = crosscorr(u(t - 0.30), u(t), 60, t=t)
    peak = c["lags"][int(np.argmax(c["r"]))] * median_step(t)
    assert peak == pytest.approx(0.30, abs=median_step(t) / 2 + 1e-12)


def test_an_even_time_base_gives_the_usual_estimates():
    # truth: on an even time base the statistics with t are those without it (the estimates of MATLAB's resid)
    rng = np.random.default_rng(6)
    t = 0.02 * np.arange(3000) + 5.0
    e = np.convolve(rng.standard_normal(3000), np.ones(5) / 5, mode="same")
    u = rng.standard_normal(3000)
    assert np.allclose(autocorr(e, 100, t=t)["r"], autocorr(e, 100)["r"])
    assert np.allclose(crosscorr(e, u, 50, t=t)["r"], crosscorr(e, u, 50)["r"])
    a, b = residual_spectrum(e, t=t), residual_spectrum(e, 50.0)
    assert np.allclose(a["psd"], b["psd"]) and a["dominant_hz"] == pytest.approx(b["dominant_hz"])


def test_spectrum_needs_fs_or_t_but_not_both():
    e = np.zeros(100)
    with pytest.raises(ParameterError, match="fs"):
        residual_spectrum(e)
    with pytest.raises(ParameterError, match="both"):
        residual_spectrum(e, 50.0, t=np.arange(100) * 0.02)


def test_lag_zero_is_one_even_where_two_samples_nearly_coincide():
    # truth: r(0) = 1 by definition (each sample with itself); the time base has 149 samples closer than half a
    # median step to their neighbour, which must not count at lag 0
    t = historian_times(n=2000, spread=0.6, seed=8)
    assert np.sum(np.diff(t) < 0.5 * median_step(t)) > 100
    e = np.random.default_rng(9).standard_normal(t.size)
    assert autocorr(e, 50, t=t)["r"][0] == pytest.approx(1.0, abs=1e-12)
