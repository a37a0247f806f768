"""Study: close the loop -- diagnose a record, redesign the gains on what it taught, verify, optimize the ramp.

On the shipped example record (``kilnctl/data/example_record.csv``, whose
diagnosis finds the paper's second motor):

1. diagnose the record (``kilnctl diagnose``): the learned structure and its
   calibrated values;
2. the rigid root-locus design, checked on the exact linearization of the
   learned structure, and the gains redesigned there (root locus of the
   learned model with the design region);
3. both designs verified on the learned hybrid plant (micro model plus the
   learned effects) with the paper's 74 rpm/s ramp;
4. the start-up ramp optimized on the learned structure with the redesigned
   gains and verified on the same hybrid plant.

Writes ``close_the_loop.png``, ``table.md``, ``table.csv`` and ``table.json``
into the output folder and prints the summary and the table.

Run: ``python studies/close_the_loop.py [--out DIR] [--from DIAGNOSE.json]``
(default ``studies/out/close_the_loop``; ``--from`` reuses a diagnosis of the
example, e.g. ``out/diagnose/diagnose.json`` of ``make demo``, and skips
step 1).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from kilnctl.close_loop import close_the_loop
from kilnctl.figures import save_figure
from kilnctl.measure import example_paths, load_setup
from kilnctl.measure.example import diagnose_example


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="studies/out/close_the_loop", help="output folder")
    ap.add_argument("--from", dest="source", metavar="DIAGNOSE.json",
                    help="a diagnosis of the example record to reuse (default: diagnose it now)")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_all = time.perf_counter()
    rec_path, setup_path = example_paths()
    source = args.source
    if source is None:
        print("1. diagnosis of the example record")
        t0 = time.perf_counter()
        diagnose_example(out, progress=lambda line: print("   " + line))
        source = out / "diagnose" / "diagnose.json"
        print(f"   ({time.perf_counter() - t0:.1f} s)")
    else:
        print(f"1. diagnosis of the example record: reused from {source}")

    t0 = time.perf_counter()
    study = close_the_loop(source, base=load_setup(setup_path).params, record=rec_path.name)
    print("\n2.-4. redesign, verification and ramp on the learned structure "
          f"({time.perf_counter() - t0:.1f} s)\n")
    print(study.summary())
    print()
    print(study.to_text())
    (out / "table.md").write_text(f"### Close the loop on {rec_path.name}\n\n" + study.to_markdown())
    study.to_csv(out / "table.csv")
    (out / "table.json").write_text(json.dumps(study.to_dict(), indent=2, allow_nan=False, default=float))
    save_figure(study.plot(), out / "close_the_loop.png")
    print(f"\nwrote {out / 'close_the_loop.png'}, {out / 'table.md'}, {out / 'table.csv'}, {out / 'table.json'}")
    print(f"total {time.perf_counter() - t_all:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
