"""Shaped speed-reference profiles for the start-up: piecewise-linear and S-curve.

The paper's ramp generator (component ``ramp``) raises the speed reference
at one constant rate.  The components here shape it instead; each is placed
right after ``ramp`` in the component list and overrides the reference
signals ``e_v`` [rpm] and ``ev_dot`` [rpm/s] that ``ramp`` defined (``ramp``
stays in the plant: the controller requires it by name, and its output
``speed_ref_rpm`` then reports the shaped reference).

The profile's numbers are *constant states* of the component (their rate is
zero): ``simulate(..., initial={"ramp_r1": 60.0})`` sets them for a hybrid
run, and the optimizer (:mod:`kilnctl.optimize`) makes them decision
variables through the initial state, so one declaration serves both.

Profiles
--------
``ramp_pwl<N>``
    Piecewise-linear in time with N segments of equal *speed* increment
    omega_ref/N: segment k raises the reference from (k-1)/N to k/N of
    omega_ref at rate ``ramp_rk`` [rpm/s].  N = 1 is the paper's constant
    ramp.  Exact corners (``fmax``).
``ramp_pwl<N>_smooth``
    The same with each corner rounded over ``ramp_corner`` [s] (softplus,
    see :func:`pwl_reference`): a smooth function of time and rates, for
    gradient-based optimization.
``ramp_knots<K>``
    Through K knots (t_k, w_k) from rest at t = 0, held at w_K after the
    last: a logged reference that is not one ramp and hold (two rates, a
    hold and a second ramp, a ramp down), :func:`knots_reference`.
``ramp_scurve``
    Jerk-limited S-curve: the reference acceleration rises at ``ramp_j``
    [rpm/s^2] to ``ramp_a`` [rpm/s], holds, and falls back to zero exactly
    when the reference reaches omega_ref.  Its value is continuously
    differentiable in time and in (a, j), so the same component serves the
    hybrid plant and the smooth optimization model.

Examples
--------
>>> import abc

import casadi as ca
>>> from kilnctl.model.ramps import pwl_reference
>>> t = ca.SX.sym("t")
>>> ev, evd, t_end = pwl_reference(t, [50.0], 500.0)
>>> float(ca.substitute(ev, t, 4.0)), float(t_end)
(200.0, 10.0)
"""

from __future__ import annotations

import abc

import casadi as ca

from ..errors import ModelError
from .base import REGISTRY, Component, register

__all__ = ["pwl_reference", "scurve_reference", "knots_reference", "knots_component", "pwl_component", "smooth_ramp", "softplus",
           "RATE_SCALE", "JERK_SCALE", "MAX_KNOTS", "CORNER_DEFAULT", "scurve_timing"]

#: nominal magnitude of a ramp rate [rpm/s] (state scaling)
RATE_SCALE = 100.0
#: nominal magnitude of a jerk [rpm/s^2] (state scaling)
JERK_SCALE = 100.0
#: default rounding of the corners of the smooth piecewise-linear reference [s]
CORNER_DEFAULT = 0.05


def softplus(x):
    """Numerically safe softplus log(1 + exp(x)) of a CasADi expression.

    Parameters
    ----------
    x : casadi.SX or float
        Argument [-].

    Returns
    -------
    casadi.SX
        log(1 + exp(x)), evaluated as max(x, 0) + log1p(exp(-|x|)), which is
        exact and does not overflow; its derivative is the logistic function.
    """
    return ca.fmax(x, 0) + ca.log1p(ca.exp(-ca.fabs(x)))


def smooth_ramp(x, width=None):
    """max(x, 0), exact or rounded over ``width``.

    Parameters
    ----------
    x : casadi.SX
        Argument, in the unit of ``width``.
    width : casadi.SX or float, optional
        Rounding width (same unit as ``x``); None gives the exact corner.

    Returns
    -------
    casadi.SX
        ``fmax(x, 0)`` or ``width * softplus(x / width)``; the rounded form
        lies above the exact one by at most ``width * ln 2`` (at x = 0).
    """
    if width is None:
        return ca.fmax(x, 0)
    return width * softplus(x / width)


def _step(x, width=None):
    """Derivative of :func:`smooth_ramp` with respect to x: a (smooth) unit step."""
    if width is None:
        return 0.5 * (1 + ca.sign(x))
    return 0.5 * (1 + ca.tanh(0.5 * x / width))


