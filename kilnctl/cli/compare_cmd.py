"""``kilnctl compare``: simulate a measured experiment and say where the model fails.

Prints fit % per channel, the residual tests and the failing intervals (or
JSON with ``--json``); ``--report DIR`` writes ``compare.html`` (self-contained,
figures embedded), ``compare.json`` and ``compare.png``.  Input files are
never modified.
"""

from __future__ import annotations

from ..errors import ConfigFileError
from . import print_json
from .common import Command, add_options, load_experiment_setup

__all__ = ["CompareCommand", "register"]


class CompareCommand(Command):
    """Simulate the experiment of a measured record (docs/measurements.md) and compare: fit % per channel as
    MATLAB's compare defines it, residual whiteness and cross-correlation with 99 % bands, residual spectrum,
    and the intervals where |residual| > 3 sigma.
    """

    name = "compare"
    help = "compare the model with a measured start-up: fit %%, residual tests, where it fails"

    def add_arguments(self, parser) -> None:
        add_options(parser, data=True, columns=True, strict=True,
                    config="setup of the experiment (kilnctl TOML parameter file, optional [measurement] section); "
                           "default: the paper's Table 1",
                    model="model to compare (default macro)",
                    effects={"default": "", "help": "comma-separated effects to add, e.g. second_motor,"
                             "speed_sensor_lag (see kilnctl.measure.CATALOGUE)"},
                    report="write compare.html, compare.json and compare.png into DIR",
                    json="print the comparison as JSON")

    def run(self, args) -> int:
        from ..measure.effects import effect_components
        from ..measure.io import read_record, record_columns
        from ..measure.compare import compare

        setup = load_experiment_setup(args)  # a bad --report is refused before the work
        names = parse_names(args.effects)
        effects, params = effect_components(names, setup.params, model=args.model)
        data = read_record(args.data, setup.params, record_columns(setup, args.columns))
        c = compare(data, params, model=args.model, effects=effects, t0=setup.options.get("t0_s"))
        d = c.to_dict()
        d["record_notes"] = list(data.notes)  # how the file was read: units converted, columns ignored
        if args.report:
            from ..measure.report import write_comparison_report

            write_comparison_report(c, args.report, protect=(args.data, args.config), record_notes=data.notes)
        if args.json:
            print_json(d)
            return 0
        print("\n".join(c.summary_lines()))
        for note in data.notes:
            print(f"  record: {note}")
        if args.report:
            print(f"  wrote {args.report}/compare.html, compare.json, compare.png")
        return 0


register = CompareCommand.register


def parse_names(text: str, flag: str = "--effects") -> tuple[str, ...]:
    """Split ``A,B`` into names; an empty item is an error.

    Parameters
    ----------
    text : str
        Comma-separated names.
    flag : str
        Option name, for the message.

    Returns
    -------
    tuple of str
    """
    if not text or not text.strip():
        return ()
    items = [s.strip() for s in text.split(",")]
    if any(not s for s in items):
        raise ConfigFileError(f"{flag} {text!r} has an empty name: give names separated by single commas")
    return tuple(items)
