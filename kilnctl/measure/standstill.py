"""The record at standstill before the start-up: sensor offsets, a drive holding the kiln, a kiln already turning.

Before the ramp the model stands still; the samples a logger keeps before it show what the model cannot
have: a sensor's offset, the current with which a drive switched on before the ramp holds the kiln
(:attr:`~kilnctl.measure.io.Experiment.held`), or a kiln that turns already (a barring drive, a late
trigger).  Kept apart from the residual's signature so that reading a record (:mod:`~kilnctl.measure.io`)
can use it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from .stats import robust_sigma, variance_inflation

if TYPE_CHECKING:
    from .io import Measurement

__all__ = ["standstill_offsets", "rest_level", "window_mean_spread", "REST_GUARD_S", "REST_SPEED", "MIN_WINDOWS"]

#: the samples at rest end this long before the start-up's t0 [s], and their measured speed is below this
#: fraction of the set speed [-] (see rest_level, standstill_offsets)
REST_GUARD_S, REST_SPEED = 0.05, 0.01
#: fewest spans of a residual whose means give the standard error of a mean (:func:`window_mean_spread`)
MIN_WINDOWS = 8


def standstill_offsets(m: Measurement, exp, *, min_samples: int = 10, residuals: dict | None = None,
                       held: dict | None = None) -> list[dict]:
    """Offsets of the current and speed signals while the drive stands still before the start-up.

    Before the ramp the model's current and speed are zero (its current is the one that holds the kiln where the
    record shows the drive holding it, ``held``); a record whose samples at rest read otherwise has a sensor
    offset (or a current at rest that no catalogued effect makes, e.g. a holding torque).  An effect that adds a
    constant torque once the kiln turns (motor-side Coulomb friction, a drag) can stand in for a current offset
    over the rest of the record, so the user is told.  Counted: the samples before
    ``t0 - 0.05 s`` whose measured speed is below 1 % of the final reference; an offset is reported when its
    median is more than 5 standard errors (allowing for the noise's autocorrelation, see
    :func:`variance_inflation`) and more than 0.5 % of the channel's peak from zero.  A second of samples at
    rest cannot show noise correlated over a good part of a second (red team 6: AR(1) noise of tau = 0.4 s read
    as offsets of +8 and +4.5 A, 2 standard errors of its 1 s mean, judged as 10): given the model's
    ``residuals``, the standard error is at least the spread of the means of as many consecutive residual samples
    elsewhere in the record (what noise, and what the model misses, make of such a mean).  When most samples
    before the start show a speed of 1 % of the set speed or more, the kiln was turning (an inching or barring
    drive, a late trigger): that is reported first, as an offset of the speed.

    Parameters
    ----------
    m : Measurement
        The record.
    exp : Experiment
        Its experiment (start ``t0`` [s], ``omega_ref`` [rpm]).
    min_samples : int, default 10
        Fewer samples at rest than this: nothing is said.
    residuals : dict, optional
        Channel -> the model's residual over the record (measured - model) [A or rpm], e.g. a
        :class:`~kilnctl.measure.compare.Comparison`'s; used when it holds at least :data:`MIN_WINDOWS` spans of
        the samples at rest.
    held : dict, optional
        Channel -> the model's level at rest where it starts held by its speed loop (:attr:`Experiment.held`:
        the current that holds a kiln unbalance, :func:`kilnctl.model.rest.holding_current`) [A]; the offset is
        the measured level less it.  Default zero.

    Returns
    -------
    list of dict
        Per offset channel: ``channel``, ``offset`` [A or rpm], ``n_samples``, ``text`` (and ``turning`` True for
        a kiln turning before the start).
    """
    before = m.t < exp.t0 - REST_GUARD_S
    out = []
    turning = _turning_before(m, exp, before, min_samples)
    if turning is not None:
        out.append(turning)
    for c, unit, what in (("current_A", "A", "current"), ("speed_rpm", "rpm", "speed")):
        level = rest_level(m, exp, c, residual=None if residuals is None else residuals.get(c),
                           min_samples=min_samples)
        if level is None:
            return out
        med, sig, se, n = level["median"], level["sigma"], level["se"], level["n_samples"]
        peak = float(np.max(np.abs(m.channels[c])))
        own = float((held or {}).get(c, 0.0))
        if abs(med - own) > 5.0 * se and abs(med - own) > 0.005 * peak:
            has = (f"the model holds the kiln with {own:+.3g} {unit}" if own else "the model has zero")
            out.append({"channel": c, "offset": med - own, "n_samples": n,
                        "text": (f"the {what} reads {med:+.3g} {unit} at standstill before the start ({n} samples, "
                                 f"noise {sig:.2g} {unit}) where {has}: a sensor offset, or a {what} "
                                 "at rest that no catalogued effect makes")})
    return out


def rest_level(m: Measurement, exp, channel: str = "current_A", *, residual=None, min_samples: int = 10) -> dict | None:
    """A channel's level while the drive stands still before the start-up, with its standard error.

    The samples before ``t0 - 0.05 s`` whose measured speed is below 1 % of the final reference, those the
    reader kept (spikes and clipped samples left out).  The standard error allows for the noise's
    autocorrelation (:func:`variance_inflation`) and, given the model's ``residual`` over the record, is at
    least the spread of the means of as many consecutive residual samples (:func:`window_mean_spread`: noise
    correlated over longer than the samples at rest, which they cannot show).

    Parameters
    ----------
    m : Measurement
        The record.
    exp : Experiment
        Its experiment (start ``t0`` [s], ``omega_ref`` [rpm]).
    channel : {'current_A', 'speed_rpm'}
        The channel.
    residual : array_like, optional
        The model's residual of that channel over the record (measured - model) [A or rpm].
    min_samples : int, default 10
        Fewer samples at rest than this: None.

    Returns
    -------
    dict or None
        ``mean`` and ``median`` [A or rpm], ``sigma`` (robust standard deviation of the samples), ``se`` (standard
        error of their mean), ``n_samples``; None with too few samples at rest.
    """
    rest = (m.t < exp.t0 - REST_GUARD_S) & (np.abs(m.speed) < REST_SPEED * max(abs(exp.omega_ref), 1e-9)) & m.kept
    n = int(rest.sum())
    if n < min_samples:
        return None
    x = m.channels[channel][rest]
    med = float(np.median(x))
    sig = robust_sigma(x - med)
    se = sig * math.sqrt(variance_inflation(x - med) / n) if sig > 0 else 0.0
    if residual is not None:
        se = max(se, window_mean_spread(residual, n))
    return {"mean": float(np.mean(x)), "median": med, "sigma": sig, "se": se, "n_samples": n}


def _turning_before(m: Measurement, exp, before, min_samples: int) -> dict | None:
    """The kiln turning before the start-up, when most of the samples before it show a speed of 1 % of the set
    speed or more (an inching or barring drive, or a record that begins after the start): the model starts
    from rest there, so its first seconds cannot match, and a constant-torque effect may make up for it (red
    team 11: a barring drive at 2 % of the speed was taken for 376 N m of motor friction); None otherwise."""
    n = int(before.sum())
    if n < min_samples:
        return None
    w = m.speed[before]
    level = REST_SPEED * max(abs(exp.omega_ref), 1e-9)
    if np.mean(np.abs(w) >= level) < 0.5:
        return None
    med = float(np.median(w))
    share = 100 * abs(med) / max(abs(exp.omega_ref), 1e-9)
    return {"channel": "speed_rpm", "offset": med, "n_samples": n, "turning": True,
            "text": (f"the kiln turns before the start-up: the speed reads {med:+.3g} rpm ({share:.1f} % of the "
                     f"set speed) over the {n} samples before "
                     f"t = {exp.t0:.2f} s, where the model starts at rest (an inching or barring drive turning it, "
                     "or a record that begins after the start)")}


def window_mean_spread(e, n: int) -> float:
    """Spread of the means of ``n`` consecutive samples of a residual: the standard error of such a mean.

    The residual is cut into spans of ``n`` samples (the last, shorter one dropped) and the robust standard
    deviation (:func:`robust_sigma`) of their means is returned, so noise correlated over any time and what the
    model misses slowly both count, without a model of the correlation.

    Parameters
    ----------
    e : array_like
        Residual, evenly sampled [any unit]; non-finite samples are left out.
    n : int
        Samples per mean.

    Returns
    -------
    float
        [unit of ``e``]; 0 when ``e`` holds fewer than :data:`MIN_WINDOWS` spans.
    """
    e = np.asarray(e, float)
    e = e[np.isfinite(e)]
    k = e.size // max(int(n), 1)
    if k < MIN_WINDOWS:
        return 0.0
    means = e[: k * n].reshape(k, n).mean(axis=1)
    return float(robust_sigma(means - np.median(means)))
