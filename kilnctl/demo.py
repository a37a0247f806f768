"""The main job behind ``make demo``: design, verify, optimize, diagnose, close the loop, with figures.

Run as ``python -m kilnctl.demo --out DIR``.  Each step prints what it found
and writes its figures into ``DIR``:

1. parameters (``params.toml``, the resolved set);
2. root-locus design of the speed-loop gains (``root_locus.png``,
   ``step_response.png``, ``param_locus.png``, ``design.png``);
3. the design verified on the nonlinear macro and micro models
   (``verify_macro.png``, the report ``verify/verify.html``,
   ``startup_micro.png``, ``startup_micro.csv``);
4. the start-up ramp that lowers the start-up (dynamic) gear stress
   (``ramp_optimization.png``, the report ``ramp/optimize_ramp.html``);
5. the diagnosis of the example measurement (``diagnose/diagnose.html``);
6. the loop closed on the structure the diagnosis learned
   (:mod:`kilnctl.close_loop`): the gains of step 2 checked and redesigned on
   its exact linearization, both verified on its hybrid plant, the ramp
   optimized on it (``close_the_loop.png``, ``close_the_loop.csv``,
   ``close_the_loop.md``).
"""

from __future__ import annotations

import argparse
import json
import sys
import textwrap
import time
from pathlib import Path

from .params import Parameters


#: the burden's modes (kilnctl.model.kiln) in words
_BURDEN_MODES = {"stick": "stuck to the shell", "slip_pos": "sliding on the shell wall",
                 "slip_neg": "sliding against the turning", "held": "held at its angle by kinetic friction"}


def _step(title: str) -> float:
    print(f"\n=== {title} " + "=" * max(0, 70 - len(title)))
    return time.perf_counter()


def _save(fig, path: Path) -> None:
    from .figures import save_figure

    save_figure(fig, path)
    import matplotlib.pyplot as plt

    plt.close(fig)
    print(f"  wrote {path}")


