"""``kilnctl params``: print the resolved parameter set with units and sources."""

from __future__ import annotations

from . import print_json
from .common import Command, add_config_arg, add_options, load_params


class ParamsCommand(Command):
    """Print every parameter of the plant and controller (the paper's Table 1, overridden by --config) with its
    value, unit, source (Table 1, an equation of the paper, or an assumption and why) and meaning; '*' marks
    values changed from the default. Use it to check a configuration file before a run.
    """

    name = "params"
    help = "print the parameter set with units and sources"

    def add_arguments(self, parser) -> None:
        add_config_arg(parser)
        add_options(parser, json=True)

    def run(self, args) -> int:
        params = load_params(args)
        rows = params.describe()
        if args.json:
            print_json({r["name"]: {k: r[k] for k in ("value", "unit", "source", "description", "group")}
                        for r in rows})
            return 0
        group = None
        for r in rows:
            if r["group"] != group:
                group = r["group"]
                print(f"\n[{group}]")
            value = r["value"] if isinstance(r["value"], str) else f"{r['value']:.6g}"
            mark = "*" if r["value"] != r["default"] else " "
            print(f"{mark} {r['name']:<15} {value:>12}  {r['unit']:<12} {r['description']}")
            print(f"  {'':<15} {'':>12}  source: {r['source']}")
        print("\n(* = changed from the default)")
        return 0


register = ParamsCommand.register
