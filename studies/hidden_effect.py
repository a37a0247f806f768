"""Study: your model does not match your kiln -- compare, calibrate, diagnose, watch the error fall.

Walks the whole loop of ``docs/tutorial_diagnose.md`` on the shipped example
record (``kilnctl/data/example_record.csv``):

1. compare the model of the setup with the record: fit %, where it fails;
2. the paper's parametric friction study (Fig. 4) as a sweep, beside the
   least-squares calibration of mu_c, mu_s, m_v;
3. diagnose: which catalogued effect is missing;
4. the final comparison, and the report.

Run: ``python studies/hidden_effect.py [--out DIR]`` (default
``studies/out/hidden_effect``); takes a few minutes.
"""

from __future__ import annotations

import argparse
from importlib import resources
from pathlib import Path

from kilnctl.measure import Calibration, Diagnosis, compare, load_setup, read_csv, sweep


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="studies/out/hidden_effect", help="output folder")
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data_dir = resources.files("kilnctl") / "data"
    setup = load_setup(data_dir / "example_setup.toml")
    record = read_csv(data_dir / "example_record.csv", setup.params)

    # 1. the model as set up
    c0 = compare(record, setup.params)
    print("1. the setup's model against the record")
    print("\n".join(c0.summary_lines()))
    c0.plot().savefig(out / "1_compare_setup.png", dpi=100)

    # 2. the paper's friction study (Fig. 4) as a sweep, and the calibration
    rows = sweep(record, setup.params, {"mu_c": [0.3, 0.35, 0.4, 0.45], "mu_s": [0.45, 0.51, 0.6]})
    print("\n2. friction sweep (the paper's Fig. 4 study): fit % of the current")
    print(f"   {'mu_c':>5} {'mu_s':>5} {'fit I %':>8} {'final I [A]':>12}")
    for r in rows:
        if "error" in r:
            print(f"   {r['mu_c']:5.2f} {r['mu_s']:5.2f}   skipped: {r['error'][:60]}")
        else:
            print(f"   {r['mu_c']:5.2f} {r['mu_s']:5.2f} {r['fit_current_A']:8.1f} {r['final_current_A']:12.0f}")
    cal = Calibration(setup.params, setup.options.get("calibrate", ("mu_c", "mu_s", "m_v"))).fit(record)
    print("   least squares instead of the sweep:")
    print("   " + cal.summary().replace("\n", "\n   "))

    # 3. which effect is missing
    print("\n3. diagnosis")
    d = Diagnosis(setup.params, cal.names_).fit(record, progress=lambda s: print("   " + s))
    print(d.summary())
    files = d.report(out / "report")

    # 4. before and after
    print("\n4. before and after")
    print(f"   {'':<28}{'fit I %':>9}{'fit n %':>9}")
    for name, fit in (("setup's model", c0.fit), ("calibrated base", d.baseline_), ("diagnosed model", d.final_)):
        print(f"   {name:<28}{fit['current_A']:9.1f}{fit['speed_rpm']:9.2f}")
    print(f"   {d.headline()}")
    print(f"   report: {files[0]}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
