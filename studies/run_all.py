"""Run every study of the paper in turn and report how long each took.

Each study writes its figure, ``table.md`` and ``table.json`` into
``studies/out/<study>/`` and prints its table "paper reports / kilnctl gives".

Run: ``python studies/run_all.py [study ...]`` (names without ``.py``; all by default).
"""

from __future__ import annotations

import runpy
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent
STUDIES = ("fig04_friction", "fig09_pendulum", "fig10_startup", "fig11_12_backlash", "fig13_inertia", "fig14_mass")


def main(argv=None) -> int:
    """Run the named studies (all by default); return the exit code.

    Parameters
    ----------
    argv : list of str, optional
        Study names; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        0 when every study ran, 2 for an unknown study name.
    """
    names = list(sys.argv[1:] if argv is None else argv) or list(STUDIES)
    unknown = [n for n in names if n not in STUDIES]
    if unknown:
        print(f"unknown studies {unknown}; choose from {', '.join(STUDIES)}", file=sys.stderr)
        return 2
    times = {}
    for name in names:
        print(f"\n=== {name} " + "=" * (70 - len(name)))
        t0 = time.perf_counter()
        runpy.run_path(str(HERE / f"{name}.py"), run_name="__main__")
        times[name] = time.perf_counter() - t0
    print("\n=== run times " + "=" * 57)
    for name, t in times.items():
        print(f"{name:<20} {t:6.1f} s   -> studies/out/{name}/")
    print(f"{'total':<20} {sum(times.values()):6.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
