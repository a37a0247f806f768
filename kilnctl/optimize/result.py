"""Result of a ramp optimization: numbers, the comparison with the baseline, plots."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..figures import COLORS, Plotted, finish, limit_line
from .problem import RampProblem
from .verify import StartupMeasures

#: the objectives in a few words, for reports
OBJECTIVE_WORDS = {"peak": "the highest tooth stress, running load included",
                   "dynamic": "the start-up stress above the running load"}

__all__ = ["RampResult", "StageLog"]


@dataclass
class StageLog:
    """One continuation stage of the solve.

    Attributes
    ----------
    widths : dict
        Smoothing widths (``smooth_ds`` [m], ``smooth_v`` [rad/s], ``ramp_corner`` [s]).
    beta : float
        Smooth-maximum sharpness [1/stress scale].
    status : str
        IPOPT return status.
    iterations : int
        IPOPT iterations.
    objective : float
        Smooth objective at the stage's solution [stress scale].
    theta : list of float
        Profile numbers at the stage's solution.
    seconds : float
        Wall time of the stage [s].
    cases : list of str
        Cases the stage optimized over (the active scenarios).
    """

    widths: dict
    beta: float
    status: str
    iterations: int
    objective: float
    theta: list
    seconds: float
    cases: list = field(default_factory=list)


def _worst(measures: dict, kind: str) -> tuple[str, StartupMeasures]:
    name = max(measures, key=lambda k: measures[k].objective(kind))
    return name, measures[name]


@dataclass
class RampResult(Plotted):
    """An optimized start-up ramp, predicted on the smooth model and verified on the hybrid plant.

    Its figure (:meth:`plot`): reference, bending stress and current, the
    optimum against the baseline.

    Attributes
    ----------
    problem : RampProblem
        The problem solved.
    values : ndarray
        Optimal profile numbers (units of ``problem.profile.units``).
    predicted : dict of str to StartupMeasures
        Smooth-model measures per case.
    verified : dict of str to StartupMeasures
        Hybrid-plant measures per case (empty when not verified).
    baseline : dict of str to StartupMeasures
        Hybrid-plant measures of the paper's constant ramp ``params.ramp_rate``.
    solver_status : str
        IPOPT status of the last stage.
    iterations : int
        IPOPT iterations over all stages.
    stages : list of StageLog
        The continuation.
    transcription : str
        ``single_shooting`` or ``multiple_shooting``.
    solve_seconds, verify_seconds : float
        Wall times [s].
    tolerance : float
        Relative disagreement between prediction and verification above which
        the result is flagged [-].
    flags : list of str
        Everything the verification found wrong (empty when all is well).
    notes : list of str
        Facts worth knowing that are not errors (the peak is the running
        load; the baseline misses t_max ...).
    traces : dict
        Time series for plotting: ``smooth`` (dict of arrays), ``hybrid`` and
        ``baseline`` (Responses) of the worst verified case.
    """

    problem: RampProblem
    values: np.ndarray
    predicted: dict
    verified: dict
    baseline: dict
    solver_status: str
    iterations: int
    stages: list
    transcription: str
    solve_seconds: float
    verify_seconds: float
    tolerance: float
    flags: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    traces: dict = field(default_factory=dict, repr=False)
    active_cases: list = field(default_factory=list)
    phases: list = field(default_factory=list)

    # --- the headline numbers ---------------------------------------------------
    @property
    def objective_kind(self) -> str:
        """``'peak'`` or ``'dynamic'``."""
        return self.problem.objective

    @property
    def worst_predicted(self) -> tuple[str, StartupMeasures]:
        """(case, measures) of the case with the highest predicted objective."""
        return _worst(self.predicted, self.objective_kind)

    @property
    def worst_verified(self) -> tuple[str, StartupMeasures] | None:
        """(case, measures) of the case with the highest verified objective, or None."""
        return _worst(self.verified, self.objective_kind) if self.verified else None

    @property
    def worst_baseline(self) -> tuple[str, StartupMeasures] | None:
        """(case, measures) of the baseline's worst case, or None."""
        return _worst(self.baseline, self.objective_kind) if self.baseline else None

    @property
    def agreement(self) -> float | None:
        """Relative difference (predicted - verified)/verified of the worst-case objective [-]."""
        if not self.verified:
            return None
        p = self.worst_predicted[1].objective(self.objective_kind)
        v = self.worst_verified[1].objective(self.objective_kind)
        return (p - v) / v

    @property
    def ok(self) -> bool:
        """True when verified and nothing was flagged."""
        return bool(self.verified) and not self.flags

    def summary(self) -> dict:
        """JSON-ready summary (the keys of ``kilnctl optimize-ramp --json``).

        Returns
        -------
        dict
            ``profile``, ``ramp`` (the profile's numbers), ``objective``,
            ``peak_stress_predicted_Pa``, ``peak_stress_verified_Pa``,
            ``baseline_ramp`` [rpm/s], ``baseline_peak_stress_Pa``,
            ``reduction_pct`` (of the peak stress against the baseline),
            ``time_to_speed_s``, ``solver_status``, ``iterations``, and the
            dynamic stresses, running load, agreement, flags, timings and the
            per-case table.
        """
        prob = self.problem
        kind = self.objective_kind
        _, wp = self.worst_predicted
        wv = self.worst_verified
        wb = self.worst_baseline

        def peak(m, k="peak"):
            return None if m is None else m[1].objective(k)

        out = {
            "profile": prob.profile.label,
            "ramp": prob.profile.describe(self.values, prob.params.omega_ref),
            "objective": kind,
            "t_max_s": prob.t_max,
            "horizon_s": prob.horizon,
            "robust": prob.robust,
            "peak_stress_predicted_Pa": max(m.peak_stress_Pa for m in self.predicted.values()),
            "peak_stress_verified_Pa": None if wv is None else max(m.peak_stress_Pa for m in self.verified.values()),
            "dynamic_stress_predicted_Pa": max(m.peak_dynamic_stress_Pa for m in self.predicted.values()),
            "dynamic_stress_verified_Pa": None if wv is None else
            max(m.peak_dynamic_stress_Pa for m in self.verified.values()),
            "running_stress_Pa": None if wv is None else wv[1].running_stress_Pa,
            "baseline_ramp": prob.params.ramp_rate,
            "baseline_peak_stress_Pa": None if wb is None else max(m.peak_stress_Pa for m in self.baseline.values()),
            "baseline_dynamic_stress_Pa": None if wb is None else
            max(m.peak_dynamic_stress_Pa for m in self.baseline.values()),
            "reduction_pct": None,
            "objective_reduction_pct": None,
            "time_to_speed_s": None if wv is None else
            max((m.time_to_speed_s if m.time_to_speed_s is not None else float("inf"))
                for m in self.verified.values()),
            "agreement_pct": None if self.agreement is None else 100.0 * self.agreement,
            "tolerance_pct": 100.0 * self.tolerance,
            "solver_status": self.solver_status,
            "iterations": self.iterations,
            "transcription": self.transcription,
            "solve_time_s": self.solve_seconds,
            "verify_time_s": self.verify_seconds,
            "active_cases": list(self.active_cases),
            "phases": list(self.phases),
            "flags": list(self.flags),
            "notes": list(self.notes),
            "cases": {name: {"predicted": self.predicted[name].as_dict(),
                             "verified": self.verified[name].as_dict() if name in self.verified else None,
                             "baseline": self.baseline[name].as_dict() if name in self.baseline else None}
                      for name in self.predicted},
        }
        if wv is not None and wb is not None:
            out["reduction_pct"] = 100.0 * (1 - out["peak_stress_verified_Pa"] / out["baseline_peak_stress_Pa"])
            out["objective_reduction_pct"] = 100.0 * (1 - peak(wv, kind) / peak(wb, kind))
        if out["time_to_speed_s"] == float("inf"):
            out["time_to_speed_s"] = None
        return out

    def table(self) -> str:
        """Plain-text report: predicted and verified side by side, against the baseline."""
        s = self.summary()
        prob = self.problem
        dyn_red = None if s["baseline_dynamic_stress_Pa"] is None else \
            100.0 * (1 - s["dynamic_stress_verified_Pa"] / s["baseline_dynamic_stress_Pa"])
        mpa = lambda v: "-" if v is None else f"{v / 1e6:8.2f}"  # noqa: E731
        rows = {"peak": f"  {'peak bending stress [MPa]':34s}{mpa(s['peak_stress_predicted_Pa']):>10s}"
                        f"{mpa(s['peak_stress_verified_Pa']):>10s}{mpa(s['baseline_peak_stress_Pa']):>10s}",
                "dynamic": f"  {'peak dynamic stress [MPa]':34s}{mpa(s['dynamic_stress_predicted_Pa']):>10s}"
                           f"{mpa(s['dynamic_stress_verified_Pa']):>10s}{mpa(s['baseline_dynamic_stress_Pa']):>10s}"}
        order = ("dynamic", "peak") if s["objective"] == "dynamic" else ("peak", "dynamic")
        lines = [f"start-up ramp, profile {s['profile']}, objective '{s['objective']}' "
                 f"({OBJECTIVE_WORDS[s['objective']]}), 95 % speed by t_max = {prob.t_max:g} s "
                 f"({'robust, ' + str(len(self.predicted)) + ' cases' if prob.robust else 'nominal'})",
                 f"  ramp: {_ramp_text(s['ramp'])}",
                 f"  {'':34s}{'predicted':>10s}{'verified':>10s}{'baseline':>10s}",
                 *(rows[k] for k in order)]
        if s["reduction_pct"] is not None:
            changes = {"peak": f"peak stress {_change(s['reduction_pct'])}",
                       "dynamic": f"dynamic stress {_change(dyn_red)}"}
            lines.append(f"  against the baseline ramp {s['baseline_ramp']:g} rpm/s: "
                         + ", ".join(changes[k] for k in order))
        if s["running_stress_Pa"] is not None:
            lines.append(f"  running load (burden at its angle): {s['running_stress_Pa'] / 1e6:.2f} MPa")
        tts = s["time_to_speed_s"]
        lines.append(f"  time to 95 % speed: {'not reached' if tts is None else f'{tts:.2f} s'}")
        if s["agreement_pct"] is not None:
            lines.append(f"  predicted vs verified: {s['agreement_pct']:+.2f} % (tolerance {s['tolerance_pct']:g} %)")
        lines.append(f"  IPOPT: {s['solver_status']}, {s['iterations']} iterations, {s['solve_time_s']:.1f} s "
                     f"({s['transcription']}); verification {s['verify_time_s']:.1f} s")
        for f in self.flags:
            lines.append(f"  FLAG: {f}")
        for n in self.notes:
            lines.append(f"  note: {n}")
        return "\n".join(lines)

    def headline(self) -> str:
        """One plain sentence: what the ramp changes in the objective, and what no ramp changes.

        Returns
        -------
        str
        """
        s = self.summary()
        rate = s["baseline_ramp"]
        mpa = lambda v: f"{v / 1e6:.1f} MPa"  # noqa: E731
        if s["dynamic_stress_verified_Pa"] is None or s["baseline_dynamic_stress_Pa"] is None:
            return f"{s['profile']} ramp found ({s['solver_status']}), not verified on the hybrid plant"
        dyn = 100.0 * (1 - s["dynamic_stress_verified_Pa"] / s["baseline_dynamic_stress_Pa"])
        peak = s["reduction_pct"]
        base = f"with the {rate:g} rpm/s ramp"
        first_is_dyn = self.objective_kind == "dynamic"
        dyn_text = (f"start-up (dynamic) stress {mpa(s['dynamic_stress_verified_Pa'])} against "
                    f"{mpa(s['baseline_dynamic_stress_Pa'])}{' ' + base if first_is_dyn or abs(peak) < 0.05 else ''} "
                    f"({_change(dyn)})")
        if abs(peak) < 0.05:
            peak_text = (f"the peak stress, {mpa(s['peak_stress_verified_Pa'])}, is the same with both ramps: "
                         "it is the running load of the burden, which no ramp changes")
        else:
            peak_text = (f"peak stress {mpa(s['peak_stress_verified_Pa'])} against "
                         f"{mpa(s['baseline_peak_stress_Pa'])}{'' if first_is_dyn else ' ' + base} ({_change(peak)})")
        first, second = (dyn_text, peak_text) if first_is_dyn else (peak_text, dyn_text)
        name = _profile_name(s["profile"])
        return f"{name[0].upper()}{name[1:]} ramp: {first}; {second}"

    figsize = (10, 8.5)

    def _draw(self, fig):
        ax = fig.subplots(3, 1, sharex=True)
        hyb, base, sm = self.traces.get("hybrid"), self.traces.get("baseline"), self.traces.get("smooth")
        prob = self.problem
        rate = prob.params.ramp_rate
        if base is not None:
            ax[0].plot(base.t, base.outputs["speed_ref_rpm"], color=COLORS["reference"], ls="--", lw=1,
                       label=f"baseline reference ({rate:g} rpm/s)")
            ax[1].plot(base.t, base.outputs["sigma"] / 1e6, color=COLORS["baseline"], lw=1,
                       label=f"baseline ramp {rate:g} rpm/s, hybrid plant")
            ax[2].plot(base.t, base.outputs["i_a"], color=COLORS["baseline"], lw=1, label=f"baseline ramp {rate:g} rpm/s")
        if hyb is not None:
            ax[0].plot(hyb.t, hyb.outputs["speed_ref_rpm"], color=COLORS["model"], label="optimized reference")
            ax[0].plot(hyb.t, hyb.outputs["speed_rpm"], color=COLORS["model2"], lw=1, label="motor speed (optimized)")
            ax[1].plot(hyb.t, hyb.outputs["sigma"] / 1e6, color=COLORS["final"], lw=1.2,
                       label="optimized ramp, hybrid plant")
            ax[2].plot(hyb.t, hyb.outputs["i_a"], color=COLORS["final"], lw=1.2, label="optimized ramp")
        if sm is not None:
            ax[1].plot(sm["t"], sm["sigma"] / 1e6, color=COLORS["model"], ls=":", lw=1.2,
                       label="optimized ramp, smooth model (prediction)")
        target = prob.speed_fraction * prob.params.omega_ref
        limit_line(ax[0], prob.t_max, f"t_max = {prob.t_max:g} s: the speed must reach...", axis="v",
                   color="k", ls=":", lw=0.9)
        limit_line(ax[0], target, f"...{100 * prob.speed_fraction:g} % of the set point ({target:.0f} rpm) by then",
                   color="k", ls=":", lw=0.6)
        s = self.summary()
        if s["running_stress_Pa"] is not None:
            limit_line(ax[1], s["running_stress_Pa"] / 1e6, f"running load of the burden "
                       f"({s['running_stress_Pa'] / 1e6:.1f} MPa): no ramp changes it", color="0.3", ls="-.", lw=0.8)
        limit_line(ax[2], prob.params.I_max, f"current limit I_max = {prob.params.I_max:g} A")
        ax[0].set_ylabel("speed [rpm]")
        ax[1].set_ylabel("tooth bending stress [MPa]")
        ax[2].set_ylabel("armature current [A]")
        ax[2].set_xlabel("time [s]")
        ax[2].set_ylim(0, 1.1 * prob.params.I_max)
        for a in ax:
            a.grid(True, alpha=0.3)
            a.legend(loc="lower right", fontsize=8)
        ax[1].set_title("the spikes are backlash impacts as the pinion takes up the gap; "
                        "dynamic stress = stress minus the running load", fontsize=9)
        return finish(fig, self.headline().replace("; ", ";\n", 1), width=150)


