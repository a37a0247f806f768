"""Root-locus design of the PID speed controller, the paper's procedure made repeatable.

The procedure (``docs/tutorial_design.md`` explains it with figures):

1. The requirements give a target for the *dominant* closed-loop pole, a real
   pole at ``s = -sigma`` (no overshoot from it): as fast as allowed, so
   ``sigma = wn_max``, but at most a fifth of the electromechanical pair's
   decay rate (the usual dominance rule).
2. The motor's electromechanical pair (natural frequency ``w0`` of
   :func:`kilnctl.linear.electromechanical_frequency`, damping about 0.23) is
   damped to ``zeta_min`` at its own natural frequency: the PID damps it, it
   does not move it.
3. The two PID zeros are placed where the root locus of ``L(s) = K C(s) G(s)``
   passes through those three target poles, and the gain is read off the locus
   at the target: ``k_D = -1/L_1(-sigma)`` with ``L_1 = L/k_D``.
4. Both load conditions are analysed; the targets move (``sigma`` down,
   ``zeta`` of the pair up) until every requirement holds for stick *and* slip,
   or the best design found is reported with the requirements it misses.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import DesignError
from ..linear import CONDITIONS, electromechanical_frequency, inertia
from ..params import Parameters
from .analysis import analyse, unmet_requirements
from .gains import GAIN_UNITS, PIDGains
from .requirements import Requirements, torsional_mode_frequency

__all__ = ["DesignResult", "RequirementsNotMetError", "design_pid", "gains_for", "place_poles",
           "DOMINANCE_RATIO"]

#: the dominant pole is kept at least this many times slower than the electromechanical pair's decay
DOMINANCE_RATIO = 5.0

#: parameters the linear design depends on (the cache key of :func:`gains_for`)
_DESIGN_KEYS = ("R_a", "L_a", "k_i", "k_b", "J_m", "B_m", "K_fb", "J_o", "J_v", "J_e", "J_e_mode", "n",
                "R_o", "R_p", "k_po")


class RequirementsNotMetError(DesignError):
    """The requirements cannot all be met; carries the best design found.

    Attributes
    ----------
    best : DesignResult
        The design that came closest, with its figures for both conditions.
    unmet : list of str
        The requirements missed, each a sentence with the value achieved.
    """

    def __init__(self, message: str, best: "DesignResult", unmet: list[str]):
        super().__init__(message)
        self.best = best
        self.unmet = unmet


def place_poles(params: Parameters, sigma: float, zeta: float, condition: str = "stick") -> PIDGains:
    """Return the PID gains that put the closed-loop poles at the design targets.

    Targets: a real pole at ``-sigma`` and the electromechanical pair at damping
    ``zeta`` and its open-loop natural frequency ``w0``; matching
    ``L_a J (s + sigma)(s^2 + 2 zeta w0 s + w0^2)`` with the characteristic
    polynomial gives::

        k_D = (L_a J (2 zeta w0 + sigma) - L_a B_m - R_a J) / (K k_i)
        k_p = 2 L_a J zeta w0 sigma / (K k_i)
        k_I = L_a J sigma w0^2 / (K k_i)

    Parameters
    ----------
    params : Parameters
        Parameter set.
    sigma : float
        Decay rate of the dominant real pole [1/s], > 0.
    zeta : float
        Damping ratio of the electromechanical pair [-]; raised as needed so
        that ``k_D >= 0``.
    condition : {"stick", "slip"}
        Load condition whose inertia the targets are placed for.

    Returns
    -------
    PIDGains
        Gains [V/rpm, V/(rpm*s), V*s/rpm].
    """
    if not (math.isfinite(sigma) and sigma > 0):
        raise DesignError(f"target decay rate sigma = {sigma!r} 1/s must be a finite number > 0")
    J = inertia(params, condition)
    w0 = electromechanical_frequency(params, condition)
    La, Ra, ki, Bm, K = params.L_a, params.R_a, params.k_i, params.B_m, params.K_fb
    zeta = max(zeta, _zeta_for_zero_kd(params, sigma, condition))
    a = La * J
    kd = (a * (2 * zeta * w0 + sigma) - La * Bm - Ra * J) / (K * ki)
    kp = 2 * a * zeta * w0 * sigma / (K * ki)
    kI = a * sigma * w0**2 / (K * ki)
    return PIDGains(kp, kI, max(kd, 0.0))


def _zeta_for_zero_kd(params: Parameters, sigma: float, condition: str) -> float:
    """Pair damping at which k_D = 0 (a PI controller): below it k_D would be negative."""
    J = inertia(params, condition)
    w0 = electromechanical_frequency(params, condition)
    return ((params.B_m / J + params.R_a / params.L_a) - sigma) / (2 * w0)


@dataclass(frozen=True)
class DesignResult:
    """Outcome of :func:`design_pid`: gains, figures per load condition, requirements.

    Attributes
    ----------
    gains : PIDGains
        Designed gains ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D`` [V*s/rpm].
    requirements : Requirements
        The requirements, resolved (``wn_max`` a number [rad/s]).
    reports : dict of str to ConditionReport
        Closed-loop figures for ``"stick"`` and ``"slip"``.
    design_condition : str
        Condition whose inertia the targets were placed for.
    target : dict
        ``sigma`` [1/s] of the dominant pole, ``zeta`` [-] and ``wn`` [rad/s]
        of the electromechanical pair, as placed.
    unmet : tuple of str
        Requirements not met (empty when the design meets them all).
    params : Parameters
        The parameter set designed for.
    """

    gains: PIDGains
    requirements: Requirements
    reports: dict
    design_condition: str
    target: dict
    unmet: tuple = ()
    params: Parameters = field(default_factory=Parameters, repr=False)

    @property
    def meets_requirements(self) -> bool:
        """True when every requirement holds in both load conditions."""
        return not self.unmet

    @property
    def zeros(self) -> np.ndarray:
        """Zeros of the PID [rad/s] (where the locus ends)."""
        return self.gains.zeros()

    def to_dict(self) -> dict:
        """Return a JSON-ready summary (no NaN or inf).

        The top level repeats the figures of the design condition; every
        condition's figures are under ``conditions``.

        Returns
        -------
        dict
            ``kp``, ``ki``, ``kd``, ``units``, ``pid_zeros``, the design
            condition's figures (see :meth:`ConditionReport.to_dict`),
            ``conditions``, ``requirements``, ``torsional_mode_rad_s``,
            ``target``, ``meets_requirements`` and ``unmet``.
        """
        conds = {c: r.to_dict() for c, r in self.reports.items()}
        out = dict(self.gains.as_dict())
        out["units"] = dict(GAIN_UNITS)
        out["pid_zeros"] = [[float(z.real), float(z.imag)] for z in self.zeros]
        out["design_condition"] = self.design_condition
        out.update(conds[self.design_condition])
        out["conditions"] = conds
        out["requirements"] = self.requirements.as_dict()
        out["torsional_mode_rad_s"] = torsional_mode_frequency(self.params)
        out["target"] = {k: float(v) for k, v in self.target.items()}
        out["meets_requirements"] = self.meets_requirements
        out["unmet"] = list(self.unmet)
        return out

    def summary(self) -> str:
        """Return a text table of the gains and the figures for both conditions, side by side."""
        req = self.requirements
        rows = [
            ("inertia J [kg*m^2]", lambda r: f"{r.J:.3f}"),
            ("dominant pole [rad/s]", lambda r: _fmt_pole(r.poles[0])),
            ("other poles [rad/s]", lambda r: ", ".join(_fmt_pole(p) for p in r.poles[1:] if p.imag >= 0)),
            ("dominant zeta [-]", lambda r: f"{r.dominant_zeta:.3f}"),
            ("dominant wn [rad/s]", lambda r: f"{r.dominant_wn:.3f}"),
            (f"min zeta, all poles (>= {req.zeta_min:g})", lambda r: f"{r.zeta_min_all:.3f}"),
            (f"settling time 2 % [s] (<= {req.settling_time_max:g})", lambda r: _fmt(r.settling_time, ".3f")),
            (f"overshoot [%] (<= {req.overshoot_max:g})", lambda r: _fmt(r.overshoot, ".2f")),
            ("dip after the kick [%]", lambda r: _fmt(r.dip, ".1f")),
            ("rise time 10-90 % [s]", lambda r: _fmt(r.rise_time, ".3f")),
            ("bandwidth -3 dB [rad/s]", lambda r: _fmt(r.bandwidth, ".3f")),
            ("gain margin [dB]", lambda r: _fmt(r.gain_margin_db, ".1f")),
            ("phase margin [deg]", lambda r: _fmt(r.phase_margin, ".1f")),
            ("current jump k_D/L_a [A/rpm]", lambda r: f"{r.current_jump:.2f}"),
            (f"lag behind {self.params.ramp_rate:g} rpm/s ramp [rpm]", lambda r: _fmt(r.ramp_lag, ".2f")),
        ]
        conds = list(self.reports)
        width = max(len(r[0]) for r in rows) + 2
        lines = [f"gains: {self.gains}",
                 f"PID zeros [rad/s]: {', '.join(_fmt_pole(z) for z in self.zeros if z.imag >= 0)}",
                 f"requirements: zeta_min = {req.zeta_min:g}, settling_time_max = {req.settling_time_max:g} s, "
                 f"overshoot_max = {req.overshoot_max:g} %, wn_max = {req.wn_max:.3f} rad/s",
                 "",
                 f"{'':<{width}}" + "".join(f"{c:>22}" for c in conds)]
        for label, fn in rows:
            lines.append(f"{label:<{width}}" + "".join(f"{fn(self.reports[c]):>22}" for c in conds))
        lines.append("")
        lines.append("meets all requirements in both conditions" if self.meets_requirements
                     else "NOT MET: " + "; ".join(self.unmet))
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    # --- data objects for plotting (computed here, drawn by their .plot()) -----
    def locus(self, kappas=None):
        """Return the root locus over the loop gain at the designed gains.

        Parameters
        ----------
        kappas : array_like, optional
            Gain scalings [-] (``kappa = 1`` is the design); a default range
            when omitted.

        Returns
        -------
        RootLocusData
        """
        from .locus import root_locus
        return root_locus(self.params, self.gains, requirements=self.requirements, kappas=kappas)

    def step_responses(self, t_final: float | None = None):
        """Return the closed-loop step responses to a speed-reference step.

        Parameters
        ----------
        t_final : float, optional
            End time [s]; about 2.5 settling times when omitted.

        Returns
        -------
        StepResponseData
        """
        from .locus import step_responses
        return step_responses(self.params, self.gains, requirements=self.requirements, t_final=t_final)

    def parameter_locus(self, values=None, parameter: str = "m_v"):
        """Return the closed-loop poles over a physical parameter at the designed gains.

        Parameters
        ----------
        values : array_like, optional
            Parameter values (SI units of the parameter); for ``m_v`` the
            paper's accretion range 240 000 to 974 000 kg by default.
        parameter : str, default "m_v"
            Parameter varied (``m_v`` carries ``J_v`` along, see
            :func:`kilnctl.design.parameter_locus`).

        Returns
        -------
        ParameterLocusData
        """
        from .locus import parameter_locus
        return parameter_locus(self.params, self.gains, values=values, parameter=parameter,
                               requirements=self.requirements)

    def plot(self):
        """Draw the root locus (full and zoomed) and the step responses on one figure.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .plots import plot_design
        return plot_design(self)


