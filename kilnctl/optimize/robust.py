"""The price of robustness: the nominal optimum against the robust one, both on the hybrid plant.

A robust ramp (:class:`~kilnctl.optimize.RampProblem` with scenarios) holds
the worst case over the scenarios down; the nominal optimum is best for the
nominal parameters only.  :func:`price_of_robustness` solves both and
measures each on every case of the hybrid plant, so the table shows what the
robust ramp gives up at the nominal point (the price) and what it gains in
the worst case (the protection).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..errors import ParameterError
from ..simulate import resolve_gains
from .problem import RampProblem
from .result import RampResult
from .solve import optimize_ramp
from .verify import measure_hybrid

__all__ = ["RobustnessPrice", "price_of_robustness"]


@dataclass
class RobustnessPrice:
    """Nominal and robust optimum, each measured on every case of the hybrid plant.

    Attributes
    ----------
    nominal : RampResult
        Optimum of the nominal problem (verified on the nominal case).
    robust : RampResult
        Optimum of the robust problem (verified on every case).
    nominal_on_cases : dict of str to StartupMeasures
        The nominal optimum re-simulated on every case of the robust problem.
    """

    nominal: RampResult
    robust: RampResult
    nominal_on_cases: dict

    def _worst(self, measures: dict) -> float:
        kind = self.robust.problem.objective
        return max(m.objective(kind) for m in measures.values())

    def summary(self) -> dict:
        """JSON-ready comparison (objective values in Pa).

        Returns
        -------
        dict
            ``objective``; for ``nominal_optimum`` and ``robust_optimum``:
            ``ramp``, ``nominal_Pa`` (objective at the nominal point),
            ``worst_case_Pa`` and ``worst_case``; ``price_pct`` (nominal
            objective given up by the robust ramp) and ``protection_pct``
            (worst case gained), both relative to the nominal optimum.
        """
        kind = self.robust.problem.objective
        prof = self.robust.problem.profile
        omega = self.robust.problem.params.omega_ref
        n_nom = self.nominal.verified["nominal"].objective(kind)
        r_nom = self.robust.verified["nominal"].objective(kind) if "nominal" in self.robust.verified else None
        n_w, r_w = self._worst(self.nominal_on_cases), self._worst(self.robust.verified)
        worst_case = lambda ms: max(ms, key=lambda k: ms[k].objective(kind))  # noqa: E731
        return {
            "objective": kind,
            "nominal_optimum": {"ramp": prof.describe(self.nominal.values, omega), "nominal_Pa": n_nom,
                                "worst_case_Pa": n_w, "worst_case": worst_case(self.nominal_on_cases)},
            "robust_optimum": {"ramp": prof.describe(self.robust.values, omega), "nominal_Pa": r_nom,
                               "worst_case_Pa": r_w, "worst_case": worst_case(self.robust.verified)},
            "price_pct": None if r_nom is None else 100.0 * (r_nom / n_nom - 1.0),
            "protection_pct": 100.0 * (1.0 - r_w / n_w),
        }

    def table(self) -> str:
        """Plain-text table: nominal and worst-case objective of both optima."""
        s = self.summary()
        kind = "peak" if s["objective"] == "peak" else "dynamic"
        rows = [f"price of robustness ({kind} stress, hybrid plant, {len(self.robust.verified)} cases)",
                f"  {'':20s}{'nominal [MPa]':>15s}{'worst case [MPa]':>18s}  worst case"]
        for label, key in (("nominal optimum", "nominal_optimum"), ("robust optimum", "robust_optimum")):
            d = s[key]
            nom = "-" if d["nominal_Pa"] is None else f"{d['nominal_Pa'] / 1e6:.2f}"
            rows.append(f"  {label:20s}{nom:>15s}{d['worst_case_Pa'] / 1e6:>18.2f}  {d['worst_case']}")
        if s["price_pct"] is not None:
            rows.append(f"  the robust ramp costs {s['price_pct']:+.1f} % at the nominal point and changes the worst "
                        f"case by {-s['protection_pct']:+.1f} %")
        return "\n".join(rows)


def price_of_robustness(problem: RampProblem, **solve_options) -> RobustnessPrice:
    """Solve the nominal and the robust problem and measure both optima on every case.

    Parameters
    ----------
    problem : RampProblem
        A robust problem (with scenarios); its nominal version drops them.
    **solve_options
        Passed to :func:`optimize_ramp` for both solves.

    Returns
    -------
    RobustnessPrice

    Raises
    ------
    ParameterError
        The problem has no scenarios.
    """
    if not problem.robust:
        raise ParameterError("price_of_robustness needs a problem with scenarios (RampProblem(..., scenarios=...))")
    robust = optimize_ramp(problem, **solve_options)
    nominal = optimize_ramp(replace(problem, scenarios=()), **solve_options)
    on_cases = {}
    for name, cp in problem.cases():
        on_cases[name], _ = measure_hybrid(resolve_gains(cp), problem.profile, nominal.values, problem.horizon,
                                           problem.speed_fraction, effects=problem.effects)
    return RobustnessPrice(nominal, robust, on_cases)