def _profile_name(label: str) -> str:
    """'S-curve', 'constant-rate', '3-segment' for the profile labels 'scurve', 'constant', 'pwl:3'."""
    if label.startswith("pwl:"):
        return f"{label[4:]}-segment"
    return {"scurve": "S-curve", "constant": "constant-rate"}.get(label, label)


def _change(pct: float) -> str:
    """'46.7 % lower', '3.0 % higher', 'unchanged'."""
    if abs(pct) < 0.05:
        return "unchanged"
    return f"{abs(pct):.1f} % {'lower' if pct > 0 else 'higher'}"


def _ramp_text(d: dict) -> str:
    if "rate_rpm_s" in d:
        return f"{d['rate_rpm_s']:.2f} rpm/s (reference at speed after {d['end_time_s']:.2f} s)"
    if "jerk_rpm_s2" in d:
        return (f"S-curve, acceleration {d['accel_rpm_s']:.2f} rpm/s (reached {d['accel_reached_rpm_s']:.2f}), "
                f"jerk {d['jerk_rpm_s2']:.2f} rpm/s^2, at speed after {d['end_time_s']:.2f} s")
    rates = ", ".join(f"{r:.1f}" for r in d["rates_rpm_s"])
    return f"piecewise-linear rates [{rates}] rpm/s, at speed after {d['end_time_s']:.2f} s"
