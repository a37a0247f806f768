"""The shape of a recorded speed reference: the paper's straight ramp, or a jerk-limited S-curve.

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ScurveFit", "fit_scurve", "scurve_values", "SCURVE_GAIN", "MIN_CORNER"]

#: the S-curve is used when its RMS misfit of the logged reference is below this fraction of the straight
#: ramp's [-] ...
SCURVE_GAIN = 0.3
#: ... and the straight ramp's misfit is above this fraction of the final reference [-] (a logged reference
#: is digital, or nearly: a straight ramp fits it to its resolution, which an S-curve cannot beat threefold)
MIN_CORNER = 1e-4


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
