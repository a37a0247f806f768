"""CPU time of the short model runs a calibration makes (issue 12, item 5: the per-run overhead).

Times ``kilnctl.measure.runner.run_model`` on the shipped example record (40 s at 50 Hz), the way
``Calibration`` calls it: the parameter set of the record's ramp with one value changed per run
(``Parameters.replace``).  Two sets of runs, after one warm-up run per structure (plant building and
compiling are not timed):

* ``base``: the base macro model, ``mu_c`` stepped over +-10 % (a few mode switches per run);
* ``catalogue``: the base model and every catalogue effect the macro model carries, in turn (from 4 to
  about 1000 mode switches per run: the speed-sensor lag keeps switching).

Printed: CPU time per run (this process only; the ``replace`` included) and mode switches per run.

Usage: ``python -m benchmarks.run_model_speed [--runs 200]``
"""

from __future__ import annotations

import argparse
import sys
import time


def _setup():
    from kilnctl.measure import CATALOGUE, example_paths, load_setup, read_csv
    from kilnctl.measure.effects import effect_components

    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    exp = rec.experiment(setup.params)
    base = setup.params.replace(ramp_rate=exp.ramp_rate, omega_ref=exp.omega_ref)
    structures = [((), base)]
    for key in CATALOGUE:
        try:
            structures.append(effect_components([key], base))
        except Exception:  # an effect of the micro model only (backlash)
            continue
    return rec, exp, base, structures


def _time(runs, rec, exp) -> tuple[float, float]:
    """CPU seconds per run and mode switches per run of ``runs``: (params, mu_c, effects), each run on
    ``params.replace(mu_c=mu_c)`` as a calibration's trial does."""
    from kilnctl.measure.runner import run_model

    events = 0
    c0 = time.process_time()
    for p, mu_c, effects in runs:
        events += len(run_model(p.replace(mu_c=mu_c), rec, exp, effects=effects).events)
    return (time.process_time() - c0) / len(runs), events / len(runs)


def main(argv=None) -> int:
    """Run the benchmark; return the exit code."""
    ap = argparse.ArgumentParser(prog="python -m benchmarks.run_model_speed")
    ap.add_argument("--runs", type=int, default=200, help="runs per set (default 200)")
    args = ap.parse_args(argv)
    from kilnctl.measure.runner import run_model

    rec, exp, base, structures = _setup()
    for effects, p in structures:
        run_model(p, rec, exp, effects=effects)  # build and compile outside the timing
    factors = [0.9 + 0.2 * k / max(1, args.runs - 1) for k in range(args.runs)]
    base_runs = [(base, min(base.mu_c * f, base.mu_s), ()) for f in factors]
    mix_runs = []
    for k, f in enumerate(factors):
        effects, p = structures[k % len(structures)]
        mix_runs.append((p, min(base.mu_c * f, base.mu_s), effects))
    for name, runs in (("base", base_runs), ("catalogue", mix_runs)):
        cpu, events = _time(runs, rec, exp)
        print(f"{name}: {len(runs)} runs, {1e3 * cpu:.2f} ms CPU per run, {events:.0f} mode switches per run")
    return 0


if __name__ == "__main__":
    sys.exit(main())
