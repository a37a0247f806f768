"""Sweep scaling: 1000 micro-model start-ups on 1 and 2 local workers, and a resume after an interruption.

Measures, in one run on this machine:

* the wall time of the whole sweep with 1 worker process and with 2 (each pool
  starts fresh, so the per-worker start-up -- imports, plant build, gain
  design -- is included, as a user meets it), and the speed-up;
* an interruption: the same sweep runs in a child process with a cache and is
  sent SIGINT (Ctrl-C) once part of it is done; the sweep is then run again
  and must compute only the missing points, and give the same table, bit for
  bit, as the uninterrupted run.

The machine's load average is recorded: other processes on the two cores make
the times (and the speed-up) worse than on an idle machine.

Run: ``python -m benchmarks.sweep_scaling [--n 1000] [--interrupt-at 0.4]``
(``--n 100`` for a quick check).  Results: printed, and written to
``benchmarks/out/sweep_scaling.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pandas as pd

from kilnctl.files import write_atomic
from kilnctl.sweep import LatinHypercube, LogUniform, Study, Uniform, code_fingerprint, run_sweep

OUT = Path(__file__).parent / "out" / "sweep_scaling.json"
T_END = 30.0  # s: a start-up with the slowest ramp (37 rpm/s) settles within it


def make_study(n: int) -> Study:
    """Return the benchmark sweep: a Latin hypercube of n micro-model start-ups.

    Parameters
    ----------
    n : int
        Number of start-ups.

    Returns
    -------
    Study
        Burden mass 240-974 t, backlash 0-16 mm, ramp constant 37-740 rpm/s
        (log-uniform): the paper's ranges (Figs. 11, 14, 15).
    """
    space = LatinHypercube({"m_v": Uniform(240e3, 974e3), "delta_x": Uniform(0.0, 0.016),
                            "ramp_rate": LogUniform(37.0, 740.0)}, n=n, seed=7)
    return Study(space, ["peak_stress_Pa", "peak_current_A", "n_events"], model="micro", t_end=T_END,
                 name=f"sweep_scaling_{n}")


def _child(n: int, cache: str) -> int:
    """Run the sweep with a cache until interrupted (the process the benchmark sends SIGINT to)."""
    # a process started in the background inherits SIGINT ignored: take Ctrl-C as a user's terminal gives it
    signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        run_sweep(make_study(n), workers=2, cache=cache, progress=False)
    except KeyboardInterrupt:
        return 130
    return 0


def _interrupt_and_resume(n: int, fraction: float, reference: pd.DataFrame) -> dict:
    # cache keys hash the model's sources: take them as they are now, as the child process will
    code_fingerprint.cache_clear()
    code = code_fingerprint()
    cache = Path(tempfile.mkdtemp(prefix="kilnctl-sweep-bench-"))
    cmd = [sys.executable, "-m", "benchmarks.sweep_scaling", "--child", str(cache), "--n", str(n)]
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, cwd=Path(__file__).resolve().parents[1])
    target = int(fraction * n)
    while proc.poll() is None and len(list(cache.rglob("[!.]*.json"))) < target:
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    code = proc.wait(timeout=120)
    t_first = time.perf_counter() - t0
    cached = len(list(cache.rglob("[!.]*.json")))
    code_fingerprint.cache_clear()
    res = run_sweep(make_study(n), workers=2, cache=cache, progress=True)
    cols = ["m_v", "delta_x", "ramp_rate", "peak_stress_Pa", "peak_current_A", "n_events"]
    identical = res.table[cols].equals(reference[cols])
    return {"child_exit_code": code, "points_cached_at_interruption": cached,
            "points_computed_on_resume": res.info["n_computed"], "points_read_from_cache": res.info["n_cached"],
            "resume_computed_only_missing": res.info["n_computed"] == n - cached,
            "interrupted_run_wall_s": t_first, "resume_wall_s": res.info["wall_s"],
            "resumed_table_identical_to_uninterrupted": bool(identical), "cache": str(cache),
            "sources_changed_during_the_run": code_fingerprint() != code}


def main(argv=None) -> dict:
    """Run the benchmark, print and write its results.

    Parameters
    ----------
    argv : list of str, optional
        ``--n N`` start-ups (default 1000), ``--interrupt-at F`` (fraction done
        when SIGINT is sent, default 0.4).

    Returns
    -------
    dict
        The results written to ``benchmarks/out/sweep_scaling.json``.
    """
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=1000)
    ap.add_argument("--interrupt-at", type=float, default=0.4)
    ap.add_argument("--child", metavar="CACHE", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        sys.exit(_child(args.n, args.child))
    st = make_study(args.n)
    st.parameter_sets()  # the gain design for the base kiln, done once in this process: not part of either timing
    load0 = os.getloadavg()
    runs, cpu = {}, {}
    for workers in (1, 2):
        c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        res = run_sweep(st, workers=workers, progress=True)
        c1 = resource.getrusage(resource.RUSAGE_CHILDREN)  # the pool's workers, reaped at its shutdown
        runs[workers] = res
        cpu[workers] = (c1.ru_utime + c1.ru_stime) - (c0.ru_utime + c0.ru_stime)
        print(f"{workers} worker(s): {res.info['wall_s']:.1f} s for {args.n} start-ups, workers' CPU "
              f"{cpu[workers]:.1f} s ({res.info['n_failed']} failed)", file=sys.stderr)
    same = runs[1].table.drop(columns="cached").equals(runs[2].table.drop(columns="cached"))
    resume = _interrupt_and_resume(args.n, args.interrupt_at, runs[2].table)
    w1, w2 = runs[1].info["wall_s"], runs[2].info["wall_s"]
    out = {
        "n_startups": args.n, "model": "micro", "t_end_s": T_END, "cores": os.cpu_count(),
        "load_average_1min_at_start": load0[0], "load_average_1min_at_end": os.getloadavg()[0],
        "wall_s_1_worker": w1, "wall_s_2_workers": w2, "speedup_1_to_2": w1 / w2,
        "ms_per_startup_1_worker": 1e3 * w1 / args.n, "ms_per_startup_2_workers": 1e3 * w2 / args.n,
        "worker_cpu_s_1_worker": cpu[1], "worker_cpu_s_2_workers": cpu[2],
        # share of the cores the workers actually got: 1.0 on an idle machine, less when others compete
        "cpu_share_1_worker": cpu[1] / w1, "cpu_share_2_workers": cpu[2] / (2 * w2),
        "tables_identical_1_vs_2_workers": bool(same), "n_failed": runs[2].info["n_failed"],
        "resume": resume,
    }
    write_atomic(OUT, json.dumps(out, indent=1))
    print(f"\nsweep scaling: {args.n} micro-model start-ups of {T_END:g} s, {os.cpu_count()} cores, "
          f"load average {load0[0]:.1f} at start, {out['load_average_1min_at_end']:.1f} at end")
    print(f"  1 worker    {w1:7.1f} s  ({out['ms_per_startup_1_worker']:.0f} ms per start-up; the worker got "
          f"{out['cpu_share_1_worker']:.0%} of a core)")
    print(f"  2 workers   {w2:7.1f} s  ({out['ms_per_startup_2_workers']:.0f} ms per start-up; each worker got "
          f"{out['cpu_share_2_workers']:.0%} of a core)  speed-up {out['speedup_1_to_2']:.2f}; same table: {same}")
    r = resume
    print(f"  interrupted after {r['points_cached_at_interruption']} points (exit code {r['child_exit_code']}); "
          f"resume computed {r['points_computed_on_resume']} and read {r['points_read_from_cache']} from the "
          f"cache; only the missing ones: {r['resume_computed_only_missing']}; same table as uninterrupted: "
          f"{r['resumed_table_identical_to_uninterrupted']}")
    print(f"  wrote {OUT}")
    return out


if __name__ == "__main__":
    main()
