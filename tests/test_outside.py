"""Changes outside the catalogue fitted in closed form (kilnctl.measure.outside).

Truths: lines and steps built by hand, with noise of a fixed seed, and stats.best_step (the step's own
search, tested in test_stats.py)."""

import numpy as np
import pytest

from kilnctl.measure.outside import CurrentDrift, CurrentStep
from kilnctl.measure.stats import best_step


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
