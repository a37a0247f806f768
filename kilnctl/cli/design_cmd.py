"""``kilnctl design``: design the PID speed-loop gains by root locus for both load conditions.

Prints the gains and the closed-loop figures for stick and slip side by side (or
JSON with ``--json``); ``--plot FILE`` writes the root locus and the step
responses, whole or not at all, never over the ``--config`` file.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigFileError
from . import print_json
from .common import add_command, add_config_arg, add_options, load_params


def register(sub) -> None:
    """Add the ``design`` subcommand.

    Parameters
    ----------
    sub : argparse._SubParsersAction
        The subparsers of the ``kilnctl`` parser.
    """
    p = add_command(
        sub, "design", run, help="design the PID speed-loop gains by root locus (stick and slip)",
        description="Design k_p, k_I, k_D of the paper's PID speed controller (eq. 21) by root locus so that "
                    "the requirements hold with the burden sticking and slipping. Requirements not given keep "
                    "their defaults (docs/tutorial_design.md). The config's 'gains' option is ignored: this "
                    "command always designs.")
    add_config_arg(p)
    p.add_argument("--zeta", type=float, metavar="Z",
                   help="minimum damping ratio of every closed-loop pole, in [0, 1] (default 0.7)")
    p.add_argument("--settling-time", type=float, metavar="S",
                   help="maximum 2 %% settling time of the speed after a reference step [s] (default 2)")
    p.add_argument("--overshoot", type=float, metavar="PCT",
                   help="maximum overshoot of the speed after a reference step [%%] (default 2)")
    p.add_argument("--wn-max", type=float, metavar="W",
                   help="maximum natural frequency of the dominant pole [rad/s] (default: half the drive-train "
                        "torsional mode sqrt(k_po/J_e), 4.5 rad/s with Table 1)")
    add_options(p, effects="also check (and retune) the gains on the macro model with these effects added, e.g. "
                           "speed_sensor_lag,second_motor (names as in 'kilnctl diagnose')",
                model_from="also check (and retune) the gains on the structure and calibrated values a diagnosis "
                           "learned ('kilnctl diagnose --json' output saved to a file)",
                plot="write the root locus and step responses (format from the extension: png, pdf, svg ...)",
                json=True)


def _check_plot_path(args) -> None:
    """Refuse a plot path that is the config file, a folder, or of an unknown format (before designing)."""
    from matplotlib.backend_bases import FigureCanvasBase

    path = Path(args.plot)
    if args.config and path.resolve() == Path(args.config).resolve():
        raise ConfigFileError(f"--plot {path} is the --config file: refusing to overwrite it")
    if path.is_dir():
        raise ConfigFileError(f"--plot {path} is a folder: give a file name such as {path / 'design.png'}")
    fmt = path.suffix.lstrip(".").lower()
    known = FigureCanvasBase.get_supported_filetypes()
    if fmt not in known:
        raise ConfigFileError(f"--plot {path}: unknown figure format {fmt!r}; use a name ending in one of "
                              + ", ".join("." + k for k in sorted(known)))


def run(args) -> int:
    """Design the gains and print them; return the exit code.

    Parameters
    ----------
    args : argparse.Namespace
        Parsed arguments of ``kilnctl design``.

    Returns
    -------
    int
        0 on success; a requirement that cannot be met raises
        :class:`kilnctl.design.RequirementsNotMetError` (exit code 2 with the
        best design in the message).
    """
    from ..design import Requirements, design_pid

    if args.plot:
        _check_plot_path(args)
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
            out["learned"] = {"components": list(learned[0]), "selected": learned[1],
                              **learned[2].to_dict()}
        print_json(out)
    else:
        print(result.summary())
        if learned is not None:
            from .common import _model_of

            print(f"\nLearned structure: the {_model_of(learned[0])} model with "
                  f"{', '.join(learned[1]) or 'no effect added'}"
                  + (f" (from {args.model_from})" if args.model_from else ""))
            print(learned[2].summary())
        if args.plot:
            print(f"\nfigure written to {args.plot}")
    return 0


def _learned(args, params, result, req):
    """The rigid design checked and retuned on --effects / --model-from, or None."""
    from ..design.learned import retune
    from ..gains import PIDGains
    from .common import learned_structure_args

    comps, lp, _, selected = learned_structure_args(args, params, None)
    if comps is None:
        return None
    g = result.gains
    lp = lp.replace(gains="given", k_p=g.k_p, k_I=g.k_I, k_D=g.k_D)
    return comps, selected, retune(lp, comps, PIDGains(g.k_p, g.k_I, g.k_D), req)
