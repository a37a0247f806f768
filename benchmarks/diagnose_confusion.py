"""Diagnosis on synthetic records with a hidden effect: the confusion table.

For every effect of the catalogue (and for nothing hidden, and for pairs of
effects), records are generated with :func:`kilnctl.measure.synthetic.make_record`
(magnitudes drawn from the plausible ranges, +-5 % mismatch in two or three
base parameters, white plus coloured noise), one per seed, and diagnosed from
the base model alone.  Printed:

* the confusion table: rows = hidden effect, columns = first-ranked supported
  effect (``none`` when nothing is supported);
* per row: true effect ranked first [%], selected exactly [%], median
  relative error of the effect's parameters, final current fit minus the fit
  of the true structure [points], wall time.

Run: ``python -m benchmarks.diagnose_confusion --seeds 5 --jobs 2``
(about a minute per record and core).  ``--json FILE`` saves every record's
outcome.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

PAIRS = (("second_motor", "kiln_unbalance"), ("viscous_drag", "speed_sensor_lag"))


def _one(job):
    """Generate and diagnose one record; return its outcome (runs in a worker)."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    from kilnctl import Parameters
    from kilnctl.measure.calibrate import Calibration
    from kilnctl.measure.diagnose import Diagnosis
    from kilnctl.measure.effects import CATALOGUE, effect_components
    from kilnctl.measure.synthetic import DEFAULT_GAINS, make_record

    hidden, seed, holdout = job
    setup = Parameters(DEFAULT_GAINS)
    t0 = time.perf_counter()
    m, truth = make_record(hidden, seed=seed)
    d = Diagnosis(setup, holdout=holdout).fit(m)
    first = d.ranking_[0].effect if d.ranking_ and d.ranking_[0].supported else "none"
    # parameters of the hidden effects, as recovered by the final model
    errs = {}
    for h in hidden:
        if h not in d.selected_:
            continue
        for fp in CATALOGUE[h].parameters:
            k = fp.name
            if k in truth["magnitudes"] and k in d.final_calibration_.values_:
                tv = truth["magnitudes"][k]
                errs[k] = abs(d.final_calibration_.values_[k] - tv) / abs(tv)
    # the true structure fitted the same way (base parameters + the hidden effects' ones)
    true_fit = None
    if hidden:
        model = "micro" if any(CATALOGUE[h].model == "micro" for h in hidden) else "macro"
        comps, p = effect_components(hidden, setup, model=model)
        free = list(d.calibrate) + [fp for h in hidden for fp in CATALOGUE[h].parameters]
        # an oracle: started from the plant's own values
        init = dict(truth["magnitudes"])
        init.update({k: v for k, v in truth["plant"].items() if k in d.calibrate})
        cal = Calibration(p, free, model=model, effects=comps, max_nfev=d.max_nfev).fit(m, init=init)
        true_fit = cal.fit_percent_["current_A"]
    else:
        true_fit = d.baseline_["current_A"]
    return {"hidden": list(hidden), "seed": seed, "first": first, "selected": list(d.selected_),
            "ranking": [(r.effect, r.delta_bic, r.holdout_gain, r.supported) for r in d.ranking_],
            "baseline_fit": d.baseline_["current_A"], "final_fit": d.final_["current_A"], "true_fit": true_fit,
            "param_rel_err": errs, "unexplained": d.unexplained_ is not None, "truth": _clean(truth),
            "wall_s": time.perf_counter() - t0}


#: records made differently from kilnctl.measure.synthetic: (name, expected effect or None, recipe)
FOREIGN = (
    ("J_m raised by 30 kg m^2 (not the second_motor component)", "second_motor",
     {"plant": {"J_m": 51.5}}),
    ("viscous friction on the motor shaft, B_m = 5 N m s/rad", "viscous_drag",
     {"plant": {"B_m": 5.0}}),
    ("unbalance 5x the plausible range, cos phase", "kiln_unbalance",
     {"effects": ("kiln_unbalance",), "plant": {"T_unb": 1.0e6, "phi_unb": 1.5707963}}),
    ("micro-model plant (coupling, stiff mesh, no backlash), 200 Hz, current gain +2 %, offset 5 A",
     None, {"model": "micro", "plant": {"delta_x": 0.0}, "fs": 200.0, "gain": 1.02, "offset": 5.0}),
    ("micro-model plant, no backlash, with a second motor of 60 kg m^2", "second_motor",
     {"model": "micro", "effects": ("second_motor",), "plant": {"delta_x": 0.0, "J_m2": 60.0}}),
    ("nothing hidden, slow coloured noise (tau 2 s, 8 A)", None, {"tau": 2.0, "coloured": 8.0}),
    ("torque law with low friction (mu_c 0.3, mu_s 0.36)", "torque_friction_law",
     {"plant": {"friction_law": "torque", "mu_c": 0.3, "mu_s": 0.36}}),
)


