"""The start-up ramp optimization problem, declared once (how it is solved is separate).

A :class:`RampProblem` says *what* is wanted: the ramp profile family and
its decision variables (:class:`Profile`), the objective (peak gear bending
stress during the start-up), the constraints (95 % of the speed set point by
``t_max``, armature current and voltage within the drive's limits) and,
for a robust ramp, the scenarios it must hold for (:class:`Scenario`).
:func:`kilnctl.optimize.optimize_ramp` decides *how*: smooth model,
transcription, continuation, verification on the hybrid plant.

Examples
--------
>>> from kilnctl import Parameters
>>> from kilnctl.optimize import Profile, RampProblem
>>> Profile.parse("pwl:3").names
('ramp_r1', 'ramp_r2', 'ramp_r3')
>>> prob = RampProblem(Parameters(gains="given"), profile="scurve", t_max=12.0)
>>> prob.horizon
27.0
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ..model.ramps import pwl_component, scurve_timing
from ..params import Parameters
from ..structure import PRESETS, Structure

__all__ = ["Profile", "Scenario", "RampProblem", "default_scenarios", "OBJECTIVES", "SETTLE_MARGIN_S"]

#: objectives a problem may ask for (see docs/optimization.md)
OBJECTIVES = {
    "peak": "peak |sigma| of the girth-gear tooth over the start-up horizon, running load included",
    "dynamic": "peak |sigma - sigma_load|: the stress from accelerating the kiln shell (impacts, ramp), "
               "without the burden and bearing load that any ramp must carry",
}
#: default horizon after t_max [s]: the burden needs about 12 s at full speed to reach its running angle
SETTLE_MARGIN_S = 15.0
#: bounds of a reference rate or acceleration limit [rpm/s]
RATE_BOUNDS = (1.0, 2000.0)
#: most segments of a pwl:N profile: pwl:8 solved in 54 s, pwl:12 spent more than 6 minutes in one sensitivity
#: run at a trial point and was stopped (docs/benchmarks.md, "Long ramp optimizations")
MAX_PWL_SEGMENTS = 8
#: bounds of a jerk limit [rpm/s^2]
JERK_BOUNDS = (1.0, 2.0e4)


@dataclass(frozen=True)
class Profile:
    """A family of speed-reference profiles and its decision variables.

    Attributes
    ----------
    kind : {'constant', 'scurve', 'pwl'}
        ``constant``: the paper's single ramp rate; ``scurve``: jerk-limited
        S-curve (acceleration limit and jerk); ``pwl``: piecewise-linear
        with ``n`` segments of equal speed increment.
    n : int
        Number of segments of ``pwl`` (1 for ``constant``; 2 for ``scurve``,
        its two numbers: see :attr:`names`).
    """

    kind: str
    n: int = 1

    @classmethod
    def parse(cls, text) -> "Profile":
        """Read ``'constant'``, ``'scurve'`` or ``'pwl:N'`` (N >= 1).

        Parameters
        ----------
        text : str or Profile
            Profile specification.

        Returns
        -------
        Profile

        Raises
        ------
        ParameterError
            Unknown profile or a bad segment count.
        """
        if isinstance(text, Profile):
            return text
        if not isinstance(text, str):
            raise ParameterError(f"profile {text!r} must be 'constant', 'scurve' or 'pwl:N'")
        s = text.strip().lower()
        if s == "constant":
            return cls("constant", 1)
        if s == "scurve":
            return cls("scurve", 2)
        m = re.fullmatch(r"pwl:(\d+)", s)
        if m:
            n = int(m.group(1))
            if not 1 <= n <= MAX_PWL_SEGMENTS:
                raise ParameterError(f"profile {text!r}: the number of segments must lie in 1..{MAX_PWL_SEGMENTS} "
                                     "(more did not finish in reasonable time: docs/benchmarks.md)")
            return cls("pwl", n)
        raise ParameterError(f"unknown profile {text!r}: choose 'constant', 'scurve' or 'pwl:N' (e.g. 'pwl:4')")

    @property
    def label(self) -> str:
        """Specification string (``'constant'``, ``'scurve'``, ``'pwl:4'``)."""
        return f"pwl:{self.n}" if self.kind == "pwl" else self.kind

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the decision variables (constant states of the ramp component)."""
        if self.kind == "scurve":
            return ("ramp_a", "ramp_j")
        return tuple(f"ramp_r{k}" for k in range(1, self.n + 1))

    @property
    def units(self) -> tuple[str, ...]:
        """Units of the decision variables."""
        return ("rpm/s", "rpm/s^2") if self.kind == "scurve" else ("rpm/s",) * self.n

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of the decision variables (physical units)."""
        if self.kind == "scurve":
            return np.array([RATE_BOUNDS[0], JERK_BOUNDS[0]]), np.array([RATE_BOUNDS[1], JERK_BOUNDS[1]])
        return np.full(self.n, RATE_BOUNDS[0]), np.full(self.n, RATE_BOUNDS[1])

    @property
    def smooth_component(self) -> str:
        """Registry name of the reference component in the smooth (optimization) model."""
        if self.kind == "scurve":
            return "ramp_scurve"
        return pwl_component(self.n, smooth=True)

    @property
    def exact_component(self) -> str | None:
        """Reference component added to the hybrid plant (None: the paper's ``ramp`` alone)."""
        if self.kind == "constant":
            return None
        if self.kind == "scurve":
            return "ramp_scurve"
        return pwl_component(self.n)

    def guess(self, omega_ref: float, t_max: float, speed_fraction: float) -> np.ndarray:
        """A feasible-looking starting point: the reference reaches omega_ref at 0.8*t_max [units of names].

        Parameters
        ----------
        omega_ref : float
            Speed set point [rpm].
        t_max : float
            Time by which the speed must be reached [s].
        speed_fraction : float
            Fraction of omega_ref to reach [-].

        Returns
        -------
        ndarray
        """
        t_ref = 0.8 * t_max
        if self.kind == "scurve":
            a = omega_ref / (0.75 * t_ref)
            return np.array([a, a / (0.25 * t_ref)])
        return np.full(self.n, omega_ref / t_ref)

    def end_time(self, values, omega_ref: float) -> float:
        """Time at which the (exact) reference reaches omega_ref [s].

        Parameters
        ----------
        values : sequence of float
            Decision variables in the units of :attr:`units`.
        omega_ref : float
            Speed set point [rpm].

        Returns
        -------
        float
        """
        v = [float(x) for x in values]
        if self.kind == "scurve":
            return float(scurve_timing(v[0], v[1], omega_ref)[2])
        return float(sum(omega_ref / self.n / r for r in v))

    def describe(self, values, omega_ref: float) -> dict:
        """JSON-ready description of a profile: its numbers with units and its end time.

        Parameters
        ----------
        values : sequence of float
            Decision variables.
        omega_ref : float
            Speed set point [rpm].

        Returns
        -------
        dict
            ``constant``: ``{'rate_rpm_s'}``; ``pwl``: ``{'rates_rpm_s', 'knots'}``
            with the knots as [time s, reference rpm] pairs; ``scurve``:
            ``{'accel_rpm_s', 'jerk_rpm_s2'}``; all with ``end_time_s``.
        """
        v = [float(x) for x in values]
        d: dict = {"end_time_s": self.end_time(v, omega_ref)}
        if self.kind == "constant":
            d["rate_rpm_s"] = v[0]
        elif self.kind == "scurve":
            a_eff = float(scurve_timing(v[0], v[1], omega_ref)[0])
            d.update(accel_rpm_s=v[0], jerk_rpm_s2=v[1], accel_reached_rpm_s=a_eff)
        else:
            t, knots = 0.0, [[0.0, 0.0]]
            for k, r in enumerate(v, start=1):
                t += omega_ref / self.n / r
                knots.append([t, omega_ref * k / self.n])
            d.update(rates_rpm_s=v, knots=knots)
        return d

    def equivalent_rate(self, values, omega_ref: float) -> float:
        """Mean rate omega_ref / end time: the constant ramp that ends at the same time.

        Parameters
        ----------
        values : sequence of float
            Decision variables.
        omega_ref : float
            Speed set point [rpm].

        Returns
        -------
        float
            Rate [rpm/s].
        """
        return omega_ref / self.end_time(values, omega_ref)


@dataclass(frozen=True)
class Scenario:
    """One operating condition a robust ramp must hold for.

    Attributes
    ----------
    name : str
        Short label (``m_v=974t,dx=16mm`` ...).
    changes : dict
        Parameter values that differ from the nominal set.
    """

    name: str
    changes: dict = field(default_factory=dict)

    def apply(self, params: Parameters) -> Parameters:
        """Return ``params`` with this scenario's changes.

        Parameters
        ----------
        params : Parameters
            Nominal set.

        Returns
        -------
        Parameters
        """
        return params.replace(**self.changes) if self.changes else params


def default_scenarios(params: Parameters | None = None) -> tuple[Scenario, ...]:
    """The corners of the paper's studied ranges, as scenarios.

    Burden mass m_v 240-974 t (Fig. 14; inertia J_v kept, as Fig. 14 varies
    the mass alone), backlash delta_x 0-16 mm (Fig. 11), and the friction
    coefficients between Fig. 9's (mu_c 0.35, mu_s 0.38) and Fig. 4's best fit
    (mu_c 0.4, mu_s 0.51): 8 corners.

    Parameters
    ----------
    params : Parameters, optional
        Unused; reserved for ranges that depend on the nominal set.

    Returns
    -------
    tuple of Scenario
    """
    out = []
    for m in (240e3, 974e3):
        for dx in (0.0, 16e-3):
            for mu_c, mu_s in ((0.35, 0.38), (0.4, 0.51)):
                out.append(Scenario(f"m_v={m / 1e3:.0f}t,dx={dx * 1e3:.0f}mm,mu={mu_c}/{mu_s}",
                                    {"m_v": m, "delta_x": dx, "mu_c": mu_c, "mu_s": mu_s}))
    return tuple(out)


def _positive(name, v, unit="seconds"):
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
        raise ParameterError(f"{name} = {v!r} must be a finite number of {unit} > 0")
    return float(v)


@dataclass
class RampProblem:
    """Start-up ramp optimization problem.

    minimize over the profile's numbers theta (scaled):
        peak over t in [0, horizon] of |s(t)| in every scenario (worst case),
        s = sigma (``objective='peak'``) or sigma - sigma_load (``'dynamic'``)
    subject to
        motor speed(t_max) >= speed_fraction * omega_ref,
        |i_a(t)| <= I_max and |e_a(t)| <= V_max on [0, horizon],
        theta within the profile's bounds.

    Parameters
    ----------
    params : Parameters
        Nominal parameter set (gains resolved by the solver if ``'design'``).
    profile : str or Profile, default 'constant'
        ``'constant'``, ``'scurve'`` or ``'pwl:N'``.
    t_max : float, default 10.0
        Time by which the motor must reach ``speed_fraction`` of omega_ref [s].
    horizon : float, optional
        Simulated start-up [s], >= t_max; default t_max + 15 s, long enough for
        the burden to reach its running angle (its load is part of the peak).
    speed_fraction : float, default 0.95
        Fraction of omega_ref to reach by t_max [-].
    objective : {'peak', 'dynamic'}, default 'peak'
        See :data:`OBJECTIVES`.
    scenarios : sequence of Scenario, optional
        Operating conditions for a robust ramp; empty: the nominal set only.
    include_nominal : bool, default True
        With scenarios, keep the nominal set as one more scenario.
    max_rate : float, optional
        Largest rate of the reference [rpm/s]: every segment of ``pwl:N``,
        the ``constant`` rate, the S-curve's acceleration.  Default: the
        profile's own bound (2000 rpm/s).  Use it to forbid a ramp that creeps
        and then jumps (the optimum may do that: the result's notes say so).
    effects : sequence of str or Structure, default ()
        Effects on the micro model, in the smooth model and the hybrid
        verification alike (a structure a diagnosis learned:
        ``second_motor``, ``speed_sensor_lag``, ``kiln_unbalance``,
        ``viscous_drag``; one with modes needs a smooth twin, which the
        smooth model then carries: ``motor_coulomb_friction``), or a micro
        :class:`kilnctl.structure.Structure` (its added components become
        the effects, its options are set on ``params``).

    Raises
    ------
    ParameterError
        Bad times, fraction, objective or profile.
    """

    params: Parameters
    profile: Profile | str = "constant"
    t_max: float = 10.0
    horizon: float | None = None
    speed_fraction: float = 0.95
    objective: str = "peak"
    scenarios: tuple = ()
    include_nominal: bool = True
    max_rate: float | None = None
    effects: tuple = ()

    def __post_init__(self):
        Parameters.require(self.params)
        self.profile = Profile.parse(self.profile)
        from .model import check_effects

        if isinstance(self.effects, Structure):
            s = self.effects
            if s.model != "micro" or s.remove:
                raise ParameterError(f"effects = Structure {s}: the ramp is optimized on the micro model with "
                                     "effects added (none removed): use Structure('micro', ...)")
            self.params = s.apply(self.params)
            self.effects = tuple(c for c in s.components() if c not in PRESETS["micro"].components())
        self.effects = check_effects(self.effects)
        self.t_max = _positive("t_max", self.t_max)
        self.horizon = self.t_max + SETTLE_MARGIN_S if self.horizon is None else _positive("horizon", self.horizon)
        if self.horizon < self.t_max:
            raise ParameterError(f"horizon = {self.horizon} s must not be shorter than t_max = {self.t_max} s")
        f = self.speed_fraction
        if isinstance(f, bool) or not isinstance(f, (int, float)) or not 0 < f < 1:
            raise ParameterError(f"speed_fraction = {f!r} must lie strictly between 0 and 1")
        if self.objective not in OBJECTIVES:
            raise ParameterError(f"objective {self.objective!r} is unknown: choose one of {sorted(OBJECTIVES)}")
        if self.max_rate is not None:
            self.max_rate = _positive("max_rate", self.max_rate, "rpm/s")
            if not RATE_BOUNDS[0] < self.max_rate <= RATE_BOUNDS[1]:
                raise ParameterError(f"max_rate = {self.max_rate:g} rpm/s must lie in ({RATE_BOUNDS[0]:g}, "
                                     f"{RATE_BOUNDS[1]:g}] rpm/s")
        self.scenarios = tuple(self.scenarios)
        for s in self.scenarios:
            if not isinstance(s, Scenario):
                raise ParameterError(f"scenarios must be Scenario objects, not {type(s).__name__}")
            s.apply(self.params)  # validates the changes now, with the parameter's own message

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of the decision variables (profile units): the profile's, with ``max_rate`` applied.

        Returns
        -------
        lower, upper : ndarray
        """
        lo, hi = self.profile.bounds()
        if self.max_rate is not None:
            hi = hi.copy()
            if self.profile.kind == "scurve":
                hi[0] = min(hi[0], self.max_rate)
            else:
                hi = np.minimum(hi, self.max_rate)
        return lo, hi

    @property
    def robust(self) -> bool:
        """True when the problem has scenarios (worst case over them)."""
        return bool(self.scenarios)

    def cases(self) -> list[tuple[str, Parameters]]:
        """(name, parameters) of every case the objective takes the worst of."""
        out = []
        if not self.scenarios or self.include_nominal:
            out.append(("nominal", self.params))
        out += [(s.name, s.apply(self.params)) for s in self.scenarios]
        return out

    def baseline_values(self) -> np.ndarray:
        """The paper's constant ramp (``params.ramp_rate``) in this profile's variables."""
        r = self.params.ramp_rate
        if self.profile.kind == "scurve":
            return np.array([r, 1e3 * r])  # an almost instantaneous jerk: the constant ramp
        return np.full(self.profile.n, r)
