"""The shape of a recorded speed reference: the paper's straight ramp, a jerk-limited S-curve, or knots.

Drive converters round the corners of their ramp function generator (a
"rounding time" or jerk limit): the reference's acceleration rises over a
time T_j, holds, and falls back to zero over T_j as the reference reaches
its final value.  A model driven by a straight ramp fitted to the middle of
such a reference starts T_j/2 late and demands its whole acceleration at
once; the current then misses a step of the acceleration torque at each
corner, which no effect of the catalogue describes.  When the record logs
its speed reference, :func:`fit_scurve` fits the S-curve of
:func:`kilnctl.model.ramps.scurve_reference` to it, and the measurement
tools drive the model with it (component ``ramp_scurve``) when it fits the
logged reference much better than the straight ramp.

A start-up is not always one ramp and a hold: a converter may ramp at two
rates, hold at an intermediate speed, or take the speed down again before
the record ends.  :func:`fit_knots` fits a piecewise-linear reference
through a few knots to such a logged reference, and the model follows it
(component ``ramp_knots<K>``, :func:`kilnctl.model.ramps.knots_reference`)
when neither the straight ramp nor the S-curve comes near it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ScurveFit", "fit_scurve", "scurve_values", "KnotsFit", "fit_knots", "knots_values", "SCURVE_GAIN",
           "MIN_CORNER", "KNOTS_FROM", "KNOT_TOL"]

#: the S-curve is used when its RMS misfit of the logged reference is below this fraction of the straight
#: ramp's [-] ...
SCURVE_GAIN = 0.3
#: ... and the straight ramp's misfit is above this fraction of the final reference [-] (a logged reference
#: is digital, or nearly: a straight ramp fits it to its resolution, which an S-curve cannot beat threefold)
MIN_CORNER = 1e-4
#: a logged reference is followed through knots when the ramp and hold (or the S-curve) misses it by more than
#: this fraction of its top value, RMS over the record from the start-up on [-]: a second ramp or a ramp down
#: misses by tens of per cent, a ramp of the wrong rate for a few samples by far less than one
KNOTS_FROM = 0.01
#: largest distance of the logged reference from the polyline through the knots, as a fraction of its top
#: value [-] (the knots are then refined by least squares)
KNOT_TOL = 0.005


@dataclass(frozen=True)
class ScurveFit:
    """A jerk-limited S-curve fitted to a logged speed reference.

    Attributes
    ----------
    t0 : float
        Record time at which the reference begins to rise [s].
    a : float
        Acceleration limit of the reference [rpm/s] (the ramp rate of its straight middle).
    j : float
        Jerk limit [rpm/s^2]; a/j is the rounding time T_j [s].
    rms : float
        RMS misfit of the logged reference by the S-curve [rpm].
    rms_straight : float
        RMS misfit by the straight ramp it was compared with [rpm].
    """

    t0: float
    a: float
    j: float
    rms: float
    rms_straight: float

    @property
    def rounding_s(self) -> float:
        """Rounding time T_j = a/j [s]: how long the reference's acceleration takes to rise and to fall."""
        return self.a / self.j


def scurve_values(t, t0: float, a: float, j: float, top: float) -> np.ndarray:
    """The S-curve reference at record times ``t`` [rpm]: 0 before ``t0``, ``top`` after its end.

    Parameters
    ----------
    t : array_like
        Record times [s].
    t0 : float
        Start of the rise [s].
    a, j : float
        Acceleration [rpm/s] and jerk [rpm/s^2] limits, > 0.
    top : float
        Final reference [rpm].

    Returns
    -------
    ndarray
    """
    import casadi as ca

    from ..model.ramps import scurve_reference

    tau = np.maximum(np.asarray(t, float) - t0, 0.0)
    e_v, _, _ = scurve_reference(ca.DM(tau), a, j, top)
    return np.asarray(e_v, float).ravel()


