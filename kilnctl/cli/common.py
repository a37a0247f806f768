"""Helpers shared by the subcommands."""

from __future__ import annotations

import inspect
import os
from abc import ABC, abstractmethod
import sys
from pathlib import Path

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


class Command(ABC):
    """A ``kilnctl`` subcommand; the docstring of a subclass is the description its ``--help`` shows.

    A subclass sets :attr:`name` and :attr:`help`, adds its options in :meth:`add_arguments` and
    does its work in :meth:`run`; its module exposes ``register = TheCommand.register``, which
    :func:`kilnctl.cli.build_parser` calls.
    """

    #: the subcommand's name
    name = ""
    #: one line for ``kilnctl --help`` (argparse %-formats it: a literal percent sign is written %%)
    help = ""  # noqa: A003 - argparse's own word

    @classmethod
    def register(cls, sub):
        """Add the subcommand, its options and its action to the ``kilnctl`` parser.

        Parameters
        ----------
        sub : argparse._SubParsersAction
            The subparsers of the ``kilnctl`` parser.

        Returns
        -------
        argparse.ArgumentParser
            The subcommand's parser.
        """
        command = cls()
        parser = sub.add_parser(cls.name, help=cls.help, description=inspect.cleandoc(cls.__doc__))
        command.add_arguments(parser)
        parser.set_defaults(func=command.run)
        return parser

    def add_arguments(self, parser) -> None:
        """Add the subcommand's options (:func:`add_options` for those several subcommands share).

        Parameters
        ----------
        parser : argparse.ArgumentParser
            The subcommand's parser.
        """

    @abstractmethod
    def run(self, args) -> int:
        """Do the subcommand's work and print or write its result; return the exit code.

        Parameters
        ----------
        args : argparse.Namespace
            The parsed arguments.

        Returns
        -------
        int
            0 on success (a subcommand's module docstring names any other code).
        """


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


def print_written(files, width: int) -> None:
    """Print one ``wrote`` line for each output file that was asked for.

    Parameters
    ----------
    files : sequence of (str, path-like or None)
        Label and path of each output; a None or empty path was not asked for.
    width : int
        Characters the label column takes, so the paths line up with the
        summary lines above them [characters].
    """
    for label, path in files:
        if path:
            print(f"  wrote {label:<{width}}{path}")


def same_file(a, b) -> bool:
    """True if two paths name the same file (existing or not).

    Parameters
    ----------
    a, b : path-like
        The paths.

    Returns
    -------
    bool
    """
    a, b = Path(a), Path(b)
    try:
        if a.exists() and b.exists():
            return os.path.samefile(a, b)
    except OSError:
        pass
    return a.resolve() == b.resolve()


def check_output_files(outputs: dict, inputs: dict) -> None:
    """Refuse output files that would overwrite an input, a folder or each other, and a figure of unknown format.

    Called before any work, so that a bad name costs nothing.

    Parameters
    ----------
    outputs : dict of str to path-like or None
        Option -> file it names (None: not given); ``--plot`` names a figure, its format from the extension.
    inputs : dict of str to path-like or None
        What an input is called in the message (``"--config"``, ``"spec"``) -> the file.

    Raises
    ------
    ConfigFileError
        Naming the option, the file and the fix.
    """
    from ..errors import ConfigFileError

    outs = [(flag, Path(v)) for flag, v in outputs.items() if v]
    for flag, path in outs:
        for what, given in inputs.items():
            if given and same_file(path, given):
                raise ConfigFileError(f"{flag} {path} is the {what} file: refusing to overwrite it")
        if path.is_dir():
            raise ConfigFileError(f"{flag} {path} is a folder: give a file name")
        # a file (or a folder this user may not write into) on the path would stop the writing only after the work
        check_folder_can_be_made(flag, path.parent if path.exists() else path)
    for i, (flag, path) in enumerate(outs):
        for other, path2 in outs[i + 1:]:
            if same_file(path, path2):
                raise ConfigFileError(f"{flag} and {other} name the same file {path}: give two names")
    if outputs.get("--plot"):
        from matplotlib.figure import Figure

        suffix = Path(outputs["--plot"]).suffix.lstrip(".").lower()
        kinds = Figure().canvas.get_supported_filetypes()
        if suffix not in kinds:
            raise ConfigFileError(f"--plot {outputs['--plot']}: unknown figure format {suffix!r}; use one of "
                                  + ", ".join(sorted(kinds)))


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
    # the report writes <command>.html, <command>.json and <command>_*.png: an input of such a name in the folder
    # would be refused only when writing, after the work
    stem = getattr(args, "command", None)
    for flag, given in (("--data", args.data), ("--config", args.config)):
        if not (stem and given) or Path(given).absolute().parent != rep.absolute():
            continue
        name = Path(given).name
        if name in (f"{stem}.html", f"{stem}.json") or (name.startswith(f"{stem}_") and name.endswith(".png")):
            raise ConfigFileError(f"--report {rep} holds the {flag} file {name}, which the report would overwrite: "
                                  "give another folder for the report, or move the input")
    check_folder_can_be_made("--report", rep)