def _fmt(value, spec: str) -> str:
    if value is None:
        return "n/a"
    if not math.isfinite(value):
        return "inf" if value > 0 else "-inf"
    return format(value, spec)


def _fmt_pole(p: complex) -> str:
    if abs(p.imag) < 1e-9 * max(1.0, abs(p)):
        return f"{p.real:.3f}"
    return f"{p.real:.2f}{'+' if p.imag >= 0 else '-'}{abs(p.imag):.2f}j"


def _score(unmet) -> float:
    return sum(v for _, _, v in unmet)


#: damping targets of the electromechanical pair tried above zeta_min, in order, until every requirement holds
PAIR_DAMPING_LADDER = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0)


def _search(params: Parameters, req: Requirements, zeta_target: float, design_condition: str, w0: float):
    """Best design with the pair damped to ``zeta_target``: (score, step, gains, reports, unmet, target)."""

    def evaluate(sigma: float, zeta: float):
        gains = place_poles(params, sigma, zeta, design_condition)
        reports = {c: analyse(params, gains, c) for c in CONDITIONS}
        return gains, reports, unmet_requirements(reports, req)

    best = None
    # the pair decays at zeta*w0 (zeta at least what k_D = 0 leaves); keep the real pole DOMINANCE_RATIO slower
    pair_decay = max(zeta_target, _zeta_for_zero_kd(params, 0.0, design_condition)) * w0
    sigma_top = min(req.wn_max, pair_decay / DOMINANCE_RATIO)
    # outer ladder: move the dominant target down the real axis if overshoot forces it
    for step in range(12):
        sigma, zeta = sigma_top * 0.85**step, zeta_target
        # inner fixed point: both conditions inside wn_max and above zeta_min
        for _ in range(12):
            gains, reports, unmet = evaluate(sigma, zeta)
            names = {u[0] for u in unmet}
            if not names & {"wn_max", "zeta_min"}:
                break
            if "wn_max" in names:
                worst = max(r.dominant_wn for r in reports.values())
                sigma *= req.wn_max / worst * (1 - 1e-6)
            if "zeta_min" in names:
                worst = min(r.zeta_min_all for r in reports.values())
                zeta = min(zeta + (req.zeta_min - worst) + 1e-6, 5.0)
        target = {"sigma": sigma, "zeta": max(zeta, _zeta_for_zero_kd(params, sigma, design_condition)),
                  "wn": w0}
        candidate = (_score(unmet), step, gains, reports, unmet, target)
        if best is None or candidate[0] < best[0]:
            best = candidate
        if not unmet:
            break
        names = {u[0] for u in unmet}
        if "overshoot_max" not in names:
            break  # slower targets only lengthen settling; nothing to gain
    return best


