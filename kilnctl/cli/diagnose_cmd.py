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
from .common import Command, add_options, load_experiment_setup
from .compare_cmd import parse_names

__all__ = ["DiagnoseCommand", "register"]


def _positive_int(text: str) -> int:
    import argparse

    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"--workers {text!r}: give a whole number of processes, 1 or more")
    return value


class DiagnoseCommand(Command):
    """Calibrate the base model on a measured record, refit it with each effect of the catalogue, and keep the
    effects supported by both BIC and a held-out part of the record (greedy). See docs/tutorial_diagnose.md.
    """

    name = "diagnose"
    help = "find the physical effect the model is missing, from a measured start-up"

    def add_arguments(self, parser) -> None:
        from ..measure.effects import DEFAULT_CALIBRATE

        add_options(parser, data=True, columns=True, strict=True,
                    config="setup of the experiment (kilnctl TOML parameter file with an optional [measurement] "
                           "section); default: the paper's Table 1",
                    model="base model (default macro)")
        parser.add_argument("--calibrate", default=None, metavar="A,B",
                            help="base parameters to calibrate (default: the setup's [measurement] calibrate, else "
                                 + ",".join(DEFAULT_CALIBRATE) + ")")
        parser.add_argument("--workers", type=_positive_int, default=min(2, os.cpu_count() or 1), metavar="N",
                            help="processes refitting the candidates in parallel (default: 2, or 1 on one CPU); "
                                 "the result does not depend on it")
        parser.add_argument("--candidates", default=None, metavar="A,B",
                            help="catalogue effects to try (default: all)")
        parser.add_argument("--holdout", choices=("blocks", "tail"), default="blocks",
                            help="held-out part: interleaved blocks (default) or the last 30 %% of the record")
        add_options(parser, report="write diagnose.html, diagnose.json and figures into DIR",
                    json="print the diagnosis as JSON", quiet=True)

    def run(self, args) -> int:
        from ..measure.diagnose import DEFAULT_CALIBRATE, Diagnosis
        from ..measure.io import read_record, record_columns

        setup = load_experiment_setup(args)  # a bad --report is refused before the work
        calibrate = (parse_names(args.calibrate, "--calibrate") if args.calibrate
                     else tuple(setup.options.get("calibrate", DEFAULT_CALIBRATE)))
        candidates = (parse_names(args.candidates, "--candidates") if args.candidates
                      else setup.options.get("candidates"))
        data = read_record(args.data, setup.params, record_columns(setup, args.columns))
        d = Diagnosis(setup.params, calibrate, candidates, model=args.model, holdout=args.holdout,
                      t0=setup.options.get("t0_s"), workers=args.workers)
        progress = None if (args.quiet or args.json) else (lambda s: print(s, file=sys.stderr, flush=True))
        if progress is not None:
            # how the file was read, before the long search: a unit or column mix-up shows at once
            for note in data.notes:
                progress(f"record: {note}")
        d.fit(data, progress=progress)
        written = d.report(args.report, protect=(args.data, args.config)) if args.report else []
        if args.json:
            print_json(d.to_dict())  # with record_notes: how the file was read
            return 0
        print(d.summary())
        for note in data.notes:
            print(f"  record: {note}")
        for path in written:
            if path.suffix == ".html":
                print(f"  wrote {path} (and {len(written) - 1} more files)")
        return 0


register = DiagnoseCommand.register