def fit_scurve(t, ref, top: float, rate: float, start: float) -> ScurveFit | None:
    """Fit an S-curve to a logged rising speed reference; None when it does not fit much better.

    The S-curve (start, acceleration and jerk limits; final value ``top``)
    is fitted by least squares to the samples from well before the rise to
    well after the end of the straight ramp (``start``, ``rate``) that the
    tools use otherwise.  It is returned when its RMS misfit is below
    :data:`SCURVE_GAIN` times the straight ramp's, that misfit is above
    :data:`MIN_CORNER` of ``top``, and the rounding time spans at least two
    sample steps.

    Parameters
    ----------
    t, ref : array_like
        Record times [s] and the logged speed reference [rpm].
    top : float
        Final reference [rpm], > 0.
    rate, start : float
        The straight ramp fitted to the middle of the rise: rate [rpm/s] and
        start [s].

    Returns
    -------
    ScurveFit or None
    """
    from scipy.optimize import least_squares

    t = np.asarray(t, float)
    ref = np.asarray(ref, float)
    if not (top > 0 and rate > 0 and math.isfinite(rate) and math.isfinite(start)):
        return None
    span = top / rate
    win = (t >= start - 0.6 * span) & (t <= start + 1.6 * span)
    tw, rw = t[win], ref[win]
    if tw.size < 10:
        return None
    straight = np.clip(rate * (tw - start), 0.0, top)
    rms_straight = float(np.sqrt(np.mean((rw - straight) ** 2)))
    if rms_straight <= MIN_CORNER * top:
        return None
    # the straight ramp fitted to the middle crosses zero half a rounding time after the S-curve starts
    first = tw[np.argmax(rw > 0.005 * top)] if np.any(rw > 0.005 * top) else start
    t_j = float(np.clip(2.0 * (start - first), 0.05 * span, 0.5 * span))
    x0 = np.array([start - 0.5 * t_j, math.log(rate), math.log(rate / t_j)])
    lo = np.array([start - span, math.log(rate / 3.0), math.log(rate / span)])
    hi = np.array([start + 0.5 * span, math.log(3.0 * rate), math.log(rate / max(np.median(np.diff(tw)), 1e-6))])
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)

    def resid(x):
        return scurve_values(tw, x[0], math.exp(x[1]), math.exp(x[2]), top) - rw

    try:
        sol = least_squares(resid, x0, bounds=(lo, hi), x_scale=np.array([0.1 * span, 0.1, 0.1]))
    except (ValueError, ArithmeticError):
        return None
    t0, a, j = float(sol.x[0]), math.exp(sol.x[1]), math.exp(sol.x[2])
    rms = float(np.sqrt(np.mean(sol.fun ** 2)))
    dt = float(np.median(np.diff(tw)))
    if not (np.isfinite(rms) and rms < SCURVE_GAIN * rms_straight and a / j >= 2.0 * dt):
        return None
    return ScurveFit(t0, a, j, rms, rms_straight)


@dataclass(frozen=True)
class KnotsFit:
    """A piecewise-linear reference through knots, fitted to a logged speed reference.

    Attributes
    ----------
    t0 : float
        Record time at which the reference begins to rise from rest [s].
    times : tuple of float
        Knot times t_1 < ... < t_K, from ``t0`` [s].
    values : tuple of float
        Reference at the knots [rpm]; held at the last after it.
    rms : float
        RMS misfit of the logged reference by the knots, from ``t0`` on [rpm].
    rms_before : float
        RMS misfit of the straight ramp or S-curve it replaces, over the same samples [rpm].
    """

    t0: float
    times: tuple
    values: tuple
    rms: float
    rms_before: float

    @property
    def top(self) -> float:
        """Highest knot value [rpm]."""
        return max(self.values)

    def describe(self) -> str:
        """The knots in words: ``0 -> 750 rpm at 50 rpm/s, hold 20.0 s, 750 -> 500 rpm at -50 rpm/s``."""
        parts, t_prev, w_prev = [], 0.0, 0.0
        for t, w in zip(self.times, self.values):
            rate = (w - w_prev) / (t - t_prev)
            if abs(w - w_prev) <= 0.005 * max(self.top, 1e-9):
                parts.append(f"hold {t - t_prev:.1f} s")
            else:
                parts.append(f"{w_prev:.4g} -> {w:.4g} rpm at {rate:+.4g} rpm/s")
            t_prev, w_prev = t, w
        return ", ".join(parts)


def knots_values(t, t0: float, times, values) -> np.ndarray:
    """The reference through knots at record times ``t`` [rpm]: 0 before ``t0``, the last value after the last knot.

    Parameters
    ----------
    t : array_like
        Record times [s].
    t0 : float
        Start of the rise [s].
    times, values : sequence of float
        Knot times from ``t0`` [s] (increasing) and the reference there [rpm].

    Returns
    -------
    ndarray
    """
    tau = np.asarray(t, float) - t0
    return np.interp(tau, np.concatenate([[0.0], times]), np.concatenate([[0.0], values]), left=0.0)


