"""Helpers shared by the subcommands."""

from __future__ import annotations

import sys

from ..params import Parameters, check_plausible


#: options several subcommands share: name -> (flag, ``add_argument`` keywords); a subcommand may give its own
#: help or keywords (see :func:`add_options`)
SHARED_OPTIONS = {
    "data": ("--data", {"required": True, "metavar": "FILE", "help": "measured record: CSV, .xlsx, .parquet or "
                        ".mat with time_s, current_A, speed_rpm [, speed_ref_rpm] (docs/measurements.md)"}),
    "columns": ("--columns", {"metavar": "MAP", "help": "the record's own column names, e.g. "
                              "current_A=I_arm,speed_rpm=n_mot,time_s=t; units in the header or here ('time_s=t "
                              "[ms]') are converted (default: the setup's [measurement] columns)"}),
    "config": ("--config", {"metavar": "FILE", "help": "TOML parameter file (defaults: the paper's Table 1)"}),
    "strict": ("--strict", {"action": "store_true", "help": "refuse parameter values that are valid but almost "
                            "surely a unit slip (a backlash in mm given as m, a friction coefficient in percent, "
                            "a mass in tonnes); without it they are warnings"}),
    "model": ("--model", {"choices": ("macro", "micro"), "default": "macro"}),
    "effects": ("--effects", {"metavar": "A,B"}),
    "model_from": ("--model-from", {"metavar": "DIAGNOSE.json"}),
    "plot": ("--plot", {"metavar": "FILE", "help": "write the comparison figure (format from the extension)"}),
    "report": ("--report", {"metavar": "DIR"}),
    "dry_run": ("--dry-run", {"action": "store_true"}),
    "json": ("--json", {"action": "store_true", "help": "print JSON instead of a table"}),
    "quiet": ("--quiet", {"action": "store_true", "help": "no progress lines on stderr"}),
}


def add_command(sub, name: str, run, *, help: str, description: str):  # noqa: A002 - argparse's own keyword
    """Add a subcommand whose parsed arguments go to ``run``; return its parser.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``kilnctl`` parser.
    name : str
        Subcommand name.
    run : callable
        Takes the parsed arguments, returns the exit code.
    help : str
        One line for ``kilnctl --help``.
    description : str
        What the subcommand does, for ``kilnctl NAME --help``.

    Returns
    -------
    argparse.ArgumentParser
    """
    parser = sub.add_parser(name, help=help, description=description)
    parser.set_defaults(func=run)
    return parser


def add_options(parser, **options) -> None:
    """Add options of :data:`SHARED_OPTIONS` to a subcommand parser, in the order given.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The subcommand's parser.
    **options : bool, str or dict
        Option name (``model_from`` for ``--model-from``) -> ``True`` for the shared help, the
        subcommand's own help text, or a dict of ``add_argument`` keywords that replace the shared ones.
    """
    for name, given in options.items():
        flag, keywords = SHARED_OPTIONS[name]
        if isinstance(given, str):
            given = {"help": given}
        parser.add_argument(flag, **{**keywords, **(given if isinstance(given, dict) else {})})


def add_config_arg(parser) -> None:
    """Add ``--config FILE`` (the shared help) and ``--strict`` to a subcommand parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    """
    add_options(parser, config=True, strict=True)


def warn_implausible(params: Parameters, args, where: str = "") -> None:
    """Print one warning line per implausible value (or raise with ``--strict``).

    Parameters
    ----------
    params : Parameters
        The parameter set the command will use.
    args : argparse.Namespace
        Parsed arguments (``command``, ``strict``).
    where : str, optional
        The file the values come from.
    """
    for msg in check_plausible(params, strict=getattr(args, "strict", False), where=where):
        print(f"kilnctl {args.command}: warning: {msg} (--strict makes this an error)", file=sys.stderr)


def load_params(args) -> Parameters:
    """Return the parameter set named by ``args.config`` (defaults if none).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with a ``config`` attribute.

    Returns
    -------
    Parameters
        Implausible values are printed as warnings, or refused with ``--strict``.
    """
    config = getattr(args, "config", None)
    params = Parameters.from_toml(config) if config else Parameters()
    warn_implausible(params, args, where=config or "")
    return params


def check_report_dir(args) -> None:
    """Refuse a ``--report`` path that is a file (or the data or config file), before any work.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``report``, ``data`` and ``config``.
    """
    from pathlib import Path

    from ..errors import ConfigFileError

    rep = Path(args.report)
    for flag, given in (("--data", args.data), ("--config", args.config)):
        if given and rep.exists() and Path(given).exists() and rep.resolve() == Path(given).resolve():
            raise ConfigFileError(f"--report {rep} is the {flag} file: give a folder for the report files")
    if rep.exists() and not rep.is_dir():
        raise ConfigFileError(f"--report {rep} is a file, not a folder: give a folder (created if missing) for "
                              "the report files (HTML, JSON, figures)")


def load_experiment_setup(args):
    """Refuse a bad ``--report`` folder before any work, then load the ``--config`` setup, warning of implausible values.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``report``, ``data``, ``config`` and ``strict``.

    Returns
    -------
    kilnctl.measure.io.Setup
        The parameters and the ``[measurement]`` options of the experiment.
    """
    from ..measure.io import load_setup

    if args.report:
        check_report_dir(args)
    setup = load_setup(args.config)
    warn_implausible(setup.params, args, where=args.config or "")
    return setup


def learned_structure_args(args, params: Parameters, model: str | None):
    """The structure ``--model-from DIAGNOSE.json`` and ``--effects A,B`` describe, with the gains of ``params``.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with ``model_from`` and ``effects``.
    params : Parameters
        The setup (``--config``); its gains (given, or designed) are kept on the learned structure.
    model : str or None
        Base model; None: the diagnosis' model, else macro.

    Returns
    -------
    components : tuple of str or None
        None when neither option is given.
    params : Parameters
        With the diagnosis' calibrated values and the effects' options, gains resolved.
    added : list of str
        Components added to the base model.
    selected : list of str
        The effects named (the diagnosis' selection, then ``--effects``).
    """
    if not (getattr(args, "effects", None) or getattr(args, "model_from", None)):
        return None, params, [], []
    from ..measure.effects import effect_components
    from ..model import component_names
    from ..simulate import resolve_gains

    params = resolve_gains(params)
    gains = {k: params[k] for k in ("k_p", "k_I", "k_D")}
    selected: list[str] = []
    comps = None
    if args.model_from:
        from ..design.learned import learned_structure

        comps, params, selected = learned_structure(args.model_from, model=model, base=params)
        params = params.replace(gains="given", **gains)
    model = model or _model_of(comps) or "macro"
    base = component_names(model)
    added = [c for c in (comps or ()) if c not in base]
    if args.effects:
        names = [e.strip() for e in args.effects.split(",") if e.strip()]
        extra, params = effect_components(names, params, model)
        added += [c for c in extra if c not in added]
        selected += names
    return component_names(model, added), params, added, selected


def _model_of(components) -> str | None:
    """The base model a component list was built on (micro when it has a mesh)."""
    if components is None:
        return None
    return "micro" if "mesh" in components else "macro"
