"""The phase-free residual of self-sustained cycles and the horizon-truncated model runs of a calibration."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from kilnctl import Parameters
from kilnctl.measure import Measurement
from kilnctl.measure.calibrate import _autocov, _Problem
from kilnctl.measure.runner import run_model
from kilnctl.simulate import resolve_gains

FS = 50.0


def test_autocovariance_of_a_gapped_series_by_direct_sums():
    # truth: the definition, summed pair by pair over the samples present in both places
    rng = np.random.default_rng(3)
    x = rng.standard_normal(300)
    w = (rng.random(300) > 0.3).astype(float)
    got = _autocov(x * w, w, 2, 40)
    for k, g in zip(range(2, 41), got):
        pairs = w[:-k] * w[k:]
        assert g == pytest.approx(np.sum(x[:-k] * x[k:] * pairs) / pairs.sum(), rel=1e-9, abs=1e-12)


def _problem(meas_current, cycles_from):
    t = np.arange(meas_current.size) / FS
    m = Measurement.from_arrays(t, meas_current + 500.0, np.full(t.size, 500.0), np.full(t.size, 500.0))
    exp = SimpleNamespace(t0=0.0, ramp_rate=74.0, omega_ref=500.0)
    prob = _Problem(m, exp, Parameters(), "macro", (), {"current_A": 10.0, "speed_rpm": 1.0}, None)
    prob.cycles_from = cycles_from
    return prob, t


def test_cycles_out_of_phase_cost_nothing_in_the_phase_free_residual():
    # truth (analytic): the autocovariance of a sinusoid, A^2/2 cos(w k dt), does not depend on its phase, so a
    # model whose cycles are half a period late fits the record's cycles exactly, while the residual itself
    # is as large as it can be; a wrong period, or a wrong level, is not forgiven
    t = np.arange(0, 40.0, 1 / FS)
    w = 2 * math.pi / 3.0  # a 3 s stick-slip period
    meas = 50.0 * np.sin(w * t)
    prob, _ = _problem(meas, cycles_from=10.0)

    def run(current):
        return SimpleNamespace(outputs={"current_A": current + 500.0, "speed_rpm": np.full(t.size, 500.0)})

    late = prob.residual(run(50.0 * np.sin(w * t + math.pi)))
    head = int(np.sum(t < 10.0))
    assert np.max(np.abs(late[head:])) < 0.02 * 50.0 ** 2 / 10.0 ** 2  # lags: within 2 % of the amplitude^2
    assert np.sum(late[:head] ** 2) > 40.0 * head  # before cycles_from: the residual itself (mean of (10 sin)^2: 50)
    other_period = prob.residual(run(50.0 * np.sin(1.1 * w * t)))
    higher = prob.residual(run(50.0 * np.sin(w * t) + 20.0))
    assert np.sum(other_period[head:] ** 2) > 100.0 * np.sum(late[head:] ** 2)
    assert np.sum(higher[head:] ** 2) > 100.0 * np.sum(late[head:] ** 2)
    prob.cycles_from = None  # the ordinary residual: the late cycles cost twice the record's energy
    plain = prob.residual(run(50.0 * np.sin(w * t + math.pi)))
    assert np.sum(plain[: t.size] ** 2) == pytest.approx(np.sum((2 * meas / 10.0) ** 2), rel=1e-9)


def test_a_run_stopped_at_the_horizon_equals_the_whole_run_up_to_it():
    # truth: the same simulation run to the end of the record (the model is causal)
    params = resolve_gains(Parameters(gains="given", k_p=2.0, k_I=5.0, k_D=0.01, friction_law="torque"))
    t = np.arange(0, 20.0, 1 / FS)
    m = Measurement.from_arrays(t, np.zeros(t.size), np.zeros(t.size))
    exp = SimpleNamespace(t0=0.0, ramp_rate=params.ramp_rate, omega_ref=params.omega_ref)
    whole = run_model(params, m, exp)
    part = run_model(params, m, exp, t_stop=9.0)
    upto = t <= 9.0
    for c in ("current_A", "speed_rpm"):
        np.testing.assert_allclose(part.outputs[c][upto], whole.outputs[c][upto], rtol=1e-9, atol=1e-9)
    assert part.response.t[-1] < 9.1


def test_whitening_filter_turns_coloured_noise_white():
    # truth: white noise plus first-order autoregressive noise (phi = 0.95, the benchmark's 0.4 s at 50 Hz) has
    # lag-1 autocorrelation 0.5 * 0.95; after the fitted filter the autocorrelation of lags 1-50 lies within
    # the 99 % band of white noise (2.576 / sqrt(N)) but for about 1 % of them
    from kilnctl.measure.evidence import noise_filter, whiten
    from kilnctl.measure.stats import autocorr

    rng = np.random.default_rng(5)
    n = 4000
    ar = np.zeros(n)
    for k in range(1, n):
        ar[k] = 0.95 * ar[k - 1] + math.sqrt(1 - 0.95 ** 2) * 4.0 * rng.standard_normal()
    e = 4.0 * rng.standard_normal(n) + ar
    assert autocorr(e, 50)["r"][1] == pytest.approx(0.475, abs=0.05)
    a = noise_filter(e)
    assert 0 < a.size <= 25
    ac = autocorr(whiten(e, a)[a.size:], 50)
    assert ac["n_outside"] <= 3
    assert noise_filter(rng.standard_normal(n)).size == 0  # white noise needs no filter


def test_a_fit_that_improves_on_its_start_does_not_say_it_kept_it():
    # truth: the cost at the given values themselves (n_local=0, the test below checks it against a direct run):
    # a local fit from 10 % off the record's mu_c ends below it, and kept_start_ says so; from the values it
    # ended at, asked for no fit, the start is kept
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    setup = resolve_gains(Parameters(DEFAULT_GAINS))
    m, _ = make_record((), seed=5, t_end=12.0)
    given = {"mu_c": 0.9 * setup.mu_c, "m_v": setup.m_v}
    at_start = Calibration(setup, ("mu_c", "m_v")).fit(m, init=given, starts=[], n_local=0)
    fitted = Calibration(setup, ("mu_c", "m_v")).fit(m, init=given, starts=[], n_local=1)
    assert fitted.cost_ < at_start.cost_ and not fitted.kept_start_
    assert len(fitted.local_fits_) == 1 and fitted.local_fits_[0]["start"] == pytest.approx(given)


def test_no_local_fit_judges_the_structure_at_the_given_values():
    # truth: the model run directly at the given values (run_model), its squared error summed by hand over the
    # samples from the start of the experiment; n_local=0 asks for no fit, so nothing may move
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    setup = resolve_gains(Parameters(DEFAULT_GAINS))
    m, _ = make_record((), seed=5, t_end=12.0)
    given = {"mu_c": 0.9 * setup.mu_c, "mu_s": 1.1 * setup.mu_s, "m_v": setup.m_v, "J_v": 1.2 * setup.J_v}
    cal = Calibration(setup, ("mu_c", "mu_s", "m_v", "J_v")).fit(m, init=given, starts=[], n_local=0)
    assert cal.values_ == pytest.approx(given, rel=1e-12)
    assert cal.local_fits_ == [] and cal.kept_start_
    exp = m.experiment(setup)
    run = run_model(setup.replace(**given), m, exp)
    active = m.t >= exp.t0 - 1e-9
    for c in ("current_A", "speed_rpm"):
        direct = float(np.sum((m.channels[c][active] - run.outputs[c]) ** 2))
        assert cal.rss_[c] == pytest.approx(direct, rel=1e-9)


@pytest.mark.parametrize("B_o, on_bound", [(6e5, False), (0.0, True)])
def test_a_value_many_standard_errors_from_a_bound_is_not_on_it(B_o, on_bound):
    # truth by construction: kilnctl's generator with a viscous drag of 6e5 N*m*s/rad (red team 9's R02: 0.06 %
    # of the 0-1e9 range, within the old 1e-3 band, about three standard errors above 0 once they allow for the
    # coloured noise: 2.3e5 here, 2.1e5 the spread over seeds, see the test below), and without one (the fit
    # ends at the bound 0)
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.effects import CATALOGUE
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    setup = resolve_gains(Parameters(DEFAULT_GAINS))
    hidden = ("viscous_drag",) if B_o else ()
    m, _ = make_record(hidden, seed=7, t_end=20.0, magnitudes={"B_o": B_o} if B_o else None)
    free = ["mu_c", "m_v", *CATALOGUE["viscous_drag"].parameters]
    cal = Calibration(setup, free, effects=("viscous_drag",)).fit(m, init={"B_o": 3e5}, n_local=1)
    if on_bound:
        assert "B_o" in cal.on_bound_
    else:
        assert cal.values_["B_o"] == pytest.approx(B_o, rel=0.2)
        assert cal.values_["B_o"] > 2 * cal.stderr_["B_o"] and "B_o" not in cal.on_bound_


@pytest.mark.slow
def test_standard_errors_under_coloured_noise_match_the_spread_over_records():
    # truth: the spread of the fitted drag over twelve records of kilnctl's generator that differ only in the
    # noise's seed (white 4 A plus AR(1) 4 A of 0.4 s on the current): standard deviation 2.1e5 N*m*s/rad when
    # the sandwich covariance came in, mean reported standard error 2.4e5 (the usual s^2 (J^T J)^-1 had given
    # about 2e4: the drag's score is slow, where the coloured noise has most of its power)
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.effects import CATALOGUE
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    setup = resolve_gains(Parameters(DEFAULT_GAINS))
    values, errors = [], []
    for seed in range(7, 19):
        m, _ = make_record(("viscous_drag",), seed=seed, t_end=20.0, magnitudes={"B_o": 6e5})
        free = ["mu_c", "m_v", *CATALOGUE["viscous_drag"].parameters]
        cal = Calibration(setup, free, effects=("viscous_drag",)).fit(m, init={"B_o": 3e5}, n_local=1)
        values.append(cal.values_["B_o"])
        errors.append(cal.stderr_["B_o"])
    ratio = float(np.mean(errors) / np.std(values, ddof=1))
    assert 0.6 < ratio < 1.6, ratio
