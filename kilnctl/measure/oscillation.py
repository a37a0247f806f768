"""A sustained oscillation of the drive current (a speed loop hunting): its frequency and size.

A speed loop whose feedback lags (a filtered tachometer, a slow encoder
interface) or that runs into its current limit can settle into a limit cycle:
after the ramp the current swings at a few hertz by hundreds of amperes.  A
model that has the cause reproduces the cycle's frequency and amplitude, but
its phase only at the exact parameter values: over a 40 s record a limit
cycle of 8 Hz is 300 periods long, and a lag 1 ms off puts model and record
in antiphase before the end.  The simulation-error cost therefore has a
valley about a millisecond wide at the true value, and every grid point
beside it fits worse than a model without any cycle.  The frequency, by
contrast, changes smoothly and monotonically with the lag (29-31 ms:
8.37-8.13 Hz), so :func:`dominant_oscillation` measures it on record and
model alike, and the diagnosis matches it before the ordinary fit
(:meth:`kilnctl.measure.diagnose.Diagnosis._refit_at_frequency`, with :func:`matching_value`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .stats import median_step

__all__ = ["Oscillation", "dominant_oscillation", "matching_value", "MIN_HZ", "MIN_SHARE", "MIN_PERIODS"]

#: lowest frequency counted as a loop oscillation [Hz]: stick-slip cycles (periods of seconds) and the kiln's
#: revolution (about 0.1 Hz) lie below
MIN_HZ = 1.0
#: least share of the current's variance after the ramp in the oscillation's band [-]
MIN_SHARE = 0.5
#: least number of periods in the analysed part of the record [-]
MIN_PERIODS = 20.0
#: half-width of the band around the spectral peak [bins of the Hann-windowed periodogram]
_BAND = 3


@dataclass(frozen=True)
class Oscillation:
    """A sustained oscillation of a signal.

    Attributes
    ----------
    f_hz : float
        Its frequency [Hz] (the periodogram's peak, refined between bins).
    rms : float
        Its RMS [unit of the signal]: the part of the signal's variance in
        the peak's band.
    share : float
        That part of the variance [-].
    """

    f_hz: float
    rms: float
    share: float


def dominant_oscillation(t, y, t_from: float) -> Oscillation | None:
    """The oscillation that dominates a signal after ``t_from``, or None.

    The signal after ``t_from`` (interpolated onto an even grid at its
    median step when the samples are uneven) has its linear trend removed
    and goes through a Hann-windowed periodogram.  Its highest bin above
    the lowest is refined by a parabola through the log powers of it and
    its neighbours.  It is an oscillation when it lies at or above
    :data:`MIN_HZ`, the analysed part holds at least :data:`MIN_PERIODS`
    periods, and the band of +-3 bins around it holds at least
    :data:`MIN_SHARE` of the variance.

    Parameters
    ----------
    t : array_like
        Sample times [s].
    y : array_like
        The signal (e.g. the drive current [A]).
    t_from : float
        Where the analysed part begins [s] (after the ramp).

    Returns
    -------
    Oscillation or None
    """
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    sel = t >= t_from
    tt, yy = t[sel], y[sel]
    if tt.size < 64 or not np.all(np.isfinite(yy)):
        return None
    dt = median_step(tt)
    n = int(np.floor((tt[-1] - tt[0]) / dt + 1e-9)) + 1
    grid = tt[0] + dt * np.arange(n)
    z = np.interp(grid, tt, yy)
    z = z - np.polyval(np.polyfit(grid - grid[0], z, 1), grid - grid[0])
    var = float(np.mean(z ** 2))
    if not var > 0:
        return None
    power = np.abs(np.fft.rfft(z * np.hanning(n))) ** 2
    f = np.fft.rfftfreq(n, dt)
    if f.size < 2 * _BAND + 3:
        return None
    k = 1 + int(np.argmax(power[1:-1]))
    lo, hi = max(1, k - _BAND), min(f.size, k + _BAND + 1)
    share = float(power[lo:hi].sum() / power[1:].sum())
    a, b, c = np.log(np.maximum(power[k - 1:k + 2], 1e-300))
    curv = a - 2.0 * b + c
    delta = 0.5 * (a - c) / curv if curv < 0 else 0.0
    f_hz = float(f[k] + np.clip(delta, -0.5, 0.5) * (f[1] - f[0]))
    if f_hz < MIN_HZ or f_hz * (grid[-1] - grid[0]) < MIN_PERIODS or share < MIN_SHARE:
        return None
    return Oscillation(f_hz, float(np.sqrt(share * var)), share)


def matching_value(signal_at, values, target: Oscillation, t, t_from: float) -> float | None:
    """The parameter value at which a model's signal oscillates at ``target``'s frequency, or None.

    The signal is made at each of ``values``; where two neighbouring values
    both make it oscillate (:func:`dominant_oscillation`) on either side of
    the target frequency, the crossing is found by Brent's method.  Of
    several crossings the one whose oscillation's RMS is nearest the
    target's.

    Parameters
    ----------
    signal_at : callable
        ``signal_at(value) -> ndarray or None``: the model's signal at the
        sample times ``t`` with the parameter at ``value`` (None: the model
        cannot be run there).
    values : array_like
        Parameter values to bracket the crossing with [unit of the parameter].
    target : Oscillation
        The record's oscillation.
    t : array_like
        Sample times [s].
    t_from : float
        Where the analysed part begins [s].

    Returns
    -------
    float or None
    """
    from scipy.optimize import brentq

    def osc_at(v):
        y = signal_at(float(v))
        return None if y is None else dominant_oscillation(t, y, t_from)

    grid = np.unique(np.asarray(values, float))
    found = [osc_at(v) for v in grid]
    best = None
    for k in range(grid.size - 1):
        a, b = found[k], found[k + 1]
        if a is None or b is None or (a.f_hz - target.f_hz) * (b.f_hz - target.f_hz) > 0:
            continue

        def gap(v):
            o = osc_at(v)
            return (o.f_hz if o is not None else 0.0) - target.f_hz

        try:
            v = brentq(gap, grid[k], grid[k + 1], xtol=1e-6 * grid[k + 1], rtol=1e-6)
        except (ValueError, RuntimeError):
            continue
        o = osc_at(v)
        if o is not None and (best is None or abs(o.rms - target.rms) < best[1]):
            best = (float(v), abs(o.rms - target.rms))
    return None if best is None else best[0]
