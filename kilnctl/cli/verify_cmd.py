"""``kilnctl verify``: the designed gains on the nonlinear plant, beside the linear prediction."""

from __future__ import annotations

from . import print_json
from .common import (Command, add_config_arg, add_options, check_folder_can_be_made, check_output_files,
                     learned_cautions, learned_structure_args, load_params,
                     print_diagnosis_cautions)


class VerifyCommand(Command):
    """Simulate the start-up ramp with the PID gains (designed by root locus, or given in --config) on the
    nonlinear plant and print it beside the linear prediction of the design (stick and slip): overshoot,
    settling time, lag behind the ramp, peak and final current; then say where and why the two part (load
    torque, burden breakaway, drive limits, backlash). See docs/tutorial_verify.md.
    """

    name = "verify"
    help = "run the designed gains on the nonlinear plant and compare with the design"

    def add_arguments(self, parser) -> None:
        add_config_arg(parser)
        add_options(parser, model="nonlinear model (default macro)")
        parser.add_argument("--t-end", type=float, default=40.0, metavar="S", help="simulated time [s] (default 40)")
        add_options(parser,
                    effects="add effects to the nonlinear plant (names as in 'kilnctl diagnose', e.g. second_motor)",
                    model_from="verify on the structure and calibrated values a diagnosis learned ('kilnctl diagnose "
                               "--json' output saved to a file); the gains stay those of --config or the design",
                    plot=True,
                    report="write verify.html (one page, figure embedded), verify.json and verify.png into DIR",
                    json=True)

    def run(self, args) -> int:
        from ..figures import save_figure
        from ..verify import verify

        check_output_files({"--plot": args.plot}, {"--config": args.config})
        if args.report:
            check_folder_can_be_made("--report", args.report)
        params = load_params(args)
        components, params, _, _ = learned_structure_args(args, params, args.model)
        said = learned_cautions(args)  # what the diagnosis behind --model-from said, read once
        v = verify(params, model=args.model, t_end=args.t_end, components=components)
        if args.plot:
            save_figure(v.plot(), args.plot)
        if args.report:
            from ..pages import write_verify_report

            write_verify_report(v, args.report, protect=(args.config,), cautions=said)
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
            print_diagnosis_cautions(args, said)
            if args.report:
                print(f"wrote {args.report}/verify.html, verify.json, verify.png")
        return 0


register = VerifyCommand.register
