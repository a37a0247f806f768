"""Solving a ramp problem: smooth model, IPOPT with continuation, verification on the hybrid plant."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from ..errors import OptimizationError, ParameterError
from ..model.base import OPTION_NAMES
from ..simulate import resolve_gains
from .model import SmoothStartup
from .problem import RampProblem
from .result import RampResult, StageLog
from .transcription import TIE_BREAK, TimeGrid, build_nlp
from .verify import measure_arrays, measure_hybrid

__all__ = ["Stage", "DEFAULT_STAGES", "optimize_ramp", "RampSolveError", "VERIFY_RTOL", "ACCEPTED_STATUS"]

#: relative disagreement of predicted and verified objective above which a result is flagged [-]
VERIFY_RTOL = 0.03
#: a peak within this factor of the running stress is the running load, not a start-up transient [-]
RUNNING_LOAD_BAND = 1.03
#: an inactive scenario joins the optimization when its peak exceeds the active worst by this fraction [-]
SCREEN_RTOL = 0.005
#: output step of the prediction (as the hybrid verification's default) [s]
PREDICT_DT = 1e-3
#: IPOPT statuses taken as a solution
ACCEPTED_STATUS = ("Solve_Succeeded", "Solved_To_Acceptable_Level")
#: segment rates differing by this factor or more get a note explaining the jump [-]
JUMP_RATIO = 10.0
#: a constraint is reported violated when it exceeds its bound by more than this (scaled units) [-]
FEAS_TOL = 1e-4


@dataclass(frozen=True)
class Stage:
    """One continuation stage: smoothing widths and smooth-maximum sharpness.

    Attributes
    ----------
    smooth_ds : float
        Backlash smoothing width [m].
    smooth_v : float
        Wall-friction smoothing width [rad/s].
    ramp_corner : float
        Rounding of the piecewise-linear reference's corners [s].
    beta : float
        Sharpness of the smooth maximum of the objective [1/stress scale]:
        the smooth peak exceeds the sampled one by at most log(n)/beta stress
        scales.
    """

    smooth_ds: float
    smooth_v: float
    ramp_corner: float
    beta: float

    @property
    def widths(self) -> dict:
        """The widths by state name."""
        return {"smooth_ds": self.smooth_ds, "smooth_v": self.smooth_v, "ramp_corner": self.ramp_corner}


#: default continuation: broad smoothing first, then the final widths of kilnctl.model.smooth
DEFAULT_STAGES = (
    Stage(smooth_ds=1e-5, smooth_v=1e-3, ramp_corner=0.2, beta=100.0),
    Stage(smooth_ds=1e-6, smooth_v=1e-4, ramp_corner=0.05, beta=1000.0),
)


class RampSolveError(OptimizationError):
    """The ramp optimization failed or is infeasible.

    Attributes
    ----------
    status : str
        IPOPT return status.
    constraint : str or None
        The most violated constraint at the solver's last point, by name.
    violation : float
        How far it is violated (scaled units: fraction of the limit or of omega_ref).
    iterations : int
        IPOPT iterations spent.
    """

    def __init__(self, message: str, status: str, constraint: str | None, violation: float, iterations: int):
        super().__init__(message)
        self.status = status
        self.constraint = constraint
        self.violation = violation
        self.iterations = iterations


def _resolved_cases(problem: RampProblem):
    cases = [(name, resolve_gains(p)) for name, p in problem.cases()]
    opts0 = {k: cases[0][1][k] for k in OPTION_NAMES}
    for name, p in cases[1:]:
        diff = [k for k in OPTION_NAMES if p[k] != opts0[k]]
        if diff:
            raise ParameterError(f"scenario {name!r} changes the option(s) {diff}: scenarios may change numbers only "
                                 "(one smooth model serves them all)")
    return cases


def _violation(nlp, w, p):
    g = nlp.g_function(w, p)[0]
    g = np.asarray(g).ravel()
    viol = np.maximum(g - nlp.ubg, nlp.lbg - g)
    j = int(np.argmax(viol))
    return (nlp.g_names[j], float(viol[j])) if viol[j] > FEAS_TOL else (None, float(max(viol[j], 0.0)))


def _solve_stages(problem, model, cases, grid, sigma_scale, theta_scale, theta, stages, iters0, *, transcription,
                  n_shooting, ipopt_options, progress=None):
    """Run the continuation on one set of cases; return (theta, stage logs, iterations, status)."""
    nlp = build_nlp(problem, model, cases, grid, sigma_scale, theta_scale, theta, transcription, n_shooting,
                    ipopt_options, guess_widths=stages[0].widths)
    if nlp.callback is not None:
        nlp.callback.progress = progress
    w = nlp.w0.copy()
    logs, iters, status = [], 0, "Not_Solved"
    for k_st, st in enumerate(stages):
        t0 = time.perf_counter()
        if progress is not None:
            progress(f"  {problem.objective} stress, {len(cases)} case(s): stage {k_st + 1} of {len(stages)} "
                     f"(smooth max sharpness {st.beta:g}) ...")
        theta_now = w[:nlp.n_theta] * nlp.theta_scale
        runs = [model.run(cp, theta_now, st.widths, grid.t) for _, cp in cases]
        c_s, c_d = (max(float(np.max(np.abs(r[k]))) for r in runs) / sigma_scale for k in ("sigma", "sigma_dyn"))
        p = nlp.parameters(st.beta, c_s, c_d, st.widths)
        if k_st == 0 and len(cases) > 1:  # the epigraph variable starts just above every case
            w[nlp.n_theta] = (c_s + TIE_BREAK * c_d if problem.objective == "peak" else c_d) + 0.05
        try:
            sol = nlp.solver(x0=w, lbx=nlp.lbw, ubx=nlp.ubw, lbg=nlp.lbg, ubg=nlp.ubg, p=p)
        except RuntimeError as exc:  # CasADi reports a Ctrl-C inside IPOPT as a RuntimeError naming it
            if getattr(nlp.callback, "interrupted", False) or "KeyboardInterrupt" in str(exc):
                raise KeyboardInterrupt from None
            raise
        if getattr(nlp.callback, "interrupted", False):
            raise KeyboardInterrupt  # Ctrl-C inside an evaluation, which CasADi reported as a failed one
        stats = nlp.solver.stats()
        status = stats.get("return_status", "unknown")
        n_it = int(stats.get("iter_count", 0))
        iters += n_it
        if progress is not None:
            progress(f"  ... {status} after {n_it} iterations, {time.perf_counter() - t0:.1f} s")
        w_new = np.asarray(sol["x"]).ravel()
        if status not in ACCEPTED_STATUS:
            cname, viol = _violation(nlp, w_new, p)
            where = f"; most violated constraint: {cname} (by {viol:.3g})" if cname else \
                "; no constraint is violated at the last point (the solver stalled)"
            raise RampSolveError(
                f"ramp optimization failed: IPOPT returned {status} after {iters0 + iters} iterations at the stage "
                f"with smoothing {st.widths}{where}", status, cname, viol, iters0 + iters)
        w = w_new
        logs.append(StageLog(st.widths, st.beta, status, n_it, float(sol["f"]),
                             list(w[:nlp.n_theta] * nlp.theta_scale), time.perf_counter() - t0,
                             [name for name, _ in cases]))
    return w[:nlp.n_theta] * nlp.theta_scale, logs, iters, status


def _case_numbers(problem, model, cp, theta, widths, grid):
    """Sampled peaks and constraint ratios of one case on the grid (a cheap run without sensitivities)."""
    r = model.run(cp, theta, widths, grid.t)
    last = grid.t >= grid.t[-1] - 5.0
    return {"sigma": float(np.max(np.abs(r["sigma"]))), "sigma_dyn": float(np.max(np.abs(r["sigma_dyn"]))),
            "running": float(np.mean(r["sigma"][last])),
            "current": float(np.max(np.abs(r["i_a"]))) / cp.I_max, "voltage": float(np.max(np.abs(r["e_a"]))) / cp.V_max,
            "speed": float(r["speed_rpm"][grid.k_tmax]) / cp.omega_ref}


def _initial_active(problem, model, cases, theta, widths, grid) -> list[int]:
    """Cases worst at the starting point: nominal, highest stresses, highest current and voltage, slowest."""
    nums = [_case_numbers(problem, model, cp, theta, widths, grid) for _, cp in cases]
    pick = {0} if cases[0][0] == "nominal" else set()
    keys = ["sigma_dyn", "current", "voltage"] + (["sigma"] if problem.objective == "peak" else [])
    for k in keys:
        pick.add(int(np.argmax([n[k] for n in nums])))
    pick.add(int(np.argmin([n["speed"] for n in nums])))
    return sorted(pick)


def _screen(problem, model, cases, active, theta, widths, grid) -> list[int]:
    """Inactive cases that are worse than the active worst case or break a constraint at theta."""
    nums = [_case_numbers(problem, model, cp, theta, widths, grid) for _, cp in cases]
    keys = ["sigma_dyn"] + (["sigma"] if problem.objective == "peak" else [])
    worst = {k: max(nums[i][k] for i in active) for k in keys}
    out = []
    for i, n in enumerate(nums):
        if i in active:
            continue
        if any(n[k] > worst[k] * (1 + SCREEN_RTOL) for k in keys) or n["current"] > 1 or n["voltage"] > 1 \
                or n["speed"] < problem.speed_fraction * (1 - 1e-4):
            out.append(i)
    return out


def _infeasibility_precheck(problem: RampProblem, cases):
    """Raise at once for requests no ramp can meet (the reference itself must be at speed in time)."""
    hi = problem.bounds()[1]
    t_fast = problem.profile.end_time(hi, problem.params.omega_ref) * problem.speed_fraction
    if t_fast >= problem.t_max:
        raise RampSolveError(
            f"infeasible: even the fastest allowed {problem.profile.label} reference reaches "
            f"{problem.speed_fraction:g} of omega_ref only after {t_fast:.3g} s > t_max = {problem.t_max:g} s",
            "Not_Solved (precheck)", f"speed at t_max = {problem.t_max:g} s", float("nan"), 0)


def optimize_ramp(problem: RampProblem, *, transcription: str = "single_shooting", stages=DEFAULT_STAGES,
                  dt: float = 1e-2, n_shooting: int = 10, verify: bool = True, tolerance: float = VERIFY_RTOL,
                  initial=None, ipopt_options: dict | None = None, rtol: float = 1e-8,
                  atol: float = 1e-8, screen: bool = True, progress=None) -> RampResult:
    """Find the start-up ramp of least peak gear stress, and verify it on the hybrid plant.

    Parameters
    ----------
    problem : RampProblem
        What to optimize (profile, objective, constraints, scenarios).
    transcription : {'single_shooting', 'multiple_shooting'}, default 'single_shooting'
        How the dynamics enter the NLP (:mod:`kilnctl.optimize.transcription`).
    stages : sequence of Stage
        Continuation: each stage starts from the previous solution with
        sharper smoothing; the last stage's widths define the prediction.
    dt : float, default 1e-2
        Sampling step of the current and voltage constraints [s] (the
        objective is an integral, resolved by CVODES's own steps; the
        prediction is read on a 1 ms grid like the hybrid verification).
    n_shooting : int, default 10
        Intervals of multiple shooting.
    verify : bool, default True
        Re-simulate the optimum and the baseline ramp on the hybrid plant.
    tolerance : float, default 0.03
        Relative disagreement of predicted and verified objective that is
        flagged [-].
    initial : sequence of float, optional
        Starting profile numbers [profile units]; default
        :meth:`Profile.guess`.
    ipopt_options : dict, optional
        Extra IPOPT options (e.g. ``{"max_iter": 50}``).
    rtol, atol : float, default 1e-8, 1e-8
        CVODES tolerances of the smooth model during the solve (states and
        sensitivities scaled to order one); the prediction is re-run at
        rtol 1e-8.
    screen : bool, default True
        With scenarios: optimize over the cases that are worst at the start
        (nominal, highest stress, highest current, slowest), then check every
        case at the solution and add those that exceed the worst active case
        or a constraint, and re-solve (scenario generation; the optimum is
        that of all cases, at a fraction of the cost).  False: all cases at
        once.
    progress : callable, optional
        Called with a line of text at every continuation stage and every
        10 s during a solve (the CLI prints them on standard error).

    Returns
    -------
    RampResult

    Raises
    ------
    RampSolveError
        (an :class:`~kilnctl.errors.OptimizationError`) when IPOPT fails or
        the problem is infeasible; it carries the status, the violated
        constraint and the iteration count.
    ParameterError
        Bad options (transcription, dt, stages).
    """
    if not isinstance(problem, RampProblem):
        raise ParameterError(f"problem must be a RampProblem, not {type(problem).__name__}")
    if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not math.isfinite(dt) or not 0 < dt <= 0.05:
        raise ParameterError(f"dt = {dt!r} must be a step in (0, 0.05] s")
    stages = tuple(stages)
    if not stages or not all(isinstance(s, Stage) for s in stages):
        raise ParameterError("stages must be a non-empty sequence of Stage")
    t_start = time.perf_counter()
    prof = problem.profile
    cases = _resolved_cases(problem)
    _infeasibility_precheck(problem, cases)
    model = SmoothStartup(prof, cases[0][1], rtol=rtol, atol=atol, effects=problem.effects)
    grid = TimeGrid.make(problem.t_max, problem.horizon, dt)
    lb, ub = problem.bounds()
    theta0 = np.clip(prof.guess(problem.params.omega_ref, problem.t_max, problem.speed_fraction)
                     if initial is None else np.asarray(initial, dtype=float), lb, ub)
    if theta0.shape != (len(prof.names),):
        raise ParameterError(f"initial must have {len(prof.names)} numbers ({', '.join(prof.names)})")
    theta_scale = theta0.copy()
    fine = TimeGrid.make(problem.t_max, problem.horizon, PREDICT_DT).t
    run0 = model.run(cases[0][1], theta0, stages[0].widths, grid.t)
    sigma_scale = max(float(np.max(np.abs(run0["sigma"]))), 1e6)
    solver_args = dict(transcription=transcription, n_shooting=n_shooting, ipopt_options=ipopt_options,
                       progress=progress)
    phases = ["dynamic", "peak"] if problem.objective == "peak" else ["dynamic"]
    theta, logs, iters, status = theta0, [], 0, "Not_Solved"
    phase_log = []
    for k_ph, objective in enumerate(phases):
        sub = replace(problem, objective=objective)
        if len(cases) > 1 and screen:
            active = _initial_active(sub, model, cases, theta, stages[0].widths, grid)
        else:
            active = list(range(len(cases)))
        for _round in range(len(cases)):
            run_stages = stages if (_round == 0 and k_ph == 0) else stages[-1:]
            theta, lg, it, status = _solve_stages(sub, model, [cases[i] for i in active], grid, sigma_scale,
                                                  theta_scale, theta, run_stages, iters, **solver_args)
            logs += lg
            iters += it
            if len(active) == len(cases):
                break
            extra = _screen(sub, model, cases, active, theta, stages[-1].widths, grid)
            if not extra:
                break
            active = sorted(set(active) | set(extra))
        phase_log.append(objective)
        if objective == "dynamic" and len(phases) > 1:
            nums = [_case_numbers(problem, model, cp, theta, stages[-1].widths, grid) for _, cp in cases]
            if max(n["sigma"] for n in nums) <= RUNNING_LOAD_BAND * max(n["running"] for n in nums):
                break  # the peak is pinned at the running load: the least dynamic stress decides (lexicographic)
    values = np.asarray(theta, dtype=float)
    solve_seconds = time.perf_counter() - t_start
    # prediction: the smooth model at the last stage's widths, measured like the hybrid plant
    predicted, smooth_runs = {}, {}
    model.rtol, model.atol = 1e-8, 1e-9
    model._integrators.clear()
    for name, cp in cases:
        r = model.run(cp, values, stages[-1].widths, fine)
        smooth_runs[name] = r
        predicted[name] = measure_arrays(r["t"], r["sigma"], r["sigma_dyn"], r["i_a"], r["e_a"], r["speed_rpm"],
                                         problem.speed_fraction * cp.omega_ref)
    result = RampResult(problem, values, predicted, {}, {}, status, iters, logs, transcription, solve_seconds,
                        0.0, float(tolerance))
    result.active_cases = [cases[i][0] for i in active]
    result.phases = phase_log
    if verify:
        if progress is not None:
            progress(f"  solved in {solve_seconds:.1f} s; verifying on the hybrid plant ...")
        _verify(result, cases, smooth_runs)
    return result


def _verify(result: RampResult, cases, smooth_runs) -> None:
    """Fill in the hybrid-plant measures of the optimum and of the baseline, and the flags."""
    prob = result.problem
    t0 = time.perf_counter()
    kind = prob.objective
    base_profile = type(prob.profile)("constant", 1)
    responses, base_responses = {}, {}
    for name, cp in cases:
        result.verified[name], responses[name] = measure_hybrid(cp, prob.profile, result.values, prob.horizon,
                                                                prob.speed_fraction, effects=prob.effects)
        result.baseline[name], base_responses[name] = measure_hybrid(cp, base_profile, [prob.params.ramp_rate],
                                                                     prob.horizon, prob.speed_fraction,
                                                                     effects=prob.effects)
    result.verify_seconds = time.perf_counter() - t0
    worst = result.worst_verified[0]
    result.traces = {"smooth": smooth_runs[worst], "hybrid": responses[worst], "baseline": base_responses[worst],
                     "case": worst}
    flags = result.flags
    a = result.agreement
    if abs(a) > result.tolerance:
        flags.append(f"predicted {kind} stress differs from the hybrid plant's by {100 * a:+.1f} % "
                     f"(tolerance {100 * result.tolerance:g} %): the smoothing or the sampled peak misleads here")
    for name, m in result.verified.items():
        if m.time_to_speed_s is None or m.time_to_speed_s > prob.t_max * (1 + 1e-3):
            got = "never" if m.time_to_speed_s is None else f"after {m.time_to_speed_s:.3f} s"
            flags.append(f"{name}: the hybrid plant reaches {prob.speed_fraction:g} of omega_ref {got}, "
                         f"t_max = {prob.t_max:g} s")
        if m.limit_events:
            flags.append(f"{name}: a drive limit acted {m.limit_events} time(s) on the hybrid plant "
                         f"(peak current {m.peak_current_A:.0f} A, voltage {m.peak_voltage_V:.0f} V)")
    def which(names, of):
        names = list(names)
        if len(of) == 1:
            return ""
        if len(names) == len(of):
            return f" in all {len(of)} cases"
        return f" in {len(names)} of {len(of)} cases ({', '.join(names)})"

    late = [n for n, m in result.baseline.items() if m.time_to_speed_s is None or m.time_to_speed_s > prob.t_max]
    if late:
        result.notes.append(f"the baseline ramp {prob.params.ramp_rate:g} rpm/s itself misses t_max = "
                            f"{prob.t_max:g} s{which(late, result.baseline)}")
    pinned = [n for n, m in result.verified.items() if m.peak_stress_Pa <= RUNNING_LOAD_BAND * m.running_stress_Pa]
    if pinned:
        loads = ", ".join(f"{result.verified[n].running_stress_Pa / 1e6:.1f}" for n in pinned)
        result.notes.append(f"the peak stress is the running load of the burden ({loads} MPa mean)"
                            f"{which(pinned, result.verified)}: no ramp lowers it; the ramp sets only the dynamic "
                            "(start-up) stress")
    rates = np.asarray(result.values, dtype=float)
    if prob.profile.kind == "pwl" and len(rates) > 1 and rates.max() >= JUMP_RATIO * rates.min():
        slow, fast = int(np.argmin(rates)), int(np.argmax(rates))
        result.notes.append(
            f"the segment rates differ by a factor of {rates.max() / rates.min():.0f} ({rates.min():.3g} rpm/s in "
            f"segment {slow + 1}, {rates.max():.4g} rpm/s in segment {fast + 1}): the optimum creeps, then jumps. "
            "It is the optimum of the smooth model and the hybrid plant confirms its stresses above; if the drive "
            "must not do that, limit the rate (--max-rate, RampProblem(max_rate=...)) or use fewer segments")
    storm = [n for n, m in {**result.verified}.items() if m.engine.startswith("cvodes")]
    storm += [f"{n} (baseline)" for n, m in result.baseline.items() if m.engine.startswith("cvodes")]
    if storm:
        result.notes.append("verified with the CVODES engine where the default (compiled) engine stopped on an event "
                            f"storm: {', '.join(storm)}")
