"""``kilnctl diagnose``: find which catalogued effect the model is missing, from a measured start-up.

Calibrates the base model, refits it with each effect of the catalogue, keeps
the effects that both lower BIC and predict a held-out part of the record
better (greedy), and reports how the error fell.  ``--report DIR`` writes
``diagnose.html`` (one self-contained page, figures embedded), ``diagnose.json``
and the figures as PNG.  Input files are never modified.
"""

from __future__ import annotations

import os
import sys

from . import print_json
from .common import add_strict_arg, check_report_dir, warn_implausible
from .compare_cmd import parse_names

__all__ = ["register", "run"]


def _positive_int(text: str) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"--workers {text!r}: give a whole number of processes, 1 or more")
    return value


def register(sub) -> None:
    """Add the ``diagnose`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``kilnctl`` parser.
    """
    p = sub.add_parser(
        "diagnose", help="find the physical effect the model is missing, from a measured start-up",
        description="Calibrate the base model on a measured record, refit it with each effect of the catalogue, "
                    "and keep the effects supported by both BIC and a held-out part of the record (greedy). "
                    "See docs/tutorial_diagnose.md.")
    p.add_argument("--data", required=True, metavar="FILE", help="measured record: CSV, .xlsx, .parquet or .mat "
                   "with time_s, current_A, speed_rpm [, speed_ref_rpm] (docs/measurements.md)")
    p.add_argument("--columns", metavar="MAP", help="the record's own column names, e.g. "
                   "current_A=I_arm,speed_rpm=n_mot,time_s=t; units in the header or here ('time_s=t [ms]') are "
                   "converted (default: the setup's [measurement] columns)")
    add_strict_arg(p)
    p.add_argument("--config", metavar="FILE", help="setup of the experiment (kilnctl TOML parameter file with an "
                   "optional [measurement] section); default: the paper's Table 1")
    p.add_argument("--model", choices=("macro", "micro"), default="macro", help="base model (default macro)")
    from ..measure.effects import DEFAULT_CALIBRATE

    p.add_argument("--calibrate", default=None, metavar="A,B",
                   help="base parameters to calibrate (default: the setup's [measurement] calibrate, else "
                        + ",".join(DEFAULT_CALIBRATE) + ")")
    p.add_argument("--workers", type=_positive_int, default=min(2, os.cpu_count() or 1), metavar="N",
                   help="processes refitting the candidates in parallel (default: 2, or 1 on one CPU); the result "
                        "does not depend on it")
    p.add_argument("--candidates", default=None, metavar="A,B", help="catalogue effects to try (default: all)")
    p.add_argument("--holdout", choices=("blocks", "tail"), default="blocks",
                   help="held-out part: interleaved blocks (default) or the last 30 %% of the record")
    p.add_argument("--report", metavar="DIR", help="write diagnose.html, diagnose.json and figures into DIR")
    p.add_argument("--json", action="store_true", help="print the diagnosis as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run the diagnosis and print or write it; return the exit code.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``diagnose`` arguments.

    Returns
    -------
    int
        0 on success.
    """
    from ..measure.diagnose import DEFAULT_CALIBRATE, Diagnosis
    from ..measure.io import load_setup, read_record, record_columns

    if args.report:
        check_report_dir(args)  # before the diagnosis, which takes tens of seconds
    setup = load_setup(args.config)
    warn_implausible(setup.params, args, where=args.config or "")
    calibrate = (parse_names(args.calibrate, "--calibrate") if args.calibrate
                 else tuple(setup.options.get("calibrate", DEFAULT_CALIBRATE)))
    candidates = (parse_names(args.candidates, "--candidates") if args.candidates
                  else setup.options.get("candidates"))
    data = read_record(args.data, setup.params, record_columns(setup, args.columns))
    d = Diagnosis(setup.params, calibrate, candidates, model=args.model, holdout=args.holdout,
                  t0=setup.options.get("t0_s"), workers=args.workers)
    progress = None if (args.quiet or args.json) else (lambda s: print(s, file=sys.stderr, flush=True))
    d.fit(data, progress=progress)
    written = d.report(args.report, protect=(args.data, args.config)) if args.report else []
    if args.json:
        print_json(d.to_dict())
        return 0
    print(d.summary())
    for note in data.notes:
        print(f"  record: {note}")
    for path in written:
        if path.suffix == ".html":
            print(f"  wrote {path} (and {len(written) - 1} more files)")
    return 0
