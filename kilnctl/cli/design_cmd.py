"""``kilnctl design``: design the PID speed-loop gains by root locus for both load conditions.

Prints the gains and the closed-loop figures for stick and slip side by side (or
JSON with ``--json``); ``--plot FILE`` writes the root locus and the step
responses, whole or not at all, never over the ``--config`` file.
"""

from __future__ import annotations

from . import print_json
from .common import (Command, add_config_arg, add_options, check_output_files, learned_cautions, load_params,
                     print_diagnosis_cautions)


class DesignCommand(Command):
    """Design k_p, k_I, k_D of the paper's PID speed controller (eq. 21) by root locus so that the requirements
    hold with the burden sticking and slipping. Requirements not given keep their defaults
    (docs/tutorial_design.md). The config's 'gains' option is ignored: this command always designs.
    """

    name = "design"
    help = "design the PID speed-loop gains by root locus (stick and slip)"

    def add_arguments(self, parser) -> None:
        add_config_arg(parser)
        parser.add_argument("--zeta", type=float, metavar="Z",
                            help="minimum damping ratio of every closed-loop pole, in [0, 1] (default 0.7)")
        parser.add_argument("--settling-time", type=float, metavar="S",
                            help="maximum 2 %% settling time of the speed after a reference step [s] (default 2)")
        parser.add_argument("--overshoot", type=float, metavar="PCT",
                            help="maximum overshoot of the speed after a reference step [%%] (default 2)")
        parser.add_argument("--wn-max", type=float, metavar="W",
                            help="maximum natural frequency of the dominant pole [rad/s] (default: half the "
                                 "drive-train torsional mode sqrt(k_po/J_e), 4.5 rad/s with Table 1)")
        add_options(parser,
                    effects="also check (and retune) the gains on the macro model with these effects added, e.g. "
                            "speed_sensor_lag,second_motor (names as in 'kilnctl diagnose')",
                    model_from="also check (and retune) the gains on the structure and calibrated values a diagnosis "
                               "learned ('kilnctl diagnose --json' output saved to a file)",
                    plot="write the root locus and step responses (format from the extension: png, pdf, svg ...)",
                    json=True)

    def run(self, args) -> int:
        from ..design import Requirements, design_pid

        check_output_files({"--plot": args.plot}, {"--config": args.config})
        params = load_params(args)
        given = {"zeta_min": args.zeta, "settling_time_max": args.settling_time, "overshoot_max": args.overshoot,
                 "wn_max": args.wn_max}
        req = Requirements(**{k: v for k, v in given.items() if v is not None})
        result = design_pid(params, req)
        if args.plot:
            import matplotlib.pyplot as plt

            from ..figures import save_figure

            fig = result.plot()
            save_figure(fig, args.plot)
            plt.close(fig)
        learned = _learned(args, params, result, req)
        if args.json:
            out = result.to_dict()
            if learned is not None:
                out["learned"] = {"components": list(learned[0].components()), "selected": learned[1],
                                  **learned[2].to_dict()}
                if args.model_from:
                    out["learned"]["diagnosis_cautions"] = learned_cautions(args)
            print_json(out)
        else:
            print(result.summary())
            if learned is not None:
                print(f"\nLearned structure: the {learned[0].model} model with "
                      f"{', '.join(learned[1]) or 'no effect added'}"
                      + (f" (from {args.model_from})" if args.model_from else ""))
                print(learned[2].summary())
                print_diagnosis_cautions(args, learned_cautions(args))
            if args.plot:
                print(f"\nfigure written to {args.plot}")
        return 0


register = DesignCommand.register


def _learned(args, params, result, req):
    """The rigid design checked and retuned on --effects / --model-from, or None."""
    from ..design.learned import retune
    from ..gains import PIDGains
    from .common import learned_structure_args

    structure, lp, _, selected = learned_structure_args(args, params, None)
    if structure is None:
        return None
    g = result.gains
    lp = lp.replace(gains="given", k_p=g.k_p, k_I=g.k_I, k_D=g.k_D)
    return structure, selected, retune(lp, structure, PIDGains(g.k_p, g.k_I, g.k_D), req)