def pwl_reference(t, rates, omega_ref, corner=None):
    """Piecewise-linear speed reference with equal speed increments per segment.

    Segment k (k = 1..N) raises the reference from (k-1)/N*omega_ref to
    k/N*omega_ref at rate ``rates[k-1]``, so it lasts
    omega_ref/(N*r_k) seconds; after the last segment the reference holds
    omega_ref.  Written as a sum of ramp functions,
    e_v(t) = r_1*t + sum_k (s_{k+1} - s_k)*max(t - t_k, 0), with slopes
    s_k = r_k and s_{N+1} = 0 and knot times t_k.

    Parameters
    ----------
    t : casadi.SX
        Time [s], t >= 0.
    rates : sequence of casadi.SX or float
        Segment rates r_1..r_N [rpm/s], > 0.
    omega_ref : casadi.SX or float
        Final motor speed reference [rpm].
    corner : casadi.SX or float, optional
        Rounding of each corner [s] (softplus); None: exact corners.  The
        start at t = 0 is always exact; rounded corners shift the reference
        by at most r*corner*ln 2 [rpm] near a knot and leave it exact far
        from the knots (the final value is omega_ref).

    Returns
    -------
    e_v : casadi.SX
        Speed reference [rpm].
    ev_dot : casadi.SX
        Its time derivative [rpm/s].
    t_end : casadi.SX
        Time at which the (exact) reference reaches omega_ref [s].
    """
    n = len(rates)
    if n < 1:
        raise ModelError("a piecewise-linear ramp needs at least one segment")
    dv = omega_ref / n
    slopes = list(rates) + [0.0]
    e_v = rates[0] * t
    ev_dot = rates[0] + 0 * t
    t_k = 0
    for k in range(n):
        t_k = t_k + dv / rates[k]
        jump = slopes[k + 1] - slopes[k]
        e_v = e_v + jump * smooth_ramp(t - t_k, corner)
        ev_dot = ev_dot + jump * _step(t - t_k, corner)
    return e_v, ev_dot, t_k


def knots_reference(t, times, values):
    """Piecewise-linear speed reference through knots, from rest at t = 0.

    The reference rises from 0 at t = 0 to ``values[0]`` at ``times[0]``,
    then runs straight from knot to knot and holds ``values[-1]`` after the
    last.  Written as a sum of ramp functions,
    e_v(t) = s_1 t + sum_k (s_{k+1} - s_k) max(t - t_k, 0), with the
    segment slopes s_k = (w_k - w_{k-1})/(t_k - t_{k-1}) (t_0 = w_0 = 0)
    and s_{K+1} = 0.  Slopes may be negative (a ramp down) or zero (a hold).

    Parameters
    ----------
    t : casadi.SX or float
        Time since the start-up began [s], t >= 0.
    times : sequence of casadi.SX or float
        Knot times t_1 < ... < t_K [s], > 0.
    values : sequence of casadi.SX or float
        Reference at the knots w_1..w_K [rpm].

    Returns
    -------
    e_v : casadi.SX
        Speed reference [rpm].
    ev_dot : casadi.SX
        Its time derivative [rpm/s] (a step at each knot).
    """
    if len(times) < 1 or len(times) != len(values):
        raise ModelError("a reference through knots needs as many knot times as values, at least one")
    slopes = []
    t_prev, w_prev = 0, 0
    for t_k, w_k in zip(times, values):
        slopes.append((w_k - w_prev) / (t_k - t_prev))
        t_prev, w_prev = t_k, w_k
    slopes.append(0.0)
    e_v = slopes[0] * t
    ev_dot = slopes[0] + 0 * t
    for k, t_k in enumerate(times):
        jump = slopes[k + 1] - slopes[k]
        e_v = e_v + jump * ca.fmax(t - t_k, 0)
        ev_dot = ev_dot + jump * _step(t - t_k)
    return e_v, ev_dot


def scurve_timing(a, j, omega_ref):
    """Effective peak acceleration and phase times of the S-curve.

    Parameters
    ----------
    a : casadi.SX or float
        Acceleration limit of the reference [rpm/s], > 0.
    j : casadi.SX or float
        Jerk limit [rpm/s^2], > 0.
    omega_ref : casadi.SX or float
        Final reference [rpm].

    Returns
    -------
    a_eff : same type
        Peak acceleration reached [rpm/s]: ``a``, or sqrt(j*omega_ref) when the
        jerk is too low to reach ``a`` (triangular acceleration).
    t1 : same type
        End of the jerk-up phase, a_eff/j [s].
    t_end : same type
        Time the reference reaches omega_ref, omega_ref/a_eff + a_eff/j [s].
    """
    if isinstance(a, (int, float)) and isinstance(j, (int, float)):
        a_eff = min(a, (j * omega_ref) ** 0.5)
    else:
        a_eff = ca.fmin(a, ca.sqrt(j * omega_ref))
    t1 = a_eff / j
    return a_eff, t1, omega_ref / a_eff + t1


