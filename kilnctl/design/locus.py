"""Root loci over the loop gain and over a physical parameter; step responses.

Each function computes a data object; the object's ``.plot()`` draws it
(:mod:`kilnctl.design.plots`) and returns the figure.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import control as ct
import numpy as np

from ..errors import DesignError, ParameterError, close_matches_hint
from ..linear import CONDITIONS, closed_loop_ss, inertia, loop_tf
from ..params import SPECS, Parameters
from .analysis import analyse
from .gains import PIDGains
from .requirements import Requirements

__all__ = ["LocusBranches", "RootLocusData", "root_locus", "StepResponseData", "step_responses",
           "ParameterLocusData", "parameter_locus", "ACCRETION_RANGE"]

#: burden mass range of the paper's accretion study (Fig. 14) [kg]
ACCRETION_RANGE = (240e3, 974e3)


def _check_conditions(params: Parameters, conditions) -> tuple[str, ...]:
    conditions = tuple(conditions)
    for c in conditions:
        inertia(params, c)  # raises ModelError naming the valid conditions
    if not conditions:
        raise DesignError("conditions is empty: give 'stick', 'slip' or both")
    return conditions


# --- root locus over the loop gain -----------------------------------------------
@dataclass(frozen=True)
class LocusBranches:
    """Root locus of one load condition.

    Attributes
    ----------
    condition : str
        ``"stick"`` or ``"slip"``.
    J : float
        Inertia at the motor shaft [kg*m^2].
    loop : control.TransferFunction
        ``L(s) = K C(s) G(s)`` at the designed gains (``kappa = 1``).
    kappas : numpy.ndarray
        Loop-gain scalings [-], increasing; the gains are ``kappa`` times the design.
    loci : numpy.ndarray
        Closed-loop poles [rad/s], one row per ``kappa``, one column per branch.
    open_loop_poles, open_loop_zeros : numpy.ndarray
        Where the branches start (``kappa = 0``) and end [rad/s].
    chosen : numpy.ndarray
        Closed-loop poles at ``kappa = 1`` [rad/s].
    """

    condition: str
    J: float
    loop: ct.TransferFunction
    kappas: np.ndarray
    loci: np.ndarray
    open_loop_poles: np.ndarray
    open_loop_zeros: np.ndarray
    chosen: np.ndarray


@dataclass(frozen=True)
class RootLocusData:
    """Root loci of the speed loop over the gain scaling ``kappa``, per condition.

    Attributes
    ----------
    gains : PIDGains
        Gains at ``kappa = 1``.
    branches : dict of str to LocusBranches
        One locus per load condition.
    requirements : Requirements or None
        Resolved requirements, drawn as the design region.
    """

    gains: PIDGains
    branches: dict
    requirements: Requirements | None = None

    def gain_at(self, s0: complex, condition: str = "stick", *, tol: float = 1e-3) -> float:
        """Return the gain scaling ``kappa = -1/L(s0)`` at a point of the locus.

        Parameters
        ----------
        s0 : complex
            Point of the s-plane [rad/s].
        condition : {"stick", "slip"}
            Which locus.
        tol : float, default 1e-3
            Largest accepted ``|Im kappa| / |kappa|`` [-]: a larger imaginary
            part means ``s0`` is not on the locus.

        Returns
        -------
        float
            ``kappa`` [-]; the gains there are ``kappa`` times :attr:`gains`.

        Raises
        ------
        DesignError
            When ``s0`` is not on the locus (or is a pole of L).
        """
        if condition not in self.branches:
            raise DesignError(f"no locus for condition {condition!r}: have {', '.join(self.branches)}")
        val = complex(self.branches[condition].loop(complex(s0)))
        if val == 0 or not np.isfinite(val):
            raise DesignError(f"s0 = {s0} is a zero or pole of L(s): the gain there is 0 or infinite")
        kappa = -1.0 / val
        if abs(kappa.imag) > tol * abs(kappa) or kappa.real < 0:
            raise DesignError(f"s0 = {s0} is not on the {condition} root locus (-1/L(s0) = {kappa:.4g})")
        return float(kappa.real)

    def nearest(self, s0: complex) -> tuple[str, complex, float]:
        """Return the locus point nearest ``s0`` and its gain scaling.

        Parameters
        ----------
        s0 : complex
            Point of the s-plane [rad/s], e.g. where the user clicked.

        Returns
        -------
        tuple
            ``(condition, s, kappa)``: the condition, the locus point [rad/s]
            and ``kappa = Re(-1/L(s))`` [-] there.
        """
        best = None
        for cond, br in self.branches.items():
            d = np.abs(br.loci - complex(s0))
            i = np.unravel_index(np.argmin(d), d.shape)
            if best is None or d[i] < best[0]:
                best = (d[i], cond, complex(br.loci[i]))
        _, cond, s = best
        val = complex(self.branches[cond].loop(s))
        kappa = float((-1.0 / val).real) if val != 0 and np.isfinite(val) else math.inf
        return cond, s, kappa

    def plot(self, axes=None):
        """Draw the loci with the design region, open-loop poles/zeros and chosen poles.

        Parameters
        ----------
        axes : pair of matplotlib Axes, optional
            ``(full view, zoom on the dominant region)``; a new figure when omitted.

        Returns
        -------
        matplotlib.figure.Figure
            Clicking a locus in an interactive backend shows the gain there.
        """
        from .plots import plot_root_locus
        return plot_root_locus(self, axes)


def _default_kappas() -> np.ndarray:
    return np.unique(np.concatenate([[0.0], np.logspace(-4, 4, 800), [1.0]]))


def _loci(L, kappas: np.ndarray) -> np.ndarray:
    """Roots of den(s) + kappa num(s) for each kappa, columns following each branch."""
    num, den = np.asarray(L.num[0][0], dtype=float), np.asarray(L.den[0][0], dtype=float)
    num = np.concatenate([np.zeros(len(den) - len(num)), num])  # L is proper: deg num <= deg den
    polys = den[None, :] + np.asarray(kappas, dtype=float)[:, None] * num[None, :]
    return _match_columns(_batch_roots(polys))


def _batch_roots(polys: np.ndarray) -> np.ndarray:
    """Roots of many polynomials of one degree (rows, highest power first), by companion matrices."""
    n = polys.shape[1] - 1
    comp = np.zeros((polys.shape[0], n, n))
    comp[:, 0, :] = -polys[:, 1:] / polys[:, :1]
    comp[:, np.arange(1, n), np.arange(n - 1)] = 1.0
    return np.linalg.eigvals(comp).astype(complex)


def _locus_points(L, kappas: np.ndarray, refine: bool, passes: int = 8) -> tuple[np.ndarray, np.ndarray]:
    """Loci over kappas; with ``refine``, add gains where a branch jumps inside the plotted region."""
    loci = _loci(L, kappas)
    if not refine:
        return kappas, loci
    radius = max(1.0, float(np.max(np.abs(np.concatenate([L.poles(), L.zeros(), loci[0]])))))
    step = 0.01 * radius
    for _ in range(passes):
        near = np.abs(loci[:-1]) < 3 * radius  # only where the plot shows it
        jump = np.abs(np.diff(loci, axis=0))
        bad = np.nonzero(np.any((jump > step) & near, axis=1))[0]
        if bad.size == 0:
            break
        k = kappas
        new = np.where(k[bad] > 0, np.sqrt(k[bad] * k[bad + 1]), 0.5 * k[bad + 1])
        kappas = np.unique(np.concatenate([k, new]))
        loci = _loci(L, kappas)
    return kappas, loci


def root_locus(params: Parameters, gains: PIDGains, *, conditions=CONDITIONS, kappas=None,
               requirements: Requirements | None = None) -> RootLocusData:
    """Compute the root locus of the speed loop over the gain scaling ``kappa``.

    ``kappa`` multiplies all three gains, so the PID zeros stay where the design
    placed them and ``kappa = 1`` is the design; a point ``s0`` of the locus has
    ``kappa = -1/L(s0)``.  The closed-loop poles at each ``kappa`` are the
    roots of ``den(s) + kappa num(s)`` of ``L = num/den``, ordered so each
    column follows one branch.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        Gains at ``kappa = 1`` [V/rpm, V/(rpm*s), V*s/rpm].
    conditions : sequence of str, default ("stick", "slip")
        Load conditions to compute.
    kappas : array_like, optional
        Gain scalings [-], >= 0; by default 0 and 800 values from 1e-4 to 1e4,
        plus 1, refined where the poles jump (break-in and break-away points).
    requirements : Requirements, optional
        Drawn as the design region by :meth:`RootLocusData.plot`; resolved
        against ``params``.

    Returns
    -------
    RootLocusData
    """
    conditions = _check_conditions(params, conditions)
    refine = kappas is None
    if kappas is None:
        kappas = _default_kappas()
    kappas = np.asarray(kappas, dtype=float)
    if kappas.ndim != 1 or kappas.size == 0 or not np.all(np.isfinite(kappas)) or np.any(kappas < 0):
        raise DesignError("kappas must be a non-empty 1-D array of finite gain scalings >= 0")
    kappas = np.unique(kappas)
    branches = {}
    for cond in conditions:
        L = loop_tf(params, gains, cond)
        ks, loci = _locus_points(L, kappas, refine)
        chosen = np.asarray(ct.feedback(L, 1).poles(), dtype=complex)
        branches[cond] = LocusBranches(
            condition=cond, J=inertia(params, cond), loop=L, kappas=ks,
            loci=loci, open_loop_poles=np.asarray(L.poles(), dtype=complex),
            open_loop_zeros=np.asarray(L.zeros(), dtype=complex), chosen=chosen)
    req = requirements.resolve(params) if requirements is not None else None
    return RootLocusData(gains=gains, branches=branches, requirements=req)


# --- step responses ----------------------------------------------------------------
@dataclass(frozen=True)
class StepResponseData:
    """Closed-loop responses to a step of the speed reference, per condition.

    Attributes
    ----------
    time : numpy.ndarray
        Time [s].
    speed : dict of str to numpy.ndarray
        ``K*omega_m/e_v`` [-]: motor speed in rpm per rpm of reference step.
    current : dict of str to numpy.ndarray
        ``i_a/e_v`` [A/rpm]: armature current per rpm of reference step (it
        jumps by ``k_D/L_a`` at the step, the derivative through L_a).
    reports : dict of str to ConditionReport
        Step information of each condition (for the markers).
    gains : PIDGains
        The gains simulated.
    requirements : Requirements or None
        Resolved requirements, drawn as limits.
    """

    time: np.ndarray
    speed: dict
    current: dict
    reports: dict
    gains: PIDGains
    requirements: Requirements | None = None

    def plot(self, axes=None):
        """Draw speed and current responses with the requirement limits.

        Parameters
        ----------
        axes : pair of matplotlib Axes, optional
            ``(speed, current)``; a new figure when omitted.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .plots import plot_step_responses
        return plot_step_responses(self, axes)


