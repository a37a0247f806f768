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
from .common import add_command, add_options, warn_implausible

#: default folder of finished points, relative to the current folder
DEFAULT_CACHE = Path(".kilnctl_cache") / "sweep"


def register(sub) -> None:
    """Add the ``sweep`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``kilnctl`` parser.
    """
    p = add_command(
        sub, "sweep", run, help="run a parametric study (grid, Latin hypercube, Monte Carlo) from a spec file",
        description="Simulate every point of the study in SPEC (TOML; format in docs/sweeps.md) in parallel, "
                    "print a summary and write the result table. Finished points are cached, so an "
                    "interrupted sweep resumes when run again.")
    p.add_argument("spec", metavar="SPEC.toml", help="sweep spec file")
    p.add_argument("--executor", default="local", metavar="WHERE",
                   help="'local' (processes on this machine, default), 'serial' (in this process) or "
                        "dask://HOST:PORT (a Dask scheduler)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="processes of the local executor (default: one per core)")
    p.add_argument("--out", metavar="FILE", help="write the result table (.csv or .json)")
    add_options(p, plot="write the sweep figure (format from the extension)")
    p.add_argument("--threshold", type=float, default=None, metavar="VALUE",
                   help="a limit on the first output, in the unit the summary prints it in (a stress in MPa, "
                        "e.g. 205.6; a current in A; a time in s): drawn in the figure, and the fraction of "
                        "points above it is printed")
    p.add_argument("--cache", metavar="DIR", default=str(DEFAULT_CACHE),
                   help=f"folder of finished points (default {DEFAULT_CACHE})")
    p.add_argument("--no-cache", action="store_true", help="neither read nor store finished points")
    p.add_argument("--max-points", type=int, default=None, metavar="N",
                   help="largest number of points, checked before any is built (default 100000, or the "
                        "environment variable KILNCTL_MAX_POINTS)")
    add_options(p, strict=True, dry_run="check the spec and list the study; simulate nothing",
                json="print the summary as JSON", quiet="no progress bar")


def _check_outputs(args) -> None:
    """Refuse output files that would overwrite the spec or each other, or have an unknown format."""
    from .simulate_cmd import _same_file

    spec = Path(args.spec)
    outs = [(flag, Path(v)) for flag, v in (("--out", args.out), ("--plot", args.plot)) if v]
    for flag, path in outs:
        if _same_file(path, spec):
            raise ConfigFileError(f"{flag} {path} is the spec file: refusing to overwrite it")
        if path.is_dir():
            raise ConfigFileError(f"{flag} {path} is a folder: give a file name")
    if len(outs) == 2 and _same_file(outs[0][1], outs[1][1]):
        raise ConfigFileError(f"--out and --plot name the same file {outs[0][1]}: give two names")
    if args.out and Path(args.out).suffix.lower() not in (".csv", ".json"):
        raise ConfigFileError(f"--out {args.out}: unknown table format; use .csv or .json")
    if args.plot:
        from matplotlib.figure import Figure

        suffix = Path(args.plot).suffix.lstrip(".").lower()
        kinds = Figure().canvas.get_supported_filetypes()
        if suffix not in kinds:
            raise ConfigFileError(f"--plot {args.plot}: unknown figure format {suffix!r}; use one of "
                                  + ", ".join(sorted(kinds)))


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


def run(args) -> int:
    """Run the sweep, write the requested files, print the summary; return the exit code.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed ``sweep`` arguments.

    Returns
    -------
    int
        0 on success; Ctrl-C ends in :func:`kilnctl.cli.main` with 130 (finished points stay
        cached).
    """
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
    for flag, path in (("table", args.out), ("plot", args.plot)):
        if path:
            print(f"  wrote {flag:<8} {path}")
    return 0