def scurve_reference(t, a, j, omega_ref):
    """Jerk-limited S-curve speed reference (trapezoidal acceleration).

    The reference acceleration rises at jerk j to a_eff, holds, and falls at
    jerk j to zero at t_end, when the reference reaches omega_ref exactly:
    e_v(t) = j/2*(t^2 - q(t - t1) - q(t - t_end + t1) + q(t - t_end)) with
    q(x) = max(x, 0)^2, which is continuously differentiable in t, a and j.

    Parameters
    ----------
    t : casadi.SX
        Time [s], t >= 0.
    a : casadi.SX or float
        Acceleration limit [rpm/s].
    j : casadi.SX or float
        Jerk limit [rpm/s^2].
    omega_ref : casadi.SX or float
        Final reference [rpm].

    Returns
    -------
    e_v : casadi.SX
        Speed reference [rpm].
    ev_dot : casadi.SX
        Its time derivative [rpm/s].
    t_end : casadi.SX
        Time the reference reaches omega_ref [s].
    """
    a_eff, t1, t_end = scurve_timing(a, j, omega_ref)
    t2 = t_end - t1

    def p(x):
        return ca.fmax(x, 0)

    e_v = 0.5 * j * (t * t - p(t - t1) ** 2 - p(t - t2) ** 2 + p(t - t_end) ** 2)
    ev_dot = j * (t - p(t - t1) - p(t - t2) + p(t - t_end))
    return e_v, ev_dot, t_end


class _ProfileRamp(Component, abc.ABC):
    """Common part of the profile components: override the reference, constant states."""

    requires = ("ramp",)
    #: (state name, unit, scale, doc) of the constant profile states
    profile_states: tuple = ()

    def declare(self, spec):
        for name, unit, scale, doc in self.profile_states:
            spec.add_state(name, unit, scale, doc + " (constant: its rate is zero)")

    @abc.abstractmethod
    def reference(self, e):
        """Return (e_v, ev_dot) [rpm, rpm/s] for the equations ``e``."""

    def signals(self, e, mode):
        e.sig["e_v"], e.sig["ev_dot"] = self.reference(e)

    def finish(self, e, mode):
        for name, *_ in self.profile_states:
            e.set_rate(name, ca.SX(0))


def _pwl_class(n: int, smooth: bool) -> type[Component]:
    states = tuple((f"ramp_r{k}", "rpm/s", RATE_SCALE, f"reference rate of segment {k} of {n}")
                   for k in range(1, n + 1))
    if smooth:
        states = states + (("ramp_corner", "s", CORNER_DEFAULT, "rounding of the reference's corners"),)
    name = f"ramp_pwl{n}" + ("_smooth" if smooth else "")

    class PwlRamp(_ProfileRamp):
        __doc__ = (f"Piecewise-linear speed reference, {n} segment(s) of omega_ref/{n} each "
                   f"({'corners rounded over ramp_corner [s]' if smooth else 'exact corners'}).\n\n"
                   "States ramp_r1..ramp_rN [rpm/s] are the segment rates (constant); see\n"
                   ":func:`kilnctl.model.ramps.pwl_reference`.")
        profile_states = states

        def initial_state(self, params):
            x0 = {f"ramp_r{k}": params.ramp_rate for k in range(1, n + 1)}
            if smooth:
                x0["ramp_corner"] = CORNER_DEFAULT
            return x0

        def reference(self, e):
            rates = [e.x[f"ramp_r{k}"] for k in range(1, n + 1)]
            corner = e.x["ramp_corner"] if smooth else None
            e_v, ev_dot, _ = pwl_reference(e.t, rates, e.p.omega_ref, corner)
            return e_v, ev_dot

    PwlRamp.name = name
    PwlRamp.summary = f"piecewise-linear speed reference, {n} segment(s)" + (", rounded corners" if smooth else "")
    PwlRamp.param_names = ("omega_ref",)
    PwlRamp.__name__ = PwlRamp.__qualname__ = f"PwlRamp{n}{'Smooth' if smooth else ''}"
    return PwlRamp