def _douglas_peucker(x, y, tol: float) -> list[int]:
    """Indices of the vertices of a polyline that stays within ``tol`` (vertically) of the points (x, y)."""
    keep = [0, x.size - 1]
    stack = [(0, x.size - 1)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            continue
        line = y[a] + (y[b] - y[a]) * (x[a + 1:b] - x[a]) / (x[b] - x[a])
        k = int(np.argmax(np.abs(y[a + 1:b] - line)))
        if abs(y[a + 1 + k] - line[k]) > tol:
            keep.append(a + 1 + k)
            stack += [(a, a + 1 + k), (a + 1 + k, b)]
    return sorted(set(keep))


def fit_knots(t, ref, start: float, before) -> KnotsFit | None:
    """Fit a reference through a few knots to a logged speed reference; None when it is not needed or fails.

    Used when the straight ramp and hold (or the S-curve) the tools take
    otherwise, ``before``, misses the logged reference by more than
    :data:`KNOTS_FROM` of its top value (RMS from the start-up on).  Knots
    are placed where the logged reference bends (a polyline within
    :data:`KNOT_TOL` of it, at most :data:`~kilnctl.model.ramps.MAX_KNOTS`
    knots), then the start time and every knot are refined by least squares.
    The fit is returned when it misses by less than :data:`SCURVE_GAIN` times
    ``before``.

    Parameters
    ----------
    t, ref : array_like
        Record times [s] and the logged speed reference [rpm].
    start : float
        Start of the rise the tools found [s] (a first guess).
    before : array_like
        The reference the tools would use otherwise, at ``t`` [rpm].

    Returns
    -------
    KnotsFit or None
    """
    from scipy.optimize import least_squares

    from ..model.ramps import MAX_KNOTS

    t = np.asarray(t, float)
    ref = np.asarray(ref, float)
    before = np.asarray(before, float)
    top = float(np.max(ref))
    if not (top > 0 and np.all(np.isfinite(ref))) or abs(ref[0]) > KNOT_TOL * top:
        return None  # a record that starts moving: the model starts at rest anyway
    rising = np.nonzero(ref > KNOT_TOL * top)[0]
    if rising.size < 3:
        return None
    first = max(int(rising[0]) - 1, 0)
    sel = t >= t[first] - 1e-9
    rms_before = float(np.sqrt(np.mean((ref[sel] - before[sel]) ** 2)))
    if rms_before <= KNOTS_FROM * top:
        return None
    x, y = t[first:], ref[first:]
    tol = KNOT_TOL * top
    for _ in range(8):
        idx = _douglas_peucker(x, y, tol)
        if len(idx) - 1 <= MAX_KNOTS:
            break
        tol *= 2.0
    else:
        return None
    t0 = float(x[idx[0]])
    times = x[idx[1:]] - t0
    values = y[idx[1:]]
    if values.size > 1 and abs(values[-1] - values[-2]) <= tol:
        times, values = times[:-1], values[:-1]  # the record ends on a hold: held after the knot where it began
    k = times.size
    if k < 1:
        return None
    span = float(t[-1] - t[first]) or 1.0

    def unpack(p):
        gaps = np.exp(p[1:k + 1])
        return p[0], np.cumsum(gaps), p[k + 1:]

    def resid(p):
        s0, tk, wk = unpack(p)
        return knots_values(x, s0, tk, wk) - y

    gaps0 = np.diff(np.concatenate([[0.0], times]))
    p0 = np.concatenate([[t0], np.log(np.maximum(gaps0, 1e-3)), values])
    try:
        sol = least_squares(resid, p0, x_scale=np.concatenate([[0.01 * span], np.full(k, 0.1), np.full(k, 0.01 * top)]))
    except (ValueError, ArithmeticError):
        return None
    s0, tk, wk = unpack(sol.x)
    fitted = knots_values(t, s0, tk, wk)
    rms = float(np.sqrt(np.mean((ref[sel] - fitted[sel]) ** 2)))
    if not (np.isfinite(rms) and rms < SCURVE_GAIN * rms_before and np.all(np.isfinite(sol.x))):
        return None
    return KnotsFit(float(s0), tuple(float(v) for v in tk), tuple(float(v) for v in wk), rms, rms_before)
