"""Timing of the start-up ramp optimization (issue 5: under 10 s constant, under 60 s robust S-curve).

Cases, each solved from scratch in this process (model structures built
inside the timing, as a user's first call would):

constant        nominal problem, paper's constant ramp, t_max 10 s (median of 3)
scurve          nominal problem, S-curve (1 run)
robust_scurve   S-curve, worst case over the 8 corners of the paper's ranges plus nominal (1 run)

and two references for what the time buys:

sensitivities   one objective + gradient evaluation: the hand-written sensitivity equations
                (kilnctl.optimize.sensitivity) against CasADi's own CVODES forward sensitivities
brute_force     the constant-ramp optimum by bisection on the hybrid plant alone (the optimum of the
                constant problem lies on the t_max constraint, so 1-d bisection finds it)

Prints a table and writes ``benchmarks/out/optimize_bench.json`` whole.  The
machine is shared: the load average at start and end is recorded with the
numbers.

Usage: ``python -m benchmarks.optimize_bench [--quick]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import casadi as ca
import numpy as np

from kilnctl import Parameters
from kilnctl.optimize import Profile, RampProblem, default_scenarios, optimize_ramp
from kilnctl.optimize.model import SmoothStartup
from kilnctl.optimize.sensitivity import SensitivityRun
from kilnctl.optimize.transcription import TimeGrid, objective_quadrature
from kilnctl.optimize.verify import measure_hybrid
from kilnctl.response import write_atomic
from kilnctl.simulate import resolve_gains

OUT = Path(__file__).resolve().parent / "out" / "optimize_bench.json"
T_MAX = 10.0
GOALS = {"constant": 10.0, "robust_scurve": 60.0}


def _solve(params, profile, robust=False):
    prob = RampProblem(params, profile=profile, t_max=T_MAX, scenarios=default_scenarios() if robust else ())
    t0 = time.perf_counter()
    res = optimize_ramp(prob)
    wall = time.perf_counter() - t0
    s = res.summary()
    return {"wall_s": wall, "solve_s": res.solve_seconds, "verify_s": res.verify_seconds,
            "iterations": res.iterations, "status": res.solver_status, "ramp": s["ramp"],
            "peak_verified_MPa": s["peak_stress_verified_Pa"] / 1e6,
            "dynamic_verified_MPa": s["dynamic_stress_verified_Pa"] / 1e6,
            "agreement_pct": s["agreement_pct"], "flags": res.flags, "active_cases": res.active_cases}


def _sensitivities(params):
    """One value + gradient of the speed at t_max and the objective integrals: hand-written vs CasADi."""
    prof = Profile.parse("constant")
    model = SmoothStartup(prof, params)
    grid = TimeGrid.make(T_MAX, T_MAX + 15.0, 1e-2)
    widths = {"smooth_ds": 1e-6, "smooth_v": 1e-4, "ramp_corner": 0.05}
    q, pq = objective_quadrature(model)
    rate = 150.0  # rpm/s: the impact sets the peak here, so the gradients are well away from zero
    plain = model.run(params, [rate], widths, grid.t)
    inv = 1.0 / np.max(np.abs(plain["sigma"]))
    pqv = [100.0, 1.0, np.max(np.abs(plain["sigma_dyn"])) * inv, inv]  # shifts at the sampled peaks
    run = SensitivityRun(model, grid.t, (q, pq), rtol=1e-8, atol=1e-8)
    run(params, [rate], widths, pqv)
    t0 = time.perf_counter()
    mine = run(params, [rate], widths, pqv)
    t_mine = time.perf_counter() - t0
    th = ca.MX.sym("th")
    F = model.integrator(0.0, grid.t, ("objective", q, pq))
    r = F(x0=model.x0(params, th, widths), p=ca.vertcat(model.param_vector(params), pqv))
    out = ca.vertcat(r["qf"][:, -1], model.output_map(grid.n)(r["xf"], grid.t, model.param_vector(params))[4, grid.k_tmax])
    G = ca.Function("G", [th], [out, ca.jacobian(out, th)])
    G(rate)
    t0 = time.perf_counter()
    val, jac = G(rate)
    t_casadi = time.perf_counter() - t0
    # the objective integrals' gradients (the speed derivative is tiny at this rate, already at speed by
    # t_max: there CasADi's run at rtol 1e-8 is 11 % off the rtol 1e-10 value, the hand-written one 0.01 %)
    ref = mine["dQ"][:, 0]
    err = float(np.max(np.abs(np.asarray(jac).ravel()[:2] - ref) / np.abs(ref)))
    return {"hand_written_s": t_mine, "casadi_cvodes_s": t_casadi, "ratio": t_casadi / t_mine,
            "max_rel_difference": err}


def _brute_force(params):
    prof = Profile.parse("constant")
    horizon = T_MAX + 15.0
    t0 = time.perf_counter()
    lo, hi, n = 20.0, 200.0, 0
    while hi - lo > 1e-3 * hi:
        mid = 0.5 * (lo + hi)
        n += 1
        tts = measure_hybrid(params, prof, [mid], horizon)[0].time_to_speed_s
        lo, hi = (mid, hi) if (tts is None or tts > T_MAX) else (lo, mid)
    return {"wall_s": time.perf_counter() - t0, "runs": n, "rate_rpm_s": hi}


def main(argv=None) -> int:
    """Run the cases, print the table, write the JSON; return 0.

    Parameters
    ----------
    argv : list of str, optional
        ``--quick``: one repeat of the constant case, no robust case.

    Returns
    -------
    int
    """
    ap = argparse.ArgumentParser(prog="python -m benchmarks.optimize_bench")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    params = resolve_gains(Parameters())
    res = {"machine": {"cpus": os.cpu_count(), "python": platform.python_version(), "casadi": ca.__version__,
                       "load_avg_start": load0}}
    reps = [_solve(params, "constant") for _ in range(1 if args.quick else 3)]
    res["constant"] = dict(reps[-1], wall_s=statistics.median(r["wall_s"] for r in reps),
                           solve_s=statistics.median(r["solve_s"] for r in reps),
                           repeats=[r["wall_s"] for r in reps])
    res["scurve"] = _solve(params, "scurve")
    if not args.quick:
        res["robust_scurve"] = _solve(params, "scurve", robust=True)
    res["sensitivities"] = _sensitivities(params)
    res["brute_force"] = _brute_force(params)
    res["machine"]["load_avg_end"] = os.getloadavg()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    write_atomic(OUT, json.dumps(res, indent=2, default=float))
    print(f"ramp optimization on {res['machine']['cpus']} cores (load average {load0[0]:.1f} at start, "
          f"{res['machine']['load_avg_end'][0]:.1f} at end)")
    print(f"{'case':16s}{'wall [s]':>10s}{'solve [s]':>11s}{'iters':>7s}{'goal [s]':>10s}  result")
    for case in ("constant", "scurve", "robust_scurve"):
        if case in res:
            r = res[case]
            goal = GOALS.get(case)
            print(f"{case:16s}{r['wall_s']:10.1f}{r['solve_s']:11.1f}{r['iterations']:7d}"
                  f"{'-' if goal is None else f'{goal:g}':>10s}  dynamic {r['dynamic_verified_MPa']:.1f} MPa, "
                  f"peak {r['peak_verified_MPa']:.1f} MPa, {r['status']}")
    s = res["sensitivities"]
    print(f"one value + gradient: hand-written sensitivities {s['hand_written_s']:.3f} s, CasADi CVODES "
          f"{s['casadi_cvodes_s']:.3f} s ({s['ratio']:.1f}x); objective gradients agree to {s['max_rel_difference']:.1e}")
    b = res["brute_force"]
    print(f"constant ramp by bisection on the hybrid plant: {b['rate_rpm_s']:.2f} rpm/s in {b['wall_s']:.2f} s "
          f"({b['runs']} runs); optimizer: {res['constant']['ramp']['rate_rpm_s']:.2f} rpm/s")
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
