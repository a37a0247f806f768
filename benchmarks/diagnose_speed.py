"""Wall time of one diagnosis of a 40 s, 50 Hz start-up with all 8 candidates (issue 12, item 5).

The record is the shipped example (``kilnctl/data/example_record.csv``: a
plant with a second motor, friction and burden mass 5 % off, white plus
coloured noise); the diagnosis calibrates the default base set and tries
every catalogue candidate, as ``kilnctl diagnose`` does.  Printed: the wall
time of each repeat, their median, the process CPU time, the runs (model
simulations) each step took, and what was selected.

Usage: ``python -m benchmarks.diagnose_speed [--repeats 3] [--workers 2] [--profile FILE]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time


def _one(workers: int, profile: str | None):
    from kilnctl.measure import Diagnosis, example_paths, load_setup, read_csv

    rec_path, setup_path = example_paths()
    setup = load_setup(setup_path)
    rec = read_csv(rec_path, setup.params)
    d = Diagnosis(setup.params, workers=workers)
    w0, c0 = time.perf_counter(), _cpu()
    if profile:
        import cProfile

        pr = cProfile.Profile()
        pr.enable()
        d.fit(rec)
        pr.disable()
        pr.dump_stats(profile)
    else:
        d.fit(rec)
    return d, time.perf_counter() - w0, _cpu() - c0


def _cpu() -> float:
    """CPU time of this process and of its finished children (the pool's workers) [s]."""
    import resource

    me, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def main(argv=None) -> int:
    """Run the benchmark; return the exit code."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    ap = argparse.ArgumentParser(prog="python -m benchmarks.diagnose_speed")
    ap.add_argument("--repeats", type=int, default=3, help="diagnoses timed (default 3)")
    ap.add_argument("--workers", type=int, default=2, help="processes refitting candidates (default 2)")
    ap.add_argument("--profile", metavar="FILE", help="cProfile the first repeat into FILE")
    ap.add_argument("--json", metavar="FILE", help="save the timings")
    args = ap.parse_args(argv)
    walls, rows = [], []
    for k in range(args.repeats):
        d, wall, cpu = _one(args.workers, args.profile if k == 0 else None)
        walls.append(wall)
        row = {"wall_s": wall, "cpu_s": cpu, "load_average_1min": os.getloadavg()[0], "selected": list(d.selected_),
               "final_fit_current": d.final_["current_A"],
               "candidate_wall_s": {r.effect: r.wall_s for r in d.ranking_}}
        rows.append(row)
        print(f"repeat {k + 1}: {wall:.1f} s wall ({cpu:.1f} s CPU with the workers; machine load "
              f"{os.getloadavg()[0]:.1f}), selected "
              f"{', '.join(d.selected_) or 'nothing'}, final current fit {d.final_['current_A']:.1f} %")
        print("   first round, s per candidate: " + ", ".join(f"{r.effect} {r.wall_s:.1f}" for r in d.ranking_))
    print(f"median over {len(walls)}: {statistics.median(walls):.1f} s wall, {args.workers} worker(s), "
          f"{os.cpu_count()} CPUs")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"median_wall_s": statistics.median(walls), "workers": args.workers, "repeats": rows}, fh,
                      indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
