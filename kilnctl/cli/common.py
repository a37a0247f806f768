"""Helpers shared by the subcommands."""

from __future__ import annotations

from ..params import Parameters


def add_config_arg(parser) -> None:
    """Add the ``--config FILE`` option to a subcommand parser.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    """
    parser.add_argument("--config", metavar="FILE", help="TOML parameter file (defaults: the paper's Table 1)")


def load_params(args) -> Parameters:
    """Return the parameter set named by ``args.config`` (defaults if none).

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments with a ``config`` attribute.

    Returns
    -------
    Parameters
    """
    return Parameters.from_toml(args.config) if getattr(args, "config", None) else Parameters()