def check_folder_can_be_made(flag: str, folder) -> None:
    """Refuse an output folder that cannot exist or be written: a file on its path, or an existing folder on its
    path that this user may not write into (checked before any work; the folder itself is made when writing).

    Parameters
    ----------
    flag : str
        The option that names the folder (``--report``, ``--out``), for the message.
    folder : path-like
        The output folder.

    Raises
    ------
    ConfigFileError
        Naming the option, the folder, what is in the way and the fix.
    """
    from ..errors import ConfigFileError

    folder = Path(folder)
    for up in (folder.absolute(), *folder.absolute().parents):
        if not up.exists():
            continue
        if not up.is_dir():
            raise ConfigFileError(f"{flag} {folder}: {up} is a file, so no folder can be made below it; give a "
                                  "folder elsewhere")
        if not os.access(up, os.W_OK | os.X_OK):
            raise ConfigFileError(f"{flag} {folder}: cannot write into {up} (permission denied); give a folder you "
                                  "may write into")
        return


def load_experiment_setup(args):
    """Refuse a bad ``--report`` folder before any work, then load the ``--config`` setup (implausible values: warned).

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


def learned_cautions(args) -> list[str]:
    """What the diagnosis behind ``--model-from`` said to read before acting on its model (empty without it);
    see :func:`kilnctl.design.learned.diagnosis_cautions`."""
    if not getattr(args, "model_from", None):
        return []
    from ..design.learned import diagnosis_cautions

    return diagnosis_cautions(args.model_from)


def print_diagnosis_cautions(args, said: list[str]) -> None:
    """Print ``said``, what the diagnosis behind ``--model-from`` said to read before acting on its model
    (:func:`learned_cautions`); nothing when it is empty."""
    import textwrap

    if not said:
        return
    print(f"\nRead what the diagnosis that learned this model ({args.model_from}) said before acting on it:")
    for text in said:
        print(textwrap.fill(text, 110, initial_indent="  - ", subsequent_indent="    "))


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
    structure : Structure or None
        The learned structure (:class:`kilnctl.structure.Structure`); None when neither option is given.
    params : Parameters
        With the diagnosis' calibrated values and the effects' options, gains resolved.
    added : list of str
        Components added to the base model.
    selected : list of str
        The effects named (the diagnosis' selection, then ``--effects``).
    """
    if not (getattr(args, "effects", None) or getattr(args, "model_from", None)):
        return None, params, [], []
    from ..gains import resolve_gains
    from ..model import component_names
    from ..structure import Structure

    params = resolve_gains(params)
    gains = {k: params[k] for k in ("k_p", "k_I", "k_D")}
    selected: list[str] = []
    structure = Structure(model or "macro")
    if args.model_from:
        from ..design.learned import learned_structure

        structure, params, selected = learned_structure(args.model_from, model=model, base=params)
        params = params.replace(gains="given", **gains)
    if args.effects:
        names = [e.strip() for e in args.effects.split(",") if e.strip()]
        structure = structure.with_effects(*names)
        params = structure.apply(params)
        selected += names
    added = [c for c in structure.components() if c not in component_names(structure.model)]
    return structure, params, added, selected
