"""The ``kilnctl`` command.

Each subcommand lives in its own module of this package and exposes
``register(subparsers)``, which adds its parser and sets ``func`` to a callable
taking the parsed arguments and returning an exit code.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys

from ..errors import KilnctlError

#: subcommand modules, in the order ``kilnctl --help`` lists them
COMMANDS = ("params_cmd", "design_cmd", "simulate_cmd", "verify_cmd", "optimize_cmd", "compare_cmd",
            "diagnose_cmd", "split_cmd", "sweep_cmd")


class _Parser(argparse.ArgumentParser):
    """An argument parser that reports an unknown option with the usage of the subcommand it was given to.

    argparse hands the arguments a subcommand does not know back to the top-level
    parser, which would print ``usage: kilnctl [-h] COMMAND ...``; a user who
    typed ``kilnctl sweep --treshold`` needs the usage of ``sweep`` instead.
    """

    def parse_args(self, args=None, namespace=None):
        """Parse like argparse, but refuse unknown arguments with the subcommand's usage."""
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            where = self
            for action in self._actions:
                if isinstance(action, argparse._SubParsersAction):
                    where = action.choices.get(getattr(ns, action.dest, None), self)
            where.error("unrecognized arguments: " + " ".join(extras)
                        + f" (see {where.prog} --help)")
        return ns


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every available subcommand.

    Returns
    -------
    argparse.ArgumentParser
    """
    from .. import __version__

    parser = _Parser(prog="kilnctl", description="Control design and tuning of rotary-kiln drives.")
    parser.add_argument("--version", action="version", version=f"kilnctl {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"{__name__}.{name}")
        except ModuleNotFoundError as exc:
            if exc.name == f"{__name__}.{name}":
                continue
            raise
        module.register(sub)
    return parser


def print_json(obj) -> None:
    """Print ``obj`` as indented JSON on standard output.

    Parameters
    ----------
    obj : object
        Anything ``json.dumps`` accepts.
    """
    json.dump(obj, sys.stdout, indent=2, allow_nan=False)
    sys.stdout.write("\n")


def main(argv=None) -> int:
    """Run the ``kilnctl`` command line.

    Parameters
    ----------
    argv : list of str, optional
        Arguments without the program name; ``sys.argv[1:]`` by default.

    Returns
    -------
    int
        Exit code: 0 on success, 2 on a user error (message on stderr).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except KilnctlError as exc:
        print(f"kilnctl {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into `head` and closed early
        sys.stderr.close()
        return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
