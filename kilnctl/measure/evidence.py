"""Evidence for a candidate effect: the tests it must pass, under coloured noise.

A candidate's BIC counts every sample as independent; under coloured noise a
slow change then looks like strong evidence.  These functions model the
residual's autocorrelation (an autoregressive whitening filter; feasible
generalised least squares) and give the held-out gain in standard errors
that allow for it; :func:`judge` applies the rules of
:class:`~kilnctl.measure.diagnose.Diagnosis` to a refitted candidate and
returns its :class:`CandidateResult` (what it gained, whether it is
supported, and why).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .effects import CATALOGUE
from .report import json_number as _num, unit_of as _unit
from .runner import CHANNELS
from .stats import _initial_positive, fit_percent, noise_excess, variance_inflation

if TYPE_CHECKING:
    from .calibrate import Calibration

__all__ = ["variance_inflation", "correlation_length", "score_covariance", "noise_filter", "whiten", "holdout_z",
           "whitened_delta_bic", "CandidateResult", "close_rival", "within_noise", "speed_follows_otherwise",
           "SPEED_EXCESS", "SPEED_FIT_STRUCTURE", "judge"]


def correlation_length(e, max_lag: int | None = None) -> int:
    """The first lag at which the autocorrelation of ``e`` is no longer positive [samples] (Geyer's initial
    positive sequence, as :func:`variance_inflation` sums it); 1 for white noise, ``max_lag`` (default N/4)
    when it stays positive."""
    if np.size(e) < 4:
        return 1
    L = max(1, min(np.size(e) // 4, max_lag or np.size(e) // 4))
    return min(int(_initial_positive(e, max_lag).size) + 1, L)


PREWHITEN_CAP = 0.99
"""Largest singular value of the first-order autoregression that prewhitens the scores (:func:`score_covariance`;
Andrews and Monahan take 0.97: AR(1) noise of a second at 50 Hz has 0.98)."""


def _lagged_sum(G, L: int) -> np.ndarray:
    """Gamma_0 + sum_(l=1..L) (1 - l/(L+1)) (Gamma_l + Gamma_l^T), Gamma_l = sum_t g_t g_(t-l)^T (every lag at
    once through the FFT, zero-padded: no wrap-around)."""
    n, p = G.shape
    nfft = 1 << int(math.ceil(math.log2(2 * n)))
    F = np.fft.rfft(G, nfft, axis=0)
    w = np.concatenate([[0.5], 1.0 - np.arange(1, L + 1) / (L + 1.0)])  # lag 0 counted once, below twice
    S = np.empty((p, p))
    for i in range(p):  # pair by pair: memory of one series, whatever the record's length
        for j in range(i, p):
            c = np.fft.irfft(F[:, i] * np.conj(F[:, j]), nfft)  # c[l] = sum_t G[t+l,i] G[t,j], c[-l] the other way
            g = w @ c[:L + 1] + w @ np.concatenate([[c[0]], c[:-L - 1:-1]])
            S[i, j] = S[j, i] = g
    return S


def score_covariance(J, r, n_channels: int = 1, n_params: int | None = None) -> np.ndarray:
    """Long-run covariance of the least-squares score J^T r when the residual is autocorrelated.

    The "meat" S of the sandwich covariance of nonlinear least squares, (J^T J)^-1 S (J^T J)^-1, estimated as
    Andrews and Monahan (1992) do: the scores g_t (of the samples at time t, summed over the channels so that
    their cross-correlation counts) are prewhitened by a first-order vector autoregression g_t = A g_(t-1) + u_t
    (its singular values capped at :data:`PREWHITEN_CAP`), the long-run covariance of u is the Newey-West sum
    with Bartlett weights up to twice the longest :func:`correlation_length` of its columns (at most N/4), and
    S = (I - A)^-1 S_u (I - A)^-T.  For white noise S is about s^2 J^T J, the usual covariance s^2 (J^T J)^-1;
    for noise correlated over many samples the usual one understates the spread of the estimates by up to the
    square root of :func:`variance_inflation`.  On a linear fit under AR(1) noise (2000 samples, 300 records)
    the standard errors from S are 0.90-0.97 of the estimates' spread for white noise, 0.98-1.01 for a
    coefficient of 0.9 and 0.85-0.93 for 0.98 (the usual ones: 0.15 for 0.95); without the prewhitening 0.66-0.70
    for 0.98 (tests/test_score_covariance.py checks white noise and 0.9).

    Parameters
    ----------
    J : ndarray, shape (n_channels * N, p)
        Jacobian of the residual, the channels stacked in blocks of N samples.
    r : ndarray, shape (n_channels * N,)
        Residual, stacked the same way.
    n_channels : int, default 1
        Channels (blocks of rows); rows of a block are consecutive samples.
    n_params : int, optional
        Parameters for the degrees-of-freedom factor m / (m - p) (default p).

    Returns
    -------
    ndarray, shape (p, p)
        S, in the units of J^T J times those of r squared.
    """
    J = np.asarray(J, float)
    r = np.asarray(r, float)
    m, p = J.shape
    n = m // n_channels
    G = sum(J[i * n:(i + 1) * n] * r[i * n:(i + 1) * n, None] for i in range(n_channels))
    # least squares g_t ~ A g_(t-1) by its normal equations (p x p: numpy's lstsq on the N x p system took 0.13 s
    # a call on the loaded test machine), the pseudo-inverse for a score that is zero or repeated
    A = (np.linalg.pinv(G[:-1].T @ G[:-1]) @ (G[:-1].T @ G[1:])).T
    U, sv, Vt = np.linalg.svd(A)
    A = (U * np.minimum(sv, PREWHITEN_CAP)) @ Vt
    u = G[1:] - G[:-1] @ A.T
    lag = max(correlation_length(u[:, j]) for j in range(p)) if np.any(u) else 1
    S_u = _lagged_sum(u, int(min(max(u.shape[0] // 4, 1), 2 * lag)))
    B = np.linalg.inv(np.eye(p) - A)
    S = B @ S_u @ B.T
    k = p if n_params is None else n_params
    return 0.5 * (S + S.T) * m / max(m - k, 1)


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


@dataclass
class CandidateResult:
    """One candidate effect refitted on the fitting part of the record.

    Attributes
    ----------
    effect : str
        Catalogue name.
    delta_bic : float
        BIC of the candidate minus BIC of the current model (fitting part);
        negative favours the candidate.
    holdout_gain : float
        Reduction of the weighted squared error on the held-out part [%]
        (positive: the candidate predicts unseen samples better).
    fit_percent : dict
        Fit % per channel on the fitting part.
    holdout_fit_percent : dict
        Fit % per channel on the held-out part.
    parameters : dict
        Fitted values with ``value``, ``stderr``, ``unit`` (effect and base).
    on_bound, not_identifiable : list of str
        Flags of the fitted parameters.
    supported : bool
        Both criteria met.
    reason : str
        Why it is (not) supported.
    wall_s : float
        Time the refit took [s].
    heldout_share : float
        Share of the candidate's change to the (scaled) model output that
        falls in the held-out part [-].
    delta_bic_corrected : float
        delta BIC of the residuals whitened by an autoregressive model of the
        better-fitting one's residual (feasible generalised least squares: the
        coloured noise modelled).
    holdout_z : float
        The held-out gain in standard errors (which allow for the residual's
        autocorrelation).
    stand_in : bool
        The refit improved the fit enough to be supported, but its values
        contradict the effect's own signature (:attr:`Effect.contradicts`):
        it stands in for another difference.
    form : str or None
        The other form of the effect (:attr:`Effect.forms`) the result is in,
        None for the effect's own.
    """

    effect: str
    delta_bic: float
    holdout_gain: float
    fit_percent: dict
    holdout_fit_percent: dict
    parameters: dict
    on_bound: list
    not_identifiable: list
    supported: bool
    reason: str
    wall_s: float
    calibration: Calibration | None = field(default=None, repr=False)
    heldout_share: float = math.nan
    delta_bic_corrected: float = math.nan
    holdout_z: float = math.nan
    stand_in: bool = False
    form: str | None = None

    def to_dict(self) -> dict:
        """Return the result as a JSON-ready dictionary."""
        return {"effect": self.effect, "delta_bic": _num(self.delta_bic),
                "holdout_gain_percent": _num(self.holdout_gain),
                "fit_percent": {k: _num(v) for k, v in self.fit_percent.items()},
                "holdout_fit_percent": {k: _num(v) for k, v in self.holdout_fit_percent.items()},
                "parameters": {k: {"value": _num(v["value"]), "stderr": _num(v["stderr"]), "unit": v["unit"]}
                               for k, v in self.parameters.items()},
                "on_bound": list(self.on_bound), "not_identifiable": list(self.not_identifiable),
                "supported": self.supported, "reason": self.reason, "wall_s": self.wall_s,
                "heldout_share": _num(self.heldout_share), "delta_bic_corrected": _num(self.delta_bic_corrected),
                "holdout_z": _num(self.holdout_z), "stand_in": self.stand_in, "form": self.form}


#: fit [%] of each channel from which the current model's residual is taken to be mostly noise (see
#: :func:`within_noise`)
NOISE_FIT = 90.0
#: a speed residual whose RMS is this many times its sample-to-sample noise
#: (:func:`~kilnctl.measure.stats.noise_excess`) is a following error the model lacks, not the logger's noise (AR(1) noise reaches it at phi = 0.99) [-] ...
SPEED_EXCESS = 10.0
#: ... when the speed fit is also below this [%] (the 79 benchmark records' final models fit the speed to 99.57 %
#: or more; red team 11's cascade drive, 97.4 % with a residual of +-6 rpm, 20 times the speed's noise, had
#: been "no structure beyond noise": the signature looked only at the current)
SPEED_FIT_STRUCTURE = 99.0


def speed_follows_otherwise(speed_fit: float, residual) -> bool:
    """True when a model's speed misses the record by more than its noise: a fit below :data:`SPEED_FIT_STRUCTURE`
    with a residual more than :data:`SPEED_EXCESS` times its sample-to-sample noise.  A speed-controlled drive
    follows its reference within its noise; a model that does not has a controller, a sensor or a limit other
    than the drive's.

    Parameters
    ----------
    speed_fit : float
        The model's speed fit [%].
    residual : array_like
        Its speed residual [rpm], in time order.

    Returns
    -------
    bool
    """
    return bool(speed_fit < SPEED_FIT_STRUCTURE and noise_excess(residual) > SPEED_EXCESS)


def within_noise(fits: dict, speed_residual=None) -> bool:
    """True when a model fits the record within its noise: every channel's fit at least :data:`NOISE_FIT`, and,
    given its speed residual, a speed that does not miss by more than its noise (:func:`speed_follows_otherwise`).

    The current alone is not enough: on red team 16's E5 (a current limit that falls with speed) the base model
    fitted the current at 92.7 % while its speed, which never left the reference, fitted at 11 %, 150 rpm off;
    the whitening filter took that misfit for noise, and a current limit that predicted the held-out part 84 %
    better (4.4 standard errors) was rejected for a whitened dBIC of +507 "where the model already fits
    within its noise".  Nor is a speed fit of 90 %: on red team 20's E2 (a limit falling with speed, the kiln
    20 rpm below its set speed for 30 s, 185 times the speed's noise) the base model's speed fitted 90.5 % on the
    fitting part, and the current limit (dBIC -186, held-out +2.1 %) was refused so.

    Parameters
    ----------
    fits : dict of str to float
        Fit [%] per channel (``Calibration.fit_percent_``, ``CandidateResult.fit_percent``).
    speed_residual : array_like, optional
        The model's speed residual [rpm]; without it the fits alone decide.

    Returns
    -------
    bool
    """
    if "current_A" not in fits or not all(fits[c] >= NOISE_FIT for c in CHANNELS if c in fits):
        return False
    return speed_residual is None or not speed_follows_otherwise(fits.get("speed_rpm", 100.0), speed_residual)


#: where the current model has stick-slip cycles and fits within noise, a refit that predicts the held-out part
#: worse must lower BIC with the coloured noise modelled by this many times ``min_delta_bic`` (see :func:`judge`)
STICK_SLIP_FALL = 5.0


def close_rival(winner, rival, threshold: float) -> bool:
    """True when ``rival``'s dBIC, plain or whitened, lies less than ``threshold`` above ``winner``'s (or below
    it): the round hardly told the two apart (the swap check's rivals, and the rival caution's).

    Parameters
    ----------
    winner, rival : CandidateResult
        Two results of one round.
    threshold : float
        The BIC threshold (``Diagnosis.min_delta_bic``).

    Returns
    -------
    bool
    """
    return (rival.delta_bic - winner.delta_bic < threshold
            or rival.delta_bic_corrected - winner.delta_bic_corrected < threshold)


def judge(m, name, cal, current, scales, train, test, exp, wall_s, *, min_delta_bic: float = 10.0,
          min_holdout_gain: float = 2.0, min_holdout_z: float = 2.0, hunting: bool = False,
          slow_change: bool = False, stick_slip: bool = False) -> CandidateResult:
    """Judge a refitted candidate against the current model: BIC, BIC with the coloured noise modelled, and the
    prediction of the held-out part (the rules of :class:`~kilnctl.measure.diagnose.Diagnosis`).

    Parameters
    ----------
    m : Measurement
        The record.
    name : str
        The candidate (a catalogue effect, or a change outside the catalogue).
    cal, current : Calibration
        The candidate's refit and the current model's, on the fitting part.
    scales : dict of str to float
        Residual scale per channel.
    train, test : ndarray of bool
        The fitting and held-out samples of the record.
    exp : Experiment
        The start-up.
    wall_s : float
        Time the refit took [s].
    min_delta_bic, min_holdout_gain, min_holdout_z : float
        The thresholds (``min_delta_bic``, ``min_holdout_gain`` and
        ``holdout_z`` of :class:`~kilnctl.measure.diagnose.Diagnosis`).
    hunting : bool
        The record's current hunts and the current model's cycle runs in step with it.
    slow_change : bool
        The candidate is a change outside the catalogue (a drift or a step of
        the current): its held-out gain is void only when BIC with the coloured
        noise modelled rises by more than ``min_delta_bic``, not at any rise
        (the whitening filter, fitted to the current model's residual, takes
        part of a slow change for coloured noise).
    stick_slip : bool
        The current model has self-sustained stick-slip cycles (the torque
        friction law, or the paper's law where mu_s exceeds mu_c R/L): where it
        fits within noise, a refit that predicts the held-out part worse is
        supported only when BIC with the coloured noise modelled falls by more
        than :data:`STICK_SLIP_FALL` times ``min_delta_bic``; and a refit that
        lowers it by that much is not refused for predicting the held-out
        part significantly worse.

    Returns
    -------
    CandidateResult
    """
    dbic = cal.bic_ - current.bic_
    active = m.t >= exp.t0 - 1e-9
    te = test[active]

    def sse(run):
        return sum(float(np.sum(((m.channels[c][active][te] - run.outputs[c][te]) / scales[c]) ** 2))
                   for c in CHANNELS)

    gain = 100.0 * (1.0 - sse(cal.run_) / max(sse(current.run_), 1e-300))
    gain_z = holdout_z(m, cal, current, exp, te, scales)
    hfit = {c: fit_percent(m.channels[c][active][te], cal.run_.outputs[c][te]) for c in CHANNELS}
    # how much of the candidate's change to the model output falls in the held-out part
    change = {c: ((cal.run_.outputs[c] - current.run_.outputs[c]) / scales[c]) ** 2 for c in CHANNELS}
    total = sum(float(v.sum()) for v in change.values())
    seen = sum(float(v[te].sum()) for v in change.values()) / total if total > 0 else 0.0
    dbic_corr = whitened_delta_bic(m, cal, current, exp, train)
    # the evidence: BIC on the fitting part, and the prediction of the samples the refit did not see.  An
    # effect whose trace lies mostly in the fitting part (events: a torsional ring after each breakaway)
    # gains little on the held-out part; it is supported when the BIC with the coloured noise modelled
    # falls too (a slow change that only follows coloured noise does not) and the held-out part is not
    # predicted significantly worse (an effect that only lines up the fitting part's events is)
    ok_bic = dbic < -min_delta_bic
    ok_gain = gain > min_holdout_gain
    # ... where the current model already fits closely (within_noise: its residual mostly noise), a
    # small held-out gain (under three times the threshold) that neither BIC with the coloured noise modelled
    # nor its own spread bears out is the record's slowly correlated noise: on the independent plant's records
    # a kiln unbalance of a sixth of the usual torque (a 100 Hz record, +2.5 %, 1.9 standard errors, whitened
    # dBIC +11) and a second motor or an unbalance after a true compliance (+2.9-4.1 %, 1.0-1.1 standard
    # errors, +11-12) were added so.  A weak true unbalance (+8.5 %, 1.5 standard errors, whitened -0.4) still
    # counts.  Where the current model still misses much, the whitening filter takes the misfit for noise and
    # the whitened BIC is no test: the torque law on the plant's torque law + compliance record (base fit 46 %)
    # gained +5.6 % at 1.8 standard errors with whitened dBIC +1292, and is needed (the whole set's run at
    # cbfc214 without this condition ended 26 points below the true structure there)
    close = within_noise(current.fit_percent_, m.channels["speed_rpm"][active] - current.run_.outputs["speed_rpm"])
    noise_like = (close and ok_gain and gain < 3.0 * min_holdout_gain and dbic_corr >= 0.0
                  and gain_z <= min_holdout_z)
    # ... and, where the current model fits within noise, any held-out gain that BIC with the coloured noise
    # modelled contradicts (rising at all): the held-out blocks lie between the fitting blocks, and noise
    # correlated over seconds links them, so a slow change that follows the fitting blocks' noise also
    # "predicts" their neighbours.  Red team 12's R16 (no effect, AR(1) noise of 3 s on a 60 s record) took a
    # kiln unbalance so: held-out +14.0 % at 2.0 standard errors, whitened dBIC +21.8.  Among the selections of
    # the whole set's runs (diagnose_all_s30.json, diagnose_all_s37.json) and red teams 6-15, each one so
    # accepted was wrong: with the whitened dBIC above the threshold a second motor on an armature reaction and
    # a Coulomb friction on a coupled second motor; between 0 and the threshold (when the veto began there) a
    # drag on an effect-free record (+8.4), an unbalance on another (+5.2, held-out +21 % at 3.0 standard
    # errors), an unbalance for a load step (red team 15's X1: +3.4, held-out +33.5 % at 2.8) and a drag for a
    # current filter (+0.4).  The true effects selected where the model fitted within noise had it at -0.4
    # (a weak unbalance) or below
    # (a change outside the catalogue, a drift or a step, keeps the threshold: the whitening filter takes part of
    # it for coloured noise, and it ends as "unexplained", not as a selected effect; a drift of 0.25 A/s over
    # 140 s had whitened +4.4, held-out +15 %)
    contradicted = close and ok_gain and dbic_corr > (min_delta_bic if slow_change else 0.0) and not hunting
    ok_gain = ok_gain and not noise_like and not contradicted
    # not significantly worse on the held-out part (in standard errors that allow for its autocorrelation):
    # a stick-slip structure fitted on the fitting blocks can predict the held-out blocks' breakaways a
    # sample off, which doubles their squared error without being evidence against it (the torque friction
    # law on a torque law + compliance record: -112 %, -1.6 standard errors, and needed).  Where the current
    # model has stick-slip cycles, a refit that lowers BIC with the coloured noise modelled by more than
    # STICK_SLIP_FALL times the threshold (the bar the cycles' rule below sets for a held-out part predicted
    # worse) is not refused for it, however many standard errors: red team 19's backlash (a kiln whose paper law
    # cycles; 10 mm of play, the impact 250 A above the model's current) lowered it by 4499 and was refused at
    # -12.8 %, -2.5 standard errors, the cycles of the held-out blocks a sample off.  In the whole set's run
    # (diagnose_all_s40.json) no candidate refused so had a whitened dBIC below -50 but one, which BIC refused
    ok_robust = dbic_corr < -min_delta_bic and (gain_z > -min_holdout_z
                                                or (stick_slip and dbic_corr < -STICK_SLIP_FALL * min_delta_bic))
    # ... but where the current model has stick-slip cycles and fits within noise, the cycles' phase over the
    # record moves with every parameter, as a hunting loop's does (below), and a refit with any added parameter
    # can tune it.  Refits that did only that (the effect left at its null value, the base moved to another
    # valley) lowered the whitened BIC by up to 29 on the benchmark's torque-law records (23.4 for four
    # candidates at once on pair:torque_friction_law+speed_sensor_lag/s1, 29.0 on plant:torque_law/s1); on red
    # team 15's C3 (no effect, 100 Hz) a motor friction of 11 N m so was selected at whitened -29.3 with the
    # held-out part 6.6 % worse.  Where such a refit predicts the held-out part worse, BIC with the coloured
    # noise modelled must fall by more than STICK_SLIP_FALL times the threshold: every true effect accepted so
    # (held-out worse, stick-slip in the model) in the whole-set runs and red teams 8-15 had it at -128 or
    # below (a kiln unbalance -16.7 %, -128.4; a current limit -23.5 %, -3566)
    cycles_only = (stick_slip and close and gain < 0.0 and not hunting and ok_robust
                   and not dbic_corr < -STICK_SLIP_FALL * min_delta_bic)
    ok_robust = ok_robust and not cycles_only
    # ... except when the record hunts and the current model's cycle runs at its frequency: the cycle's
    # phase over the record moves with every parameter (on a 30 ms lag record a motor Coulomb friction of
    # 1 N m, a fifth of an ampere, moved the cost by a third), so a refit with any added parameter tunes it
    # and lowers BIC (-20 there) without predicting the held-out part better (+0.2 %, 0.6 standard errors)
    if hunting:
        ok_robust = dbic_corr < -min_delta_bic and gain_z > min_holdout_z
    why = f"held-out gain {gain:+.1f} % ({gain_z:+.1f} standard errors)"
    if ok_bic and ok_gain:
        reason = "BIC and held-out fit both improve"
    elif ok_bic and hunting:
        reason = (f"supported: {why}, significant, and BIC with the coloured noise modelled falls by "
                  f"{-dbic_corr:.1f}" if ok_robust else
                  f"BIC improves but the record's current hunts and the model's cycle is in step with it, "
                  f"where any added parameter can tune the cycle's phase: the held-out part must be predicted "
                  f"better by more than {min_holdout_gain:g} %, or by more than {min_holdout_z:g} standard "
                  f"errors with BIC falling also once the coloured noise is modelled, and is not ({why}; BIC "
                  f"with the coloured noise modelled {dbic_corr:+.1f})")
    elif ok_bic and contradicted:
        reason = (f"BIC improves and the held-out part is predicted better ({why}), but BIC with the coloured "
                  f"noise modelled rises ({dbic_corr:+.1f}) where the model already fits within its noise: the "
                  f"held-out blocks share the fitting blocks' slowly correlated noise, which the change follows")
    elif ok_bic and noise_like:
        reason = (f"BIC improves and the held-out part is predicted slightly better ({why}), but neither bears "
                  f"it out: BIC with the coloured noise modelled rises ({dbic_corr:+.1f}) and the held-out gain is "
                  f"within {min_holdout_z:g} standard errors of none: likely the record's slowly correlated noise")
    elif ok_bic and cycles_only:
        reason = (f"BIC improves, and BIC with the coloured noise modelled falls by {-dbic_corr:.1f}, but the "
                  f"held-out part is predicted worse ({why}) and the model's stick-slip cycles shift with any added "
                  f"parameter: with the held-out part worse the whitened BIC must fall by more than "
                  f"{STICK_SLIP_FALL * min_delta_bic:g}")
    elif ok_bic and ok_robust:
        worse = (f"the held-out part is predicted worse by {-gain:.1f} %, within {min_holdout_z:g} standard errors "
                 "of no change" if gain < 0 else "the held-out part is predicted no worse")
        reason = (f"supported: {why}, but BIC with the coloured noise modelled falls by {-dbic_corr:.1f} "
                  f"(> {min_delta_bic:g}) and {worse}")
    elif not ok_bic:
        reason = f"BIC does not improve enough (dBIC {dbic:+.1f} >= {-min_delta_bic:g})"
    else:
        reason = (f"BIC improves but not out of sample ({why} <= {min_holdout_gain:g} %; BIC with the "
                  f"coloured noise modelled {dbic_corr:+.1f}): likely fitting noise")
    ok_gain = ok_gain or ok_robust
    supported = ok_bic and ok_gain
    eff = CATALOGUE.get(name)
    odd = eff.contradicts(cal.values_, cal.params_) if supported and eff and eff.contradicts else None
    if odd:  # the fit improves, but not by the effect's own signature (see Effect.contradicts)
        supported = False
        why_fit = reason[len("supported: "):] if reason.startswith("supported: ") else reason
        reason = f"not the effect's signature: {odd} (its refit did improve the fit: {why_fit})"
    pars = {k: {"value": cal.values_[k], "stderr": cal.stderr_[k], "unit": _unit(k)} for k in cal.names_}
    return CandidateResult(name, float(dbic), float(gain), dict(cal.fit_percent_), hfit, pars,
                           list(cal.on_bound_), list(cal.not_identifiable_), supported, reason,
                           wall_s, cal, float(seen), float(dbic_corr), float(gain_z), bool(odd))
