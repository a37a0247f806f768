"""Evidence for a candidate effect under coloured noise: variance inflation, whitening, held-out z.

A candidate's BIC counts every sample as independent; under coloured noise a
slow change then looks like strong evidence.  These functions model the
residual's autocorrelation (an autoregressive whitening filter; feasible
generalised least squares) and give the held-out gain in standard errors
that allow for it.  Used by :class:`~kilnctl.measure.diagnose.Diagnosis`.
"""

from __future__ import annotations

import math

import numpy as np

from .runner import CHANNELS

__all__ = ["variance_inflation", "noise_filter", "whiten", "holdout_z", "whitened_delta_bic"]


def variance_inflation(e, max_lag: int | None = None) -> float:
    """Variance inflation of a sum of autocorrelated residuals: 1 + 2 sum_k rho_k.

    The sum runs over the initial positive run of the autocorrelation (Geyer's
    initial positive sequence); 1 for white noise, (1 + phi)/(1 - phi) for
    first-order autoregressive noise.

    Parameters
    ----------
    e : array_like
        Residual, evenly sampled.
    max_lag : int, optional
        Largest lag [samples] (default N/4).

    Returns
    -------
    float
        >= 1.
    """
    from .stats import autocorr

    e = np.asarray(e, float)
    L = max(1, min(e.size // 4, max_lag or e.size // 4))
    r = autocorr(e - e.mean(), L)["r"][1:]
    neg = np.nonzero(r <= 0)[0]
    r = r[: neg[0]] if neg.size else r
    return float(max(1.0, 1.0 + 2.0 * r.sum()))


def noise_filter(e, max_order: int = 25) -> np.ndarray:
    """Whitening filter of a residual: the autoregressive model e_t = sum_k a_k e_(t-k) + w_t that BIC chooses.

    Yule-Walker estimates of every order up to ``max_order``; the order with
    the lowest n ln(sigma_w^2) + p ln(n) is kept.  Applied as
    ``w = e - sum_k a_k e_(t-k)`` (:func:`whiten`), it turns coloured
    measurement noise into nearly white noise.

    Parameters
    ----------
    e : array_like
        Residual, evenly sampled [any unit].
    max_order : int, default 25
        Largest order [samples].

    Returns
    -------
    ndarray
        Coefficients a_1..a_p [-] (empty for white noise).
    """
    from scipy.linalg import solve_toeplitz

    e = np.asarray(e, float) - float(np.mean(e))
    n = e.size
    p_max = max(0, min(max_order, n // 10))
    if p_max == 0 or not np.any(e):
        return np.zeros(0)
    r = np.array([e[: n - k] @ e[k:] for k in range(p_max + 1)]) / n
    best, best_crit = np.zeros(0), n * math.log(max(r[0], 1e-300))
    for p in range(1, p_max + 1):
        a = solve_toeplitz(r[:p], r[1: p + 1])
        s2 = r[0] - a @ r[1: p + 1]
        crit = n * math.log(max(s2, 1e-300 * r[0], 1e-300)) + p * math.log(n)
        if crit < best_crit:
            best, best_crit = a, crit
    return best


def whiten(e, a) -> np.ndarray:
    """Apply a whitening filter from :func:`noise_filter`: w_t = e_t - sum_k a_k e_(t-k) (w_t = e_t for t < p)."""
    e = np.asarray(e, float)
    w = e.copy()
    for k, ak in enumerate(a, start=1):
        w[k:] -= ak * e[:-k]
    return w


def holdout_z(m, cal, current, exp, te, scales) -> float:
    """The held-out gain in units of its standard error: sum of d_i = e_cur,i^2 - e_cand,i^2 (scaled, both
    channels) over the held-out samples, divided by sqrt(N var(d) f), f the variance inflation of the series d
    (:func:`variance_inflation`: neighbouring samples of coloured noise are not independent evidence)."""
    active = m.t >= exp.t0 - 1e-9
    d = 0.0
    for c in CHANNELS:
        y = m.channels[c][active]
        d = d + ((y - current.run_.outputs[c]) ** 2 - (y - cal.run_.outputs[c]) ** 2) / scales[c] ** 2
    d = d[te]
    if d.size < 10 or not np.any(d):
        return 0.0
    se = math.sqrt(d.size * float(np.var(d)) * variance_inflation(d, max_lag=max(1, d.size // 10)))
    return float(np.sum(d) / se) if se > 0 else 0.0


def whitened_delta_bic(m, cal, current, exp, train) -> float:
    """delta BIC of the two models with the coloured noise modelled (feasible generalised least squares).

    Coloured noise makes neighbouring residuals nearly repeat each other, and an ordinary BIC counts each as
    new evidence: a slow change of the model (a drift, an offset over the ramp) then looks far better supported
    than it is.  Per channel, an autoregressive noise model (:func:`noise_filter`) is estimated from the
    residual of the model that fits that channel better on the fitting part (the closer estimate of the
    noise: the other one still holds what it misses), both residuals pass through that one whitening filter,
    and BIC compares the whitened sums of squares on the fitting part.  A filter estimated from each model's
    own residual would let a model's misfit pass for noise (a step the model misses looks like slow noise);
    one estimated always from the candidate's would let a candidate that fits worse choose the yardstick.
    """
    active = m.t >= exp.t0 - 1e-9
    tr = train[active]
    val, n_tot = 0.0, 0
    for c in CHANNELS:
        y = m.channels[c][active]
        e_new, e_old = y - cal.run_.outputs[c], y - current.run_.outputs[c]
        ref = e_new if float(e_new[tr] @ e_new[tr]) <= float(e_old[tr] @ e_old[tr]) else e_old
        a = noise_filter(ref)
        w_new, w_old = whiten(e_new, a)[tr], whiten(e_old, a)[tr]
        val += tr.sum() * math.log(max(float(w_new @ w_new), 1e-300) / max(float(w_old @ w_old), 1e-300))
        n_tot += int(tr.sum())
    k_new = len(cal.values_) - len(current.values_)
    return float(val + k_new * math.log(max(n_tot, 2)))



# --- residual signature --------------------------------------------------------------------------