def pwl_component(n: int, smooth: bool = False) -> str:
    """Return the registry name of the N-segment piecewise-linear ramp, registering it once.

    Parameters
    ----------
    n : int
        Number of segments, >= 1.
    smooth : bool, default False
        Rounded corners (for optimization) instead of exact ones.

    Returns
    -------
    str
        ``ramp_pwl<n>`` or ``ramp_pwl<n>_smooth``.

    Raises
    ------
    ModelError
        ``n`` is not a positive integer.
    """
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ModelError(f"number of ramp segments n = {n!r} must be a positive integer")
    name = f"ramp_pwl{n}" + ("_smooth" if smooth else "")
    if name not in REGISTRY:
        register(_pwl_class(n, smooth))
    return name


def _knots_class(k: int) -> type[Component]:
    states = tuple((f"ramp_t{i}", "s", 10.0, f"time of knot {i} of {k} of the reference, from the start-up")
                   for i in range(1, k + 1)) + tuple(
        (f"ramp_w{i}", "rpm", RATE_SCALE, f"reference at knot {i} of {k}") for i in range(1, k + 1))

    class KnotsRamp(_ProfileRamp):
        __doc__ = (f"Speed reference through {k} knot(s) (t_i, w_i) from rest, held after the last.\n\n"
                   "States ramp_t1..ramp_tK [s] and ramp_w1..ramp_wK [rpm] are the knots (constant); see\n"
                   ":func:`kilnctl.model.ramps.knots_reference`.  Default: the paper's ramp (one knot at\n"
                   "omega_ref/ramp_rate, the others spaced 1 s after it on the same value).")
        profile_states = states

        def initial_state(self, params):
            t_top = params.omega_ref / params.ramp_rate
            x0 = {f"ramp_t{i}": t_top + (i - 1) for i in range(1, k + 1)}
            x0.update({f"ramp_w{i}": params.omega_ref for i in range(1, k + 1)})
            return x0

        def reference(self, e):
            return knots_reference(e.t, [e.x[f"ramp_t{i}"] for i in range(1, k + 1)],
                                   [e.x[f"ramp_w{i}"] for i in range(1, k + 1)])

    KnotsRamp.name = f"ramp_knots{k}"
    KnotsRamp.summary = f"speed reference through {k} knot(s) (a logged reference that is not one ramp)"
    KnotsRamp.param_names = ("omega_ref", "ramp_rate")
    KnotsRamp.__name__ = KnotsRamp.__qualname__ = f"KnotsRamp{k}"
    return KnotsRamp


def knots_component(k: int) -> str:
    """Return the registry name of the reference through ``k`` knots, registering it once.

    Parameters
    ----------
    k : int
        Number of knots, >= 1.

    Returns
    -------
    str
        ``ramp_knots<k>``.

    Raises
    ------
    ModelError
        ``k`` is not a positive integer.
    """
    if isinstance(k, bool) or not isinstance(k, int) or k < 1:
        raise ModelError(f"number of reference knots k = {k!r} must be a positive integer")
    name = f"ramp_knots{k}"
    if name not in REGISTRY:
        register(_knots_class(k))
    return name


@register
class ScurveRamp(_ProfileRamp):
    """Jerk-limited S-curve speed reference (see :func:`scurve_reference`).

    States ``ramp_a`` [rpm/s] (acceleration limit) and ``ramp_j`` [rpm/s^2]
    (jerk limit) are constant.  Default: a = ramp_rate, j = 2*ramp_rate per
    second (full acceleration after 0.5 s).
    """

    name = "ramp_scurve"
    summary = "jerk-limited S-curve speed reference (acceleration ramp_a, jerk ramp_j)"
    param_names = ("omega_ref",)
    profile_states = (("ramp_a", "rpm/s", RATE_SCALE, "acceleration limit of the reference"),
                      ("ramp_j", "rpm/s^2", JERK_SCALE, "jerk limit of the reference"))

    def initial_state(self, params):
        return {"ramp_a": params.ramp_rate, "ramp_j": 2.0 * params.ramp_rate}

    def reference(self, e):
        e_v, ev_dot, _ = scurve_reference(e.t, e.x["ramp_a"], e.x["ramp_j"], e.p.omega_ref)
        return e_v, ev_dot


for _n in (1, 2, 3, 4):
    pwl_component(_n)
    pwl_component(_n, smooth=True)
#: most knots of a logged reference the model follows (:func:`kilnctl.measure.reference.fit_knots`); all
#: registered here, so that a record's reference does not change the registry (and the plant cache) mid-run
MAX_KNOTS = 8
for _n in range(1, MAX_KNOTS + 1):
    knots_component(_n)
