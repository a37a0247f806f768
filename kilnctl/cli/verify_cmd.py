"""``kilnctl verify``: the designed gains on the nonlinear plant, beside the linear prediction."""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigFileError
from . import print_json
from .common import add_command, add_config_arg, add_options, learned_structure_args, load_params


def register(sub) -> None:
    """Add the ``verify`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
    """
    p = add_command(
        sub, "verify", run, help="run the designed gains on the nonlinear plant and compare with the design",
        description="Simulate the start-up ramp with the PID gains (designed by root locus, or given in "
                    "--config) on the nonlinear plant and print it beside the linear prediction of the design "
                    "(stick and slip): overshoot, settling time, lag behind the ramp, peak and final current; "
                    "then say where and why the two part (load torque, burden breakaway, drive limits, "
                    "backlash). See docs/tutorial_verify.md.")
    add_config_arg(p)
    add_options(p, model="nonlinear model (default macro)")
    p.add_argument("--t-end", type=float, default=40.0, metavar="S", help="simulated time [s] (default 40)")
    add_options(p, effects="add effects to the nonlinear plant (names as in 'kilnctl diagnose', e.g. second_motor)",
                model_from="verify on the structure and calibrated values a diagnosis learned ('kilnctl diagnose "
                           "--json' output saved to a file); the gains stay those of --config or the design",
                plot=True, report="write verify.html (one page, figure embedded), verify.json and verify.png into DIR",
                json=True)


def run(args) -> int:
    """Verify and print; return the exit code."""
    from ..figures import save_figure
    from ..verify import verify

    if args.plot and args.config and Path(args.plot).resolve() == Path(args.config).resolve():
        raise ConfigFileError(f"--plot {args.plot} is the --config file: refusing to overwrite it")
    params = load_params(args)
    components, params, _, _ = learned_structure_args(args, params, args.model)
    v = verify(params, model=args.model, t_end=args.t_end, components=components)
    if args.plot:
        save_figure(v.plot(), args.plot)
    if args.report:
        from ..pages import write_verify_report

        write_verify_report(v, args.report, protect=(args.config,))
    if args.json:
        print_json(v.to_dict())
    else:
        g = v.params
        print(f"gains: k_p = {g.k_p:.4g} V/rpm, k_I = {g.k_I:.4g} V/(rpm*s), k_D = {g.k_D:.4g} V*s/rpm")
        if components is not None:
            from ..model import component_names

            added = [c for c in components if c not in component_names(args.model)]
            print(f"nonlinear plant: the {args.model} model with {', '.join(added) or 'nothing added'}"
                  + (f" and the calibrated values of {args.model_from}" if args.model_from else ""))
        print(v)
        if args.report:
            print(f"wrote {args.report}/verify.html, verify.json, verify.png")
    return 0