def main(argv=None) -> int:
    """Run the demonstration job.

    Parameters
    ----------
    argv : list of str, optional
        Command-line arguments (``--out DIR``).

    Returns
    -------
    int
        Exit code.
    """
    ap = argparse.ArgumentParser(prog="python -m kilnctl.demo")
    ap.add_argument("--out", default="out", help="output folder (created)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    # --- parameters ---------------------------------------------------------------
    _step("1. Parameters (the paper's Table 1 and documented assumptions)")
    params = Parameters()
    params.to_toml(out / "params.toml", overwrite=True)
    print(f"  inertia at the motor: J_stick = {params.J_stick:.2f} kg*m^2 (burden stuck to the shell), "
          f"J_slip = {params.J_slip:.2f} kg*m^2 (burden sliding); reduction motor to kiln n = {params.n:g} "
          f"(gearbox {params.n_r:.1f}); wrote {out / 'params.toml'}")

    # --- design -------------------------------------------------------------------
    t0 = _step("2. Root-locus design of the speed-loop PID (eq. 21)")
    from .design import design_pid

    design = design_pid(params)
    print("  " + design.summary().replace("\n", "\n  "))
    _save(design.locus().plot(), out / "root_locus.png")
    _save(design.step_responses().plot(), out / "step_response.png")
    _save(design.parameter_locus().plot(), out / "param_locus.png")
    _save(design.plot(), out / "design.png")
    print(f"  ({time.perf_counter() - t0:.1f} s)")

    # --- verification on the nonlinear plant -----------------------------------------
    t0 = _step("3. The design on the nonlinear plant (hybrid simulation)")
    from .verify import verify

    v = verify(params, "macro", 40.0)
    print("  " + str(v).replace("\n", "\n  "))
    _save(v.plot(), out / "verify_macro.png")
    from .pages import write_verify_report

    write_verify_report(v, out / "verify")
    print(f"  report: {out / 'verify' / 'verify.html'}")
    from .simulate import simulate

    micro = simulate(params, "micro", 60.0)
    s = micro.summary()
    burden = _BURDEN_MODES.get(s["burden_mode_final"], s["burden_mode_final"])
    print(f"  micro model (backlash and tooth stress), 60 s: peak current {s['peak_current_A']:.0f} A, final "
          f"{s['final_current_A']:.0f} A; peak tooth stress {s['peak_stress_Pa'] / 1e6:.1f} MPa, final "
          f"{s['final_stress_Pa'] / 1e6:.1f} MPa; {s['n_events']} mode switches, at the end the burden is {burden}; "
          f"simulated in {micro.info['wall_s'] * 1e3:.0f} ms")
    _save(micro.plot(), out / "startup_micro.png")
    micro.to_csv(out / "startup_micro.csv")
    print(f"  wrote {out / 'startup_micro.csv'}")
    (out / "summary.json").write_text(json.dumps({"design": design.to_dict(), "verify": v.to_dict(),
                                                  "micro": s}, indent=2, allow_nan=False, default=float))
    print(f"  ({time.perf_counter() - t0:.1f} s)")

    # --- start-up ramp optimization --------------------------------------------------
    t0 = _step("4. Start-up ramp that spares the girth gear (CasADi/IPOPT, verified on the hybrid plant)")
    from .demo_ramp import demo_ramp

    demo_ramp(out, params)
    print(f"  ({time.perf_counter() - t0:.1f} s)")

    # --- diagnosis of the example measurement -----------------------------------------
    t0 = _step("5. Model against measurement: where it fails, which effect is missing")
    from .measure.example import diagnose_example

    from .measure.diagnose import Diagnosis

    crit = Diagnosis()  # the example is diagnosed with the default criteria
    print("  Each catalogued effect is added to the calibrated model in turn. dBIC: change of the information "
          f"criterion\n  (negative favours the effect, below {-crit.min_delta_bic:g} counts); held-out gain: better "
          f"prediction of the samples not fitted\n  (above {crit.min_holdout_gain:g} % counts). An effect is "
          "supported when it passes both\n  (or, with the noise's colour modelled, its BIC still falls and the "
          "held-out part is worse by less than 2 standard\n  errors); the best one is added and the search repeats. "
          "At the end each added effect is tested again without it\n  (backward check), and against the rivals it "
          "beat by less than the threshold, each and the closest two together put\n  in its place (swap check).")

    diagnose_example(out, progress=lambda line: print("  " + line))
    print(f"  ({time.perf_counter() - t0:.1f} s)")

    # --- close the loop: redesign, verify and optimize on the model the measurement taught ---------
    t0 = _step("6. Close the loop: redesign, verify and optimize on the model the measurement taught")
    from .close_loop import close_the_loop
    from .measure import example_paths, load_setup

    rec_path, setup_path = example_paths()
    study = close_the_loop(out / "diagnose" / "diagnose.json", base=load_setup(setup_path).params,
                           rigid_gains=design.gains, record=rec_path.name)
    f = out / "diagnose" / "diagnose.json"
    print("  The gains of step 2 are checked on the exact linearization of the structure step 5 learned and redesigned\n"
          "  there; both are run on the hybrid plant with that structure, then the ramp is optimized on it. One by one:\n"
          f"    kilnctl design --model-from {f}\n    kilnctl verify --model-from {f} --model micro\n"
          f"    kilnctl optimize-ramp --model-from {f} --profile scurve --objective dynamic\n")
    for line in study.summary().split("\n"):
        print(textwrap.fill(line, 116, initial_indent="  ", subsequent_indent="    "))
    print()
    print("  " + study.to_text().replace("\n", "\n  "))
    study.to_csv(out / "close_the_loop.csv")
    (out / "close_the_loop.md").write_text(study.to_markdown())
    print(f"  wrote {out / 'close_the_loop.csv'}, {out / 'close_the_loop.md'}")
    _save(study.plot(), out / "close_the_loop.png")
    print(f"  ({time.perf_counter() - t0:.1f} s)")

    print(f"\nDone: figures and data in {out}/")
    return 0


if __name__ == "__main__":
    sys.exit(main())
