"""The sandwich covariance of a least-squares fit under autocorrelated noise (kilnctl.measure.evidence).

Independent truth: the spread of the estimates over many records of known noise (Monte Carlo), and, for white
noise, the usual covariance s^2 (J^T J)^-1."""
import math

import numpy as np
import pytest
from scipy.signal import lfilter

from kilnctl.measure.evidence import correlation_length, score_covariance


def _records(phi, n=1000, count=200, seed=3):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n)
    X = np.c_[np.ones(n), t, np.sin(7.0 * t)]
    est, se_sandwich, se_usual = [], [], []
    for _ in range(count):
        w = rng.standard_normal(n)
        e = lfilter([1.0], [1.0, -phi], w)  # AR(1): e_t = phi e_(t-1) + w_t
        y = X @ [1.0, 2.0, 3.0] + e
        th = np.linalg.lstsq(X, y, rcond=None)[0]
        r = y - X @ th
        inv = np.linalg.inv(X.T @ X)
        S = score_covariance(-X, r)  # the residual y - X th has the Jacobian -X
        se_sandwich.append(np.sqrt(np.diag(inv @ S @ inv)))
        se_usual.append(np.sqrt(np.diag(inv) * (r @ r) / (n - 3)))
        est.append(th)
    spread = np.std(est, axis=0)
    return np.mean(se_sandwich, axis=0) / spread, np.mean(se_usual, axis=0) / spread


@pytest.mark.parametrize("phi", [0.0, 0.9])
def test_standard_errors_match_the_spread_of_the_estimates(phi):
    # truth: the standard deviation of 200 estimates from records of the same AR(1) noise; the sandwich's standard
    # errors match it within 20 % for white noise and for phi = 0.9, where the usual ones understate it (by the
    # square root of the variance inflation, (1 + phi)/(1 - phi) = 19: about 0.23)
    sandwich, usual = _records(phi)
    assert np.all((sandwich > 0.8) & (sandwich < 1.2)), sandwich
    if phi == 0.0:
        assert np.all((usual > 0.8) & (usual < 1.2)), usual
    else:
        assert np.all(usual < 0.4), usual


def test_white_noise_gives_the_usual_covariance():
    # truth: s^2 J^T J, the meat of the usual covariance, for one record of white noise (within the estimator's
    # own noise: 15 % on the diagonal for 4000 samples)
    rng = np.random.default_rng(7)
    n = 4000
    J = np.c_[np.ones(n), np.linspace(-1.0, 1.0, n)]
    r = 0.3 * rng.standard_normal(n)
    S = score_covariance(J, r)
    usual = (r @ r) / (n - 2) * (J.T @ J)
    assert np.diag(S) == pytest.approx(np.diag(usual), rel=0.15)


def test_two_channels_count_their_cross_correlation():
    # truth: a residual repeated in a second channel with the same Jacobian is one score doubled, whose
    # covariance is four times the one channel's (independent channels would give twice)
    rng = np.random.default_rng(11)
    n = 2000
    J1 = np.c_[np.ones(n), np.linspace(0.0, 1.0, n)]
    r1 = lfilter([1.0], [1.0, -0.8], rng.standard_normal(n))
    one = score_covariance(J1, r1, 1, n_params=2)
    both = score_covariance(np.vstack([J1, J1]), np.concatenate([r1, r1]), 2, n_params=2)
    assert both == pytest.approx(4.0 * one * (2 * n) / (2 * n - 2) * (n - 2) / n, rel=1e-9)


def test_correlation_length_of_white_and_coloured_noise():
    # truth: the autocorrelation of AR(1) noise, phi^k, stays positive for many lags (here about 1/(1 - phi) = 50
    # or more before the estimate's noise crosses 0); of white noise it is non-positive within a few lags
    rng = np.random.default_rng(5)
    w = rng.standard_normal(20000)
    assert correlation_length(w) <= 5
    assert correlation_length(lfilter([1.0], [1.0, -0.98], w)) > 50
    assert math.isclose(correlation_length(np.ones(3)), 1)


def test_lagged_sum_equals_the_direct_sum_over_lags():
    # truth: the Bartlett-weighted sum of the lagged products written out lag by lag
    from kilnctl.measure.evidence import _lagged_sum

    rng = np.random.default_rng(0)
    G = rng.standard_normal((500, 3))
    G[:, 1] += G[:, 0]
    L = 7
    S = G.T @ G
    for lag in range(1, L + 1):
        g = G[lag:].T @ G[:-lag]
        S += (1.0 - lag / (L + 1.0)) * (g + g.T)
    assert _lagged_sum(G, L) == pytest.approx(S, rel=1e-10, abs=1e-9)
