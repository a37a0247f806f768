"""Changes outside the catalogue fitted in closed form (kilnctl.measure.outside).

Truths: lines and steps built by hand, with noise of a fixed seed, and stats.best_step (the step's own
search, tested in test_stats.py)."""

import numpy as np
import pytest

from kilnctl.measure.outside import CurrentDrift, CurrentPulse, CurrentStep
from kilnctl.measure.stats import best_pulse, best_step


def test_a_drift_is_the_least_squares_line_through_the_residual():
    # truth: the line the residual was built from (12 A at 3 s, rising 0.75 A/s), noise of 2 A
    t = np.linspace(3.0, 43.0, 2001)
    e = 12.0 + 0.75 * (t - 3.0) + np.random.default_rng(1).normal(0.0, 2.0, t.size)
    fitted = CurrentDrift().fit(t, e)
    assert fitted["kind"] == "drift" and fitted["t_start"] == 3.0 and fitted["t_end"] == 43.0
    assert fitted["rate"] == pytest.approx(0.75, abs=0.01)
    assert fitted["offset"] == pytest.approx(12.0, abs=0.3)
    assert fitted["rss"] == pytest.approx(4.0 * t.size, rel=0.1)
    shape = CurrentDrift().shape(t, fitted)
    assert shape[0] == pytest.approx(fitted["offset"]) and shape[-1] - shape[0] == pytest.approx(40 * fitted["rate"])
    assert "+30 A over the record's 40 s (+0.75 A/s)" in CurrentDrift.text(dict(fitted, rate=0.75))


def test_a_drift_needs_three_samples():
    assert CurrentDrift().fit([0.0, 1.0], [1.0, 2.0]) is None


def test_a_step_is_the_best_step_without_a_level_before():
    # truth: stats.best_step with intercept=False, and the step the residual was built from (-40 A at 25 s)
    t = np.arange(0.0, 40.0, 0.02)
    e = -40.0 * (t >= 25.0) + np.random.default_rng(2).normal(0.0, 3.0, t.size)
    term = CurrentStep((10.0, 38.0))
    fitted = term.fit(t, e)
    ref = best_step(t, e, t_min=10.0, t_max=38.0, intercept=False)
    assert fitted == dict(ref, kind="step")
    assert fitted["t"] == pytest.approx(25.0, abs=0.02) and fitted["size"] == pytest.approx(-40.0, abs=0.5)
    assert np.array_equal(term.shape(t, fitted), fitted["size"] * (t >= fitted["t"]))
    assert CurrentStep((50.0, 60.0)).fit(t, e) is None
    assert "at t = 25.0 s: the current steps by -40 A" in CurrentStep.text(fitted)


def test_a_pulse_is_the_pair_of_edges_a_brute_force_search_finds():
    # truth: every pair of sample edges tried by brute force (the height the mean between them, the rss
    # recomputed from the residual), on a short residual where the pulse's edges lie on the sample grid
    rng = np.random.default_rng(5)
    t = np.arange(0.0, 6.0, 0.05)
    e = 7.0 * ((t >= 2.0) & (t < 4.0)) + rng.normal(0.0, 2.0, t.size)
    fitted = best_pulse(t, e, t_min=0.5, t_max=5.5, min_width=0.5)
    best = None
    for i in range(t.size):
        for j in range(i + 1, t.size):
            if not (t[i] >= 0.5 and t[j] <= 5.5 and t[j] - t[i] >= 0.5):
                continue
            b = e[i:j].mean()
            rss = float(np.sum(e ** 2) - np.sum(e[i:j] ** 2) + np.sum((e[i:j] - b) ** 2))
            if best is None or rss < best[0]:
                best = (rss, t[i], t[j], b)
    assert fitted["rss"] == pytest.approx(best[0], rel=1e-9)
    assert (fitted["t"], fitted["t_end"]) == (best[1], best[2]) and fitted["size"] == pytest.approx(best[3])


def test_a_pulse_is_found_where_it_was_built_and_not_shorter_than_its_least_width():
    # truth: the pulse the residual was built from (+41 A from 21 s to 30 s, as red team 18's X1 left in a
    # model without it), noise of 2 A at 50 Hz; edges tried every fourth sample (80 ms)
    t = np.arange(0.0, 45.0, 0.02)
    e = 41.0 * ((t >= 21.0) & (t < 30.0)) + np.random.default_rng(3).normal(0.0, 2.0, t.size)
    term = CurrentPulse((13.0, 43.0))
    fitted = term.fit(t, e)
    assert fitted["kind"] == "pulse"
    assert fitted["t"] == pytest.approx(21.0, abs=0.1) and fitted["t_end"] == pytest.approx(30.0, abs=0.1)
    assert fitted["size"] == pytest.approx(41.0, abs=1.0)
    shape = term.shape(t, fitted)
    assert np.array_equal(shape != 0, (t >= fitted["t"]) & (t < fitted["t_end"]))
    assert "from t = 21.0 s to 30.0 s" in CurrentPulse.text(dict(fitted, t=21.0, t_end=30.0))
    # a window narrower than the least width holds no pulse
    assert CurrentPulse((20.0, 20.5)).fit(t, e) is None


def test_a_pulse_is_abrupt_only_where_its_edges_jump_above_the_records_own_noise():
    # truth by construction: (a) the residual is a 40 A pulse from 21 to 30 s in white noise of 2 A: across each
    # edge a second's mean jumps by the whole height, and the spread of such jumps elsewhere is 2 x sqrt(2/50)
    # = 0.4 A; (b) a smooth arc of the same height (half a sine from 13 to 33 s, as a kiln unbalance over part of
    # a turn) has a best pulse too, but a second's mean changes across its edges by a few A; (c) the 40 A pulse in
    # noise whose second-long means move by about 20 A anyway (AR(1) of 2 s, 40 A standard deviation): the
    # half-height is not three times the spread of the record's own jumps
    t = np.arange(0.0, 45.0, 0.02)
    rng = np.random.default_rng(11)
    box = 40.0 * ((t >= 21.0) & (t < 30.0))
    arc = 40.0 * np.clip(np.sin(np.pi * (t - 13.0) / 20.0), 0.0, None) * ((t >= 13.0) & (t < 33.0))
    term = CurrentPulse((8.0, 43.0))
    e = box + rng.normal(0.0, 2.0, t.size)
    assert term.abrupt(t, e, term.fit(t, e))
    e = arc + rng.normal(0.0, 2.0, t.size)
    fitted = term.fit(t, e)
    assert fitted["size"] > 20.0 and not term.abrupt(t, e, fitted)
    phi = np.exp(-0.02 / 2.0)
    w = np.zeros(t.size)
    for k in range(1, t.size):
        w[k] = phi * w[k - 1] + 40.0 * np.sqrt(1.0 - phi ** 2) * rng.standard_normal()
    e = box + w
    assert not term.abrupt(t, e, dict(t=21.0, t_end=30.0, size=40.0))
