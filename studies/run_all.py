"""Run every study of the paper in turn and report how long each took.

Each study writes its figure, ``table.md`` and ``table.json`` into
``studies/out/<study>/`` and prints its table "paper reports / kilnctl gives";
the tables of the studies run are collected in ``studies/out/tables.md``
(the source of the tables in ``docs/validation.md``).

Run: ``python studies/run_all.py [study ...]`` (names without ``.py``; all by
default).  With ``--docs`` (all studies) it also renders ``docs/validation.md``
from ``studies/validation_template.md``, replacing each ``{{study}}`` with that
study's table, and copies the figures into ``docs/figures/``.
"""

from __future__ import annotations

import re
import runpy
import shutil
import sys
import time
from pathlib import Path

HERE = Path(__file__).parent
DOCS = HERE.parent / "docs"
STUDIES = ("fig04_friction", "fig09_pendulum", "fig10_startup", "fig11_12_backlash", "fig13_inertia", "fig14_mass")


def main(argv=None) -> int:
    """Run the named studies (all by default); return the exit code.

    Parameters
    ----------
    argv : list of str, optional
        Study names and ``--docs``; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        0 when every study ran, 2 for an unknown study name or ``--docs`` with a subset.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    docs = "--docs" in args
    names = [a for a in args if a != "--docs"] or list(STUDIES)
    if docs and names != list(STUDIES):
        print("--docs renders every study's table: run it without study names", file=sys.stderr)
        return 2
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
    tables = [(HERE / "out" / n / "table.md") for n in names]
    combined = "\n".join(t.read_text() for t in tables if t.exists())
    (HERE / "out").mkdir(exist_ok=True)
    (HERE / "out" / "tables.md").write_text(combined)
    print("\n=== run times " + "=" * 57)
    for name, t in times.items():
        print(f"{name:<20} {t:6.1f} s   -> studies/out/{name}/")
    print(f"{'total':<20} {sum(times.values()):6.1f} s")
    print("all tables: studies/out/tables.md")
    if docs:
        print(f"wrote {render_docs()}")
    return 0


def render_docs() -> Path:
    """Render docs/validation.md from the template and copy the study figures to docs/figures/.

    Returns
    -------
    Path
        The validation page written.
    """
    def table(m):
        text = (HERE / "out" / m.group(1) / "table.md").read_text()
        return text.split("\n", 2)[2].rstrip("\n")  # drop the title line: the page has its own headings

    page = re.sub(r"\{\{(\w+)\}\}", table, (HERE / "validation_template.md").read_text())
    (DOCS / "figures").mkdir(parents=True, exist_ok=True)
    for name in STUDIES:
        shutil.copyfile(HERE / "out" / name / f"{name}.png", DOCS / "figures" / f"{name}.png")
    out = DOCS / "validation.md"
    out.write_text(page)
    return out


if __name__ == "__main__":
    sys.exit(main())