def design_pid(params: Parameters, requirements: Requirements | None = None, *,
               design_condition: str = "stick", strict: bool = True) -> DesignResult:
    """Design the PID speed-controller gains by root locus for both load conditions.

    Parameters
    ----------
    params : Parameters
        Parameter set (motor, inertias, feedback constant; ``k_po`` and ``J_e``
        for the default ``wn_max``).
    requirements : Requirements, optional
        Closed-loop requirements; ``Requirements()`` (the documented
        defaults) when omitted.
    design_condition : {"stick", "slip"}, default "stick"
        Condition whose inertia the target poles are placed for; both are
        always checked.  Stick is the start-up condition, with the larger inertia.
    strict : bool, default True
        Raise :class:`RequirementsNotMetError` when a requirement cannot be
        met.  With False, return the best design with ``unmet`` filled in.

    Returns
    -------
    DesignResult
        Gains, target poles, figures per condition (poles, dominant zeta and
        wn, step information, margins).

    Raises
    ------
    RequirementsNotMetError
        (a :class:`kilnctl.errors.DesignError`) when ``strict`` and a
        requirement is missed in either condition; the message names each
        requirement, the best value achieved and the fix, and ``.best`` holds
        that design.
    DesignError
        For malformed requirements.
    """
    Parameters.require(params, hint="Parameters(m_v=5e5), or Parameters.from_toml(path) for a file", error=DesignError)
    if requirements is None:
        requirements = Requirements()
    if not isinstance(requirements, Requirements):
        raise DesignError(f"requirements must be a kilnctl.design.Requirements, not {type(requirements).__name__}")
    if design_condition not in CONDITIONS:
        raise DesignError(f"unknown design_condition {design_condition!r}: choose 'stick' or 'slip'")
    req = requirements.resolve(params)
    w0 = electromechanical_frequency(params, design_condition)
    # The pair's damping target starts at the floor zeta_min and, if the design misses a requirement, steps up
    # a fixed ladder. The ladder makes loosening a requirement safe: the floor only bounds the targets from
    # below, so a lower zeta_min still reaches every target a higher one would (with zeta_min = 0 the target
    # itself was 0 and the slow pair forced a slow dominant pole: settling failed where zeta_min = 0.3 worked).
    best = None
    for zeta_target in [req.zeta_min] + [z for z in PAIR_DAMPING_LADDER if z > req.zeta_min]:
        candidate = _search(params, req, zeta_target, design_condition, w0)
        if best is None or candidate[0] < best[0]:
            best = candidate
        if not candidate[4]:
            break
    _, _, gains, reports, unmet, target = best
    result = DesignResult(gains=gains, requirements=req, reports=reports, design_condition=design_condition,
                          target=target, unmet=tuple(u[1] for u in unmet), params=params)
    if unmet and strict:
        raise RequirementsNotMetError(_unmet_message(result, unmet, w0), best=result,
                                      unmet=list(result.unmet))
    return result