def step_responses(params: Parameters, gains: PIDGains, *, conditions=CONDITIONS, t_final: float | None = None,
                   requirements: Requirements | None = None) -> StepResponseData:
    """Simulate the closed speed loop after a unit step of the reference ``e_v``.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    gains : PIDGains
        PID gains [V/rpm, V/(rpm*s), V*s/rpm].
    conditions : sequence of str, default ("stick", "slip")
        Load conditions.
    t_final : float, optional
        End time [s], > 0; by default 2.5 times the longest settling time (or
        8 time constants of the slowest pole when unstable).
    requirements : Requirements, optional
        Drawn as limits by :meth:`StepResponseData.plot`.

    Returns
    -------
    StepResponseData
    """
    conditions = _check_conditions(params, conditions)
    reports = {c: analyse(params, gains, c) for c in conditions}
    if t_final is None:
        ts = [r.settling_time for r in reports.values() if r.settling_time]
        slow = max(1e-3, min(abs(r.poles[0].real) for r in reports.values()))
        t_final = 2.5 * max(ts) if ts else 8.0 / slow
        if requirements is not None:
            t_final = max(t_final, 1.2 * requirements.settling_time_max)
    if not (math.isfinite(t_final) and t_final > 0):
        raise DesignError(f"t_final = {t_final!r} s must be a finite number > 0")
    t = np.linspace(0.0, t_final, 3000)
    speed, current = {}, {}
    for c in conditions:
        resp = ct.step_response(closed_loop_ss(params, gains, c), timepts=t, input_indices=[0], squeeze=False)
        y = np.asarray(resp.outputs)[:, 0, :]  # outputs (omega_m, i_a) after a step of e_v
        speed[c] = params.K_fb * y[0]
        current[c] = y[1]
    req = requirements.resolve(params) if requirements is not None else None
    return StepResponseData(time=t, speed=speed, current=current, reports=reports, gains=gains,
                            requirements=req)


