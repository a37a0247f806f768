"""``kilnctl params``: print the resolved parameter set with units and sources."""

from __future__ import annotations

from ..files import read_toml
from ..params import FOLDED_BY_MOTORS, MOTORS_KEY
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
        motors = _motors(args)
        if motors:
            print(f"(motors = {motors} in [motor]: {', '.join(FOLDED_BY_MOTORS)} above are {motors} times one motor's; "
                  "the armature circuit and I_max are one motor's)")
        return 0


def _motors(args) -> int | None:
    """The ``motors`` of the --config file's [motor] section (already folded into the parameters), or None."""
    config = getattr(args, "config", None)
    if not config:
        return None
    motor = read_toml(config, "configuration file").get("motor", {})
    n = motor.get(MOTORS_KEY) if isinstance(motor, dict) else None
    return n if isinstance(n, int) and not isinstance(n, bool) and n > 1 else None


register = ParamsCommand.register
