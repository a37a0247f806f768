"""Helpers shared by the subcommands."""

from __future__ import annotations

import sys

from ..params import Parameters, check_plausible


def add_config_arg(parser) -> None:
    """Add the ``--config FILE`` option to a subcommand parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    """
    parser.add_argument("--config", metavar="FILE", help="TOML parameter file (defaults: the paper's Table 1)")
    add_strict_arg(parser)


def add_strict_arg(parser) -> None:
    """Add the ``--strict`` option: implausible parameter values are errors, not warnings.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    """
    parser.add_argument("--strict", action="store_true",
                        help="refuse parameter values that are valid but almost surely a unit slip (a backlash "
                             "in mm given as m, a friction coefficient in percent, a mass in tonnes); without "
                             "it they are warnings")


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
