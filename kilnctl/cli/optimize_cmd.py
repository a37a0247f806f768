"""``kilnctl optimize-ramp``: the start-up ramp of least gear stress, verified on the hybrid plant.

Solves :class:`kilnctl.optimize.RampProblem` with CasADi/IPOPT on the
smoothed micro model, re-simulates the optimum and the baseline ramp
(``ramp_rate`` of the configuration, the paper's 74 rpm/s by default) on the
exact hybrid plant, and prints predicted and verified stress side by side
(JSON with ``--json``).  ``--robust`` optimizes the worst case over the
paper's ranges of burden mass, backlash and friction and prints the price of
robustness against the nominal optimum.  Exit code 0 when the result is
verified without flags, 3 when the verification flagged it (the report
says why), 2 on an error (infeasible request, solver failure, bad input).
"""

from __future__ import annotations

import sys

from . import print_json
from .common import (Command, add_config_arg, add_options, check_folder_can_be_made, check_output_files,
                     learned_cautions, learned_structure_args, load_params,
                     print_diagnosis_cautions)

#: exit code of a result that the hybrid verification flagged
EXIT_FLAGGED = 3


class OptimizeRampCommand(Command):
    """Find the speed-reference ramp that gives the least girth-gear bending stress during the start-up while
    the motor still reaches 95 % of its set point by --t-max, with the armature current and voltage within the
    drive's limits; verify it on the exact hybrid plant.
    """

    name = "optimize-ramp"
    help = "optimize the start-up ramp for least gear stress (verified on the hybrid plant)"

    def add_arguments(self, parser) -> None:
        from ..optimize import OBJECTIVES

        add_config_arg(parser)
        parser.add_argument("--t-max", type=float, default=10.0, metavar="S",
                            help="time by which the motor must reach 95 %% of omega_ref [s] (default 10)")
        parser.add_argument("--horizon", type=float, default=None, metavar="S",
                            help="simulated start-up [s] (default t-max + 15 s: the burden reaches its running "
                                 "angle)")
        parser.add_argument("--profile", default="constant", metavar="constant|scurve|pwl:N",
                            help="ramp family: the paper's constant rate, a jerk-limited S-curve, or N "
                                 "piecewise-linear segments (default constant)")
        parser.add_argument("--objective", choices=sorted(OBJECTIVES), default="peak",
                            help="'peak': peak bending stress (running load included; ties broken by the dynamic "
                                 "stress); 'dynamic': the stress of accelerating the kiln shell only (default peak)")
        parser.add_argument("--robust", action="store_true",
                            help="minimize the worst case over m_v 240-974 t, backlash 0-16 mm and the friction "
                                 "range, and report the price of robustness")
        parser.add_argument("--transcription", choices=("single_shooting", "multiple_shooting"),
                            default="single_shooting", help="how the dynamics enter the NLP (default single_shooting)")
        add_options(parser, plot=True,
                    report="write optimize_ramp.html (one page, figure embedded), optimize_ramp.json and "
                           "optimize_ramp.png into DIR")
        parser.add_argument("--max-rate", type=float, default=None, metavar="RPM_S",
                            help="largest rate of the reference [rpm/s] (every pwl segment, the constant rate, the "
                                 "S-curve's acceleration); default 2000. Forbids a ramp that creeps and then jumps")
        add_options(parser,
                    effects="effects on the micro model, in the optimization (an effect with modes as its smooth "
                            "twin) and the verification (second_motor, speed_sensor_lag, kiln_unbalance, "
                            "viscous_drag, motor_coulomb_friction)",
                    model_from="optimize on the effects and calibrated values a diagnosis learned ('kilnctl diagnose "
                               "--json' output saved to a file); its effects must be mode-free or have a smooth twin",
                    json="print the result as JSON", quiet="no progress lines on stderr (--json implies it)")

    def run(self, args) -> int:
        from ..optimize import RampProblem, default_scenarios, optimize_ramp
        from ..optimize.robust import price_of_robustness

        check_output_files({"--plot": args.plot}, {"--config": args.config})
        if args.report:
            check_folder_can_be_made("--report", args.report)
        params = load_params(args)
        structure, params, _, _ = learned_structure_args(args, params, "micro")
        said = learned_cautions(args)  # what the diagnosis behind --model-from said, read once
        problem = RampProblem(params, profile=args.profile, t_max=args.t_max, horizon=args.horizon,
                              objective=args.objective, scenarios=default_scenarios() if args.robust else (),
                              max_rate=args.max_rate, effects=structure or ())
        progress = None
        if not (args.quiet or args.json):
            print(f"kilnctl optimize-ramp: {problem.profile.label} ramp, {len(problem.profile.names)} number(s) to "
                  "choose; Ctrl-C stops", file=sys.stderr, flush=True)

            def progress(line):
                print(line, file=sys.stderr, flush=True)
        price = None
        if args.robust:
            price = price_of_robustness(problem, transcription=args.transcription, progress=progress)
            result = price.robust
        else:
            result = optimize_ramp(problem, transcription=args.transcription, progress=progress)
        if args.plot:
            from matplotlib.figure import Figure

            from ..figures import save_figure

            save_figure(result.plot(fig=Figure(figsize=(10, 8.5))), args.plot)
        if args.report:
            from ..pages import write_ramp_report

            write_ramp_report(result, args.report, protect=(args.config,), cautions=said)
        if args.json:
            out = result.summary()
            if price is not None:
                out["robustness"] = price.summary()
            print_json(out)
        else:
            print(result.headline() + ".")
            print(result.table())
            if price is not None:
                print(price.table())
            print_diagnosis_cautions(args, said)
            if args.plot:
                print(f"  wrote plot  {args.plot}")
            if args.report:
                print(f"  wrote {args.report}/optimize_ramp.html, optimize_ramp.json, optimize_ramp.png")
        return 0 if result.ok else EXIT_FLAGGED


register = OptimizeRampCommand.register