# --- root locus over a physical parameter -----------------------------------------------
@dataclass(frozen=True)
class ParameterLocusData:
    """Closed-loop poles over a physical parameter at fixed gains.

    Attributes
    ----------
    parameter : str
        Name of the parameter varied.
    unit : str
        Its unit.
    values : numpy.ndarray
        Its values, increasing.
    nominal : float
        Its value in the parameter set designed for.
    poles : dict of str to numpy.ndarray
        Closed-loop poles [rad/s] per condition, one row per value, columns
        ordered so each follows one pole continuously.
    inertias : dict of str to numpy.ndarray
        Inertia at the motor shaft [kg*m^2] per condition and value.
    gains : PIDGains
        The fixed gains.
    requirements : Requirements or None
        Resolved requirements, drawn as limits.
    """

    parameter: str
    unit: str
    values: np.ndarray
    nominal: float
    poles: dict
    inertias: dict
    gains: PIDGains
    requirements: Requirements | None = None

    def dominant_wn(self, condition: str = "stick") -> np.ndarray:
        """Return the natural frequency of the dominant (slowest) pole at each value.

        Parameters
        ----------
        condition : {"stick", "slip"}
            Load condition.

        Returns
        -------
        numpy.ndarray
            ``|p|`` of the pole nearest the imaginary axis [rad/s], one per value.
        """
        P = self._poles(condition)
        return np.abs(P[np.arange(len(P)), np.argmax(P.real, axis=1)])

    def pair_zeta(self, condition: str = "stick") -> np.ndarray:
        """Return the damping ratio of the electromechanical pair at each value.

        Parameters
        ----------
        condition : {"stick", "slip"}
            Load condition.

        Returns
        -------
        numpy.ndarray
            Damping ratio [-] of the pole with the largest imaginary part, one per value.
        """
        P = self._poles(condition)
        upper = P[np.arange(len(P)), np.argmax(P.imag, axis=1)]
        return -upper.real / np.abs(upper)

    def _poles(self, condition: str) -> np.ndarray:
        if condition not in self.poles:
            raise DesignError(f"no poles for condition {condition!r}: have {', '.join(self.poles)}")
        return self.poles[condition]

    def plot(self, axes=None):
        """Draw the poles over the parameter: s-plane, dominant pole, electromechanical pair.

        Parameters
        ----------
        axes : sequence of three matplotlib Axes, optional
            A new figure when omitted.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .plots import plot_parameter_locus
        return plot_parameter_locus(self, axes)


def vary(params: Parameters, parameter: str, value: float, *, carry_inertia: bool = True) -> Parameters:
    """Return ``params`` with one parameter changed, as the accretion study changes it.

    Parameters
    ----------
    params : Parameters
        Parameter set.
    parameter : str
        Name of a numeric parameter.
    value : float
        New value, in the parameter's unit.
    carry_inertia : bool, default True
        For ``m_v``: scale ``J_v`` with it, ``J_v = m_v (J_v/m_v)`` of ``params``
        (same burden shape); for ``J_v``: scale ``m_v`` likewise.  In both,
        when ``J_e_mode = "table"``, ``J_e`` moves with ``J_v`` so the kiln shell
        inertia ``J_e - J_v`` stays the same (accretions add to the burden).

    Returns
    -------
    Parameters
    """
    if parameter not in SPECS:
        raise ParameterError(f"unknown parameter {parameter!r}: {close_matches_hint(parameter, SPECS)}")
    if SPECS[parameter].is_option:
        raise DesignError(f"parameter {parameter!r} is an option, not a number: a locus needs a numeric parameter")
    changes = {parameter: float(value)}
    if carry_inertia and parameter in ("m_v", "J_v"):
        ratio = params.J_v / params.m_v
        J_v = value * ratio if parameter == "m_v" else float(value)
        changes.update(m_v=J_v / ratio, J_v=J_v)
        if params.J_e_mode == "table":
            changes["J_e"] = params.J_e + (J_v - params.J_v)
    return params.replace(**changes)


def _match_columns(rows) -> np.ndarray:
    """Order each row of roots so that every column follows one branch continuously."""
    rows = np.asarray(rows, dtype=complex)
    perms = np.array(list(itertools.permutations(range(rows.shape[1]))))
    out = np.empty_like(rows)
    out[0] = rows[0]
    for i in range(1, len(rows)):
        cand = rows[i][perms]
        out[i] = cand[np.argmin(np.abs(cand - out[i - 1]).sum(axis=1))]
    return out


def parameter_locus(params: Parameters, gains: PIDGains, values=None, parameter: str = "m_v", *,
                    conditions=CONDITIONS, carry_inertia: bool = True,
                    requirements: Requirements | None = None) -> ParameterLocusData:
    """Compute the closed-loop poles over a physical parameter at fixed gains.

    python-control's root locus varies only a loop gain; this varies a plant
    parameter, as the paper's accretion study varies the burden mass (Fig. 14).

    Parameters
    ----------
    params : Parameters
        Nominal parameter set.
    gains : PIDGains
        Fixed PID gains [V/rpm, V/(rpm*s), V*s/rpm].
    values : array_like, optional
        Values of the parameter in its unit.  For ``m_v``: 50 values over the
        paper's 240 000 to 974 000 kg; for ``J_v``: the same range scaled by
        ``J_v/m_v``.  Required for other parameters.
    parameter : str, default "m_v"
        Numeric parameter to vary (see :func:`vary` for ``m_v`` and ``J_v``).
    conditions : sequence of str, default ("stick", "slip")
        Load conditions.  In slip the burden's inertia drops out (eq. 15), so
        burden mass and inertia do not move the slip poles.
    carry_inertia : bool, default True
        See :func:`vary`.
    requirements : Requirements, optional
        Drawn as limits by :meth:`ParameterLocusData.plot`.

    Returns
    -------
    ParameterLocusData
    """
    conditions = _check_conditions(params, conditions)
    if values is None:
        if parameter == "m_v":
            values = np.linspace(*ACCRETION_RANGE, 50)
        elif parameter == "J_v":
            values = np.linspace(*ACCRETION_RANGE, 50) * params.J_v / params.m_v
        else:
            raise DesignError(f"give the values of {parameter!r} to vary (only m_v and J_v have a default range)")
    values = np.unique(np.asarray(values, dtype=float))
    if values.ndim != 1 or values.size < 2 or not np.all(np.isfinite(values)):
        raise DesignError("values must hold at least two finite numbers")
    poles = {c: [] for c in conditions}
    inertias = {c: [] for c in conditions}
    for v in values:
        p = vary(params, parameter, v, carry_inertia=carry_inertia)
        for c in conditions:
            poles[c].append(np.sort_complex(np.asarray(closed_loop_ss(p, gains, c).poles(), dtype=complex)))
            inertias[c].append(inertia(p, c))
    req = requirements.resolve(params) if requirements is not None else None
    return ParameterLocusData(
        parameter=parameter, unit=SPECS[parameter].unit, values=values, nominal=float(params[parameter]),
        poles={c: _match_columns(poles[c]) for c in conditions},
        inertias={c: np.array(inertias[c]) for c in conditions}, gains=gains, requirements=req)
