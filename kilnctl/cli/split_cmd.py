"""``kilnctl split-startups``: cut a long log of the plant into start-up records.

Finds each start-up from rest (by the speed reference, else by the rise of the
measured speed) and writes ``startup_01.csv`` ... into a new or empty folder,
all of them or none, in kilnctl's record format (s, A, rpm).  The log is only
read.
"""

from __future__ import annotations

from ..errors import ConfigFileError
from . import print_json
from .common import Command, add_options, check_folder_can_be_made

__all__ = ["SplitStartupsCommand", "register"]


class SplitStartupsCommand(Command):
    """Read a long log (CSV, .xlsx, .parquet or .mat; the record formats of docs/measurements.md), find every
    start-up from rest by the speed reference (or, without one, by the rise of the measured speed), and write
    one kilnctl record per start-up into a new or empty folder: all of them or none. The log is never modified.
    """

    name = "split-startups"
    help = "cut a long log (historian, trace tool) into one record per start-up"

    def add_arguments(self, parser) -> None:
        parser.add_argument("log", metavar="LOG", help="the long log")
        parser.add_argument("--out", metavar="DIR",
                            help="new or empty folder for startup_01.csv ... (required unless --dry-run)")
        add_options(parser,
                    config="setup (kilnctl TOML; omega_ref and ramp_rate set the rest and run levels; [measurement] "
                           "columns maps the log's names); default: the paper's Table 1",
                    columns="the log's own column names, e.g. current_A=I_arm,speed_rpm=n_mot,time_s=t [ms]")
        parser.add_argument("--by", choices=("auto", "ref", "speed"), default="auto",
                            help="cut by the speed reference or the measured speed (default: the reference when the "
                                 "log has speed_ref_rpm)")
        parser.add_argument("--pre", type=float, default=2.0, metavar="S",
                            help="time at rest kept before each ramp [s] (default 2)")
        parser.add_argument("--length", type=float, default=60.0, metavar="S",
                            help="longest record, from the ramp start [s] (default 60)")
        add_options(parser, dry_run="list the start-ups; write nothing", json="print the start-ups as JSON")

    def run(self, args) -> int:
        from ..measure.io import load_setup, read_record, record_columns
        from ..measure.split import split_startups

        if not args.out and not args.dry_run:
            raise ConfigFileError("give --out DIR (a new or empty folder for the records), or --dry-run to only list "
                                  "the start-ups")
        if args.out and not args.dry_run:  # a --out that cannot be made is refused before the log is read
            check_folder_can_be_made("--out", args.out)
        setup = load_setup(args.config)
        log = read_record(args.log, setup.params, record_columns(setup, args.columns), log=True)
        found = split_startups(log, setup.params, by=args.by, pre_s=args.pre, length_s=args.length)
        written = [] if args.dry_run else found.write(args.out, protect=(args.log, args.config))
        if args.json:
            d = found.to_dict()
            d["written"] = [str(p) for p in written]
            print_json(d)
            return 0
        print("\n".join(found.summary_lines()))
        if written:
            print(f"  wrote {len(written)} record(s) into {args.out}: {written[0].name} .. {written[-1].name}")
        return 0


register = SplitStartupsCommand.register
