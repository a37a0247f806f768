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
    args = ap.parse_args(argv)
    from kilnctl.measure.effects import CATALOGUE

    rows = [()] + [(e,) for e in CATALOGUE] + ([] if args.no_pairs else list(PAIRS))
    if args.effects:
        wanted = [tuple(x for x in s.split("+") if x and x != "none") for s in args.effects.split(",")]
        rows = wanted
    jobs = [(row, args.seed0 + k, args.holdout) for row in rows for k in range(args.seeds)]
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.jobs) as ex:
        results = list(ex.map(_one, jobs))
    wall = time.perf_counter() - t0
    cols = ["none"] + list(CATALOGUE)
    short = {c: c[:8] for c in cols}
    print(f"diagnose confusion table: {args.seeds} records per row, hold-out '{args.holdout}', "
          f"{len(jobs)} records in {wall:.0f} s on {args.jobs} processes")
    print(f"{'hidden':<32}" + "".join(f"{short[c]:>9}" for c in cols)
          + f"{'first%':>8}{'exact%':>8}{'par err':>9}{'dfit':>7}{'s/rec':>7}")
    for row in rows:
        rs = [r for r in results if tuple(r["hidden"]) == row]
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
