"""``kilnctl sweep``: run the parametric study written in a spec file.

The spec format is described in :mod:`kilnctl.sweep.spec` and in
``docs/sweeps.md``.  Finished points are cached (default
``.kilnctl_cache/sweep`` in the current folder), so running the same command
again after an interruption computes only the missing points.  The table and
the figure are written whole or not at all, after every point has finished.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import ConfigFileError, KilnctlError
from . import print_json
from .common import Command, add_options, check_output_files, print_written, warn_implausible

#: default folder of finished points, relative to the current folder
DEFAULT_CACHE = Path(".kilnctl_cache") / "sweep"


class SweepCommand(Command):
    """Simulate every point of the study in SPEC (TOML; format in docs/sweeps.md) in parallel, print a summary
    and write the result table. Finished points are cached, so an interrupted sweep resumes when run again.
    """

    name = "sweep"
    help = "run a parametric study (grid, Latin hypercube, Monte Carlo) from a spec file"

    def add_arguments(self, parser) -> None:
        parser.add_argument("spec", metavar="SPEC.toml", help="sweep spec file")
        parser.add_argument("--executor", default="local", metavar="WHERE",
                            help="'local' (processes on this machine, default), 'serial' (in this process) or "
                                 "dask://HOST:PORT (a Dask scheduler)")
        parser.add_argument("--workers", type=int, default=None, metavar="N",
                            help="processes of the local executor (default: one per core)")
        parser.add_argument("--out", metavar="FILE", help="write the result table (.csv or .json)")
        add_options(parser, plot="write the sweep figure (format from the extension)")
        parser.add_argument("--threshold", type=float, default=None, metavar="VALUE",
                            help="a limit on the first output, in the unit the summary prints it in (a stress in MPa, "
                                 "e.g. 205.6; a current in A; a time in s): drawn in the figure, and the fraction of "
                                 "points above it is printed")
        parser.add_argument("--cache", metavar="DIR", default=str(DEFAULT_CACHE),
                            help=f"folder of finished points (default {DEFAULT_CACHE})")
        parser.add_argument("--no-cache", action="store_true", help="neither read nor store finished points")
        parser.add_argument("--max-points", type=int, default=None, metavar="N",
                            help="largest number of points, checked before any is built (default 100000, or the "
                                 "environment variable KILNCTL_MAX_POINTS)")
        add_options(parser, strict=True, dry_run="check the spec and list the study; simulate nothing",
                    json="print the summary as JSON", quiet="no progress bar")

    def run(self, args) -> int:
        from ..sweep import load_spec

        _check_outputs(args)
        study = load_spec(args.spec, max_points=args.max_points)
        warn_implausible(study.base, args, where=f"{args.spec} (base of the sweep)")
        try:
            study.parameter_sets()  # every point is checked before anything runs
        except KilnctlError as exc:
            raise type(exc)(f"{args.spec}: {exc}") from None
        threshold = threshold_si(study.outputs[0], args.threshold)
        if args.dry_run:
            print(study.describe())
            return 0
        from ..sweep import run_sweep
        from ..figures import save_figure

        cache = None if args.no_cache else args.cache
        # Ctrl-C: run_sweep ends the workers and raises SweepInterrupted, which kilnctl.cli.main prints as one
        # line (how many points are cached) with exit code 130
        result = run_sweep(study, args.executor, workers=args.workers, cache=cache, progress=not args.quiet)
        if args.out:
            result.save(args.out)
        if args.plot:
            from matplotlib.figure import Figure

            save_figure(result.plot(threshold=threshold, fig=Figure(figsize=(11, 7))), args.plot)
        s = result.summary()
        if threshold is not None:
            s["exceedance"] = result.exceedance(result.outputs[0], threshold)
        if args.json:
            print_json(s)
            return 0
        i = s["info"]
        print(study.describe())
        print(f"  ran            {i['n_points']} points: {i['n_computed']} computed, {i['n_cached']} from the cache, "
              f"{i['n_failed']} failed; {i['wall_s']:.1f} s on {i['executor']}")
        for k in result.outputs:
            if k in s:
                o = s[k]
                where = ", ".join(f"{v} = {val:g}" if not isinstance(val, str) else f"{v} = {val}"
                                  for v, val in o["argmax"].items())
                print(f"  {k:<18} min {_fmt(k, o['min'])}, mean {_fmt(k, o['mean'])}, max {_fmt(k, o['max'])} "
                      f"at {where}")
        if result.worst_point is not None:
            print(result.worst_point.describe(lambda v: _fmt(result.worst_point.output, v)), end="")
        if "exceedance" in s:
            e = s["exceedance"]
            print(f"  above {_fmt(result.outputs[0], threshold)}: {e['n_exceed']} of {e['n']} points, "
                  f"P = {e['probability']:.3f} "
                  f"(95 % interval {e['ci_low']:.3f} to {e['ci_high']:.3f})")
        if i["n_failed"]:
            first = result.table[result.table["status"] != "ok"].iloc[0]
            print(f"  first failure  point {first.name}: {first['error']}")
        print_written((("table", args.out), ("plot", args.plot)), 9)
        return 0


register = SweepCommand.register


def _check_outputs(args) -> None:
    """Refuse output files that would overwrite the spec or each other, or have an unknown format."""
    check_output_files({"--out": args.out, "--plot": args.plot}, {"spec": args.spec})
    if args.out and Path(args.out).suffix.lower() not in (".csv", ".json"):
        raise ConfigFileError(f"--out {args.out}: unknown table format; use .csv or .json")


#: a stress threshold above this many MPa was meant in Pa (kilnctl 0.1 took --threshold in Pa)
_MPA_SANITY = 1e5


def threshold_si(output: str, value: float | None) -> float | None:
    """Return ``--threshold`` in the SI unit of ``output`` (it is given in the unit the summary prints).

    Parameters
    ----------
    output : str
        The output the threshold applies to (the study's first output).
    value : float or None
        The threshold as typed: MPa for a ``*_Pa`` output, the output's own unit otherwise.

    Returns
    -------
    float or None
        The threshold in the output's SI unit [Pa, A, s ...].

    Raises
    ------
    ConfigFileError
        A stress threshold so large it must have been typed in Pa, or one that is not finite.
    """
    if value is None:
        return None
    if not math.isfinite(value):
        raise ConfigFileError(f"--threshold {value}: give a finite number")
    if not output.endswith("_Pa"):
        return value
    if abs(value) >= _MPA_SANITY:
        raise ConfigFileError(
            f"--threshold {value:g} is read in MPa (like every stress kilnctl prints), and {value:g} MPa is not "
            f"a gear stress: give --threshold {value / 1e6:g} if you meant {value:g} Pa")
    return value * 1e6


def _fmt(name: str, v: float) -> str:
    if name.endswith("_Pa"):
        return f"{v / 1e6:.1f} MPa"
    unit = name.rsplit("_", 1)[-1]
    return f"{v:.4g} {unit}" if unit in ("A", "s") else f"{v:.4g}"