def _unmet_message(result: DesignResult, unmet, w0: float) -> str:
    req = result.requirements
    reps = result.reports.values()
    fixes = []
    for name in dict.fromkeys(u[0] for u in unmet):
        if name == "settling_time_max":
            best = max(r.settling_time for r in reps)
            fixes.append(f"settling_time_max = {req.settling_time_max:g} s: best achieved {best:.3f} s, with the "
                         f"dominant pole held at or below wn_max = {req.wn_max:.3f} rad/s (half the "
                         f"{torsional_mode_frequency(result.params):.2f} rad/s drive-train torsional mode by "
                         f"default) and a fifth of the electromechanical pair's decay; raise settling_time_max "
                         f"to at least {best:.3f} s, or raise wn_max")
        elif name == "overshoot_max":
            best = max(r.overshoot for r in reps)
            fixes.append(f"overshoot_max = {req.overshoot_max:g} %: best achieved {best:.3f} %; raise overshoot_max "
                         f"to at least {best:.3f} %")
        elif name == "zeta_min":
            best = min(r.zeta_min_all for r in reps)
            fixes.append(f"zeta_min = {req.zeta_min:g}: best achieved {best:.3f}; lower zeta_min to at most "
                         f"{best:.3f}")
        elif name == "wn_max":
            best = max(r.dominant_wn for r in reps)
            fixes.append(f"wn_max = {req.wn_max:.3f} rad/s: best achieved {best:.3f} rad/s; raise wn_max to at "
                         f"least {best:.3f} rad/s")
        else:
            fixes.append(f"{name}: " + "; ".join(u[1] for u in unmet if u[0] == name))
    return ("the requirements cannot all be met in both load conditions: " + "; ".join(fixes)
            + f". Best design: {result.gains}")


@functools.lru_cache(maxsize=128)
def _default_design(key: Parameters) -> PIDGains:
    return design_pid(key).gains


def gains_for(params: Parameters) -> PIDGains:
    """Return the speed-controller gains a parameter set asks for.

    Parameters
    ----------
    params : Parameters
        With ``gains = "given"``: ``k_p`` [V/rpm], ``k_I`` [V/(rpm*s)], ``k_D``
        [V*s/rpm] as set.  With ``gains = "design"``: the root-locus design with
        the default :class:`Requirements` (cached on the parameters the design
        depends on).

    Returns
    -------
    PIDGains

    Raises
    ------
    RequirementsNotMetError
        When the default requirements cannot be met for this parameter set.
    """
    if params.gains == "given":
        return PIDGains(params.k_p, params.k_I, params.k_D)
    key = Parameters({k: params[k] for k in _DESIGN_KEYS})
    return _default_design(key)