def _foreign(job):
    """Generate a record by hand (not with make_record) and diagnose it."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    from kilnctl import Parameters
    from kilnctl.measure import Measurement
    from kilnctl.measure.diagnose import Diagnosis
    from kilnctl.measure.synthetic import DEFAULT_GAINS, _ar1, _sampled
    from kilnctl.simulate import simulate

    (name, expected, recipe), seed = job
    setup = Parameters(DEFAULT_GAINS)
    rng = np.random.default_rng(seed)
    off = {"mu_c": 0.4 * (1 + 0.05 * rng.choice([-1, 1])), "m_v": 580e3 * (1 + 0.05 * rng.choice([-1, 1]))}
    off.update(recipe.get("plant", {}))
    plant = setup.replace(**off)
    fs, t_end = recipe.get("fs", 50.0), 30.0
    t = np.arange(0, t_end, 1 / fs)
    y = _sampled(simulate(plant, recipe.get("model", "macro"), t_end=t_end, effects=recipe.get("effects", ())), t)
    col, tau = recipe.get("coloured", 4.0), recipe.get("tau", 0.4)
    cur = (recipe.get("gain", 1.0) * y["i_a"] + recipe.get("offset", 0.0) + 4 * rng.standard_normal(t.size)
           + _ar1(rng, t.size, col, tau, 1 / fs))
    spd = y["speed_rpm"] + 0.3 * rng.standard_normal(t.size) + _ar1(rng, t.size, 0.3, tau, 1 / fs)
    m = Measurement.from_arrays(t, cur, spd, y["speed_ref_rpm"], source=name)
    t0 = time.perf_counter()
    d = Diagnosis(setup).fit(m)
    return {"name": name, "expected": expected, "selected": list(d.selected_),
            "first": d.ranking_[0].effect if d.ranking_ and d.ranking_[0].supported else None,
            "baseline_fit": d.baseline_["current_A"], "final_fit": d.final_["current_A"],
            "unexplained": (d.unexplained_ or {}).get("hint"), "caveats": list(d.caveats_),
            "wall_s": time.perf_counter() - t0}


def _guarded(fn_job):
    """Run one record; a failure is reported with its record instead of ending the whole benchmark."""
    fn, job = fn_job
    try:
        return fn(job)
    except Exception as exc:  # noqa: BLE001 - reported, and the table says how many records it holds
        return {"job": repr(job)[:200], "error": f"{type(exc).__name__}: {exc}"}


def _clean(obj):
    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    if isinstance(obj, np.str_):
        return str(obj)
    return obj


def main(argv=None) -> int:
    """Run the benchmark and print the confusion table; return the exit code."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.diagnose_confusion")
    ap.add_argument("--seeds", type=int, default=5, help="records per row (default 5)")
    ap.add_argument("--seed0", type=int, default=100, help="first seed (default 100)")
    ap.add_argument("--jobs", type=int, default=2, help="worker processes (default 2)")
    ap.add_argument("--effects", default="", help="comma-separated rows to run (default: all, none, pairs)")
    ap.add_argument("--no-pairs", action="store_true", help="skip the two-effect rows")
    ap.add_argument("--holdout", default="blocks", choices=("blocks", "tail"), help="hold-out kind")
    ap.add_argument("--json", metavar="FILE", help="save every record's outcome")
    ap.add_argument("--foreign", action="store_true",
                    help="instead: records generated differently (other implementations, magnitudes, sampling)")
    args = ap.parse_args(argv)
    if args.foreign:
        jobs = [(f, args.seed0 + k) for f in FOREIGN for k in range(args.seeds)]
        with ProcessPoolExecutor(max_workers=args.jobs) as ex:
            res = list(ex.map(_guarded, [(_foreign, j) for j in jobs]))
        failed = [r for r in res if "error" in r]
        res = [r for r in res if "error" not in r]
        for r in failed:
            print(f"FAILED: {r['job']}: {r['error']}")
        print(f"{'record':<72}{'expected':>22}  selected")
        for r in res:
            ok = (r["selected"] == [] if r["expected"] is None else r["first"] == r["expected"])
            print(f"{r['name'][:71]:<72}{str(r['expected']):>22}  {', '.join(r['selected']) or '-'}"
                  f"  {'OK ' if ok else 'MISS'} fit {r['baseline_fit']:.1f} -> {r['final_fit']:.1f} %"
                  + (f"  unexplained: {r['unexplained']}" if r["unexplained"] else "")
                  + "".join(f"\n      caution: {c}" for c in r.get("caveats", [])))
        if args.json:
            with open(args.json, "w") as fh:
                json.dump(res, fh, indent=1, default=float)
        return 0
    from kilnctl.measure.effects import CATALOGUE

    rows = [()] + [(e,) for e in CATALOGUE] + ([] if args.no_pairs else list(PAIRS))
    if args.effects:
        wanted = [tuple(x for x in s.split("+") if x and x != "none") for s in args.effects.split(",")]
        rows = wanted
    jobs = [(row, args.seed0 + k, args.holdout) for row in rows for k in range(args.seeds)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as ex:
        results = list(ex.map(_guarded, [(_one, j) for j in jobs]))
    for r in results:
        if "error" in r:
            print(f"FAILED: {r['job']}: {r['error']}")
    results = [r for r in results if "error" not in r]
    wall = time.perf_counter() - t0
    cols = ["none"] + list(CATALOGUE)
    short = {c: c[:8] for c in cols}
    print(f"diagnose confusion table: {args.seeds} records per row, hold-out '{args.holdout}', "
          f"{len(jobs)} records in {wall:.0f} s on {args.jobs} processes")
    print(f"{'hidden':<32}" + "".join(f"{short[c]:>9}" for c in cols)
          + f"{'first%':>8}{'exact%':>8}{'par err':>9}{'dfit':>7}{'s/rec':>7}")
    for row in rows:
        rs = [r for r in results if tuple(r["hidden"]) == row]
        if not rs:
            continue
        counts = {c: sum(r["first"] == c for r in rs) for c in cols}
        name = "+".join(row) or "none"
        if row:
            first_ok = sum(r["first"] in row for r in rs)
        else:
            first_ok = sum(r["first"] == "none" for r in rs)
        exact = sum(sorted(r["selected"]) == sorted(row) for r in rs)
        perr = [v for r in rs for v in r["param_rel_err"].values()]
        dfit = [r["final_fit"] - r["true_fit"] for r in rs if r["true_fit"] is not None]
        print(f"{name:<32}" + "".join(f"{counts[c]:>9d}" for c in cols)
              + f"{100 * first_ok / len(rs):>7.0f}%{100 * exact / len(rs):>7.0f}%"
              + (f"{100 * float(np.median(perr)):>8.1f}%" if perr else f"{'-':>9}")
              + (f"{float(np.median(dfit)):>+7.2f}" if dfit else f"{'-':>7}")
              + f"{float(np.mean([r['wall_s'] for r in rs])):>7.0f}")
    print("first% = true effect ranked first and supported (for 'none': nothing supported); exact% = selected set "
          "equals the hidden set; par err = median relative error of the hidden effect's parameters (phases "
          "excluded) when selected; dfit = median final current fit minus the fit of the true structure [points]")
    fits = [(r["baseline_fit"], r["final_fit"]) for r in results if r["hidden"]]
    print(f"current fit over records with a hidden effect: median {np.median([a for a, _ in fits]):.1f} % -> "
          f"{np.median([b for _, b in fits]):.1f} %")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1, default=float)
    return 0


if __name__ == "__main__":
    sys.exit(main())
