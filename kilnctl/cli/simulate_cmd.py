"""``kilnctl simulate``: run a start-up on the nonlinear hybrid plant.

Prints a summary (or JSON with ``--json``) and optionally writes the time
series as CSV and the standard figure set.  Every output file is written
whole or not at all, and never over the ``--config`` file.
"""

from __future__ import annotations

from ..errors import SimulationError
from ..params import SPECS
from . import print_json
from ..figures import save_figure
from .common import Command, add_options, check_output_files, load_params, print_written

#: default simulated time [s]: long enough for the paper's 15-17 s settling (Fig. 4, 5)
DEFAULT_T_END = 40.0


class SimulateCommand(Command):
    """Simulate a kiln start-up on the paper's macro or micro model with the designed (or configured) PID gains,
    and summarise it.
    """

    name = "simulate"
    help = "simulate a start-up on the nonlinear plant (macro or micro model)"

    def add_arguments(self, parser) -> None:
        add_options(parser,
                    model="macro: rigid reducer (eqs. 1-21); micro: coupling, pinion, mesh with backlash "
                          "(eqs. 26-34). Default: macro",
                    config=True, strict=True)
        parser.add_argument("--t-end", type=float, default=DEFAULT_T_END, metavar="S",
                            help=f"simulated time [s] (default {DEFAULT_T_END:g})")
        parser.add_argument("--max-samples", type=int, default=None, metavar="N",
                            help="largest number of output samples (t_end/dt) the run may keep in memory, checked "
                                 "before it starts (default 1000000, about 0.4 GB; or the environment variable "
                                 "KILNCTL_MAX_SAMPLES)")
        parser.add_argument("--law", choices=SPECS["friction_law"].choices, default=None,
                            help="burden friction law: 'paper' (eq. 3 as printed) or 'torque' (torque-consistent); "
                                 "default: the config's friction_law")
        add_options(parser, effects={"default": "", "help": "comma-separated effects (catalogue or component "
                                                            "names) to add, e.g. second_motor,speed_sensor_lag"})
        parser.add_argument("--remove", default="", metavar="A,B",
                            help="comma-separated components to take out of the model, e.g. current_limit")
        parser.add_argument("--csv", metavar="FILE", help="write the time series (outputs and modes) as CSV")
        add_options(parser, plot="write the standard figure set (format from the extension)",
                    json="print the summary as JSON")

    def run(self, args) -> int:
        from ..simulate import simulate
        from ..structure import Structure

        effects = _parse_effects(args.effects)
        remove = _parse_effects(args.remove, "--remove")
        check_output_files({"--csv": args.csv, "--plot": args.plot}, {"--config": args.config})
        params = load_params(args)
        if args.law is not None:
            params = params.replace(friction_law=args.law)
        structure = Structure(args.model, effects, remove)  # checks the names before any work
        params = structure.apply(params)
        components = structure.components()
        resp = simulate(params, components=structure, t_end=args.t_end, max_samples=args.max_samples)
        if args.csv:
            resp.to_csv(args.csv)
        if args.plot:
            from matplotlib.figure import Figure

            save_figure(resp.plot(fig=Figure(figsize=(10, 9))), args.plot)
        s = summary_dict(resp, params.friction_law, effects, components)
        if args.json:
            print_json(s)
            return 0
        print(f"kilnctl simulate: {args.model} model, {s['t_end_s']:g} s, friction law '{params.friction_law}'"
              + (f", effects {', '.join(effects)}" if effects else "")
              + (f", without {', '.join(remove)}" if remove else ""))
        print(f"  gains            k_p = {_gain(s['gains']['k_p'])} V/rpm, k_I = {_gain(s['gains']['k_I'])} V/(rpm*s), "
              f"k_D = {_gain(s['gains']['k_D'])} V*s/rpm")
        print(f"  peak current     {_fmt(s['peak_current_A'], ' A')}")
        print(f"  final current    {_fmt(s['final_current_A'], ' A')} (mean of the last 5 s)")
        settled = _fmt(s['settle_time_s'], ' s', fmt='.2f')
        print(f"  speed settled    {settled} (within 2 % of {params.omega_ref:g} rpm)")
        if "peak_stress_Pa" in s:
            print(f"  peak stress      {_fmt(s['peak_stress_Pa'], ' MPa', 1e6, '.1f')}")
            print(f"  final stress     {_fmt(s['final_stress_Pa'], ' MPa', 1e6, '.1f')} (mean of the last 5 s)")
        print(f"  burden at end    {s['burden_mode_final']}")
        kinds = ", ".join(f"{k} {v}" for k, v in s["events_by_kind"].items()) or "none"
        print(f"  mode switches    {s['n_events']} ({kinds})")
        print_written((("csv", args.csv), ("plot", args.plot)), 11)
        return 0


register = SimulateCommand.register


def _parse_effects(text: str, flag: str = "--effects") -> tuple[str, ...]:
    """Split ``A,B`` into names; an empty item is an error."""
    if not text.strip():
        return ()
    items = [s.strip() for s in text.split(",")]
    if any(not s for s in items):
        raise SimulationError(f"{flag} {text!r} has an empty name: give names separated by single commas")
    return tuple(items)


def summary_dict(resp, friction_law: str, effects, components) -> dict:
    """Return the JSON summary of a run.

    Parameters
    ----------
    resp : kilnctl.response.Response
        The simulation result.
    friction_law : str
        Friction law used (``paper`` or ``torque``).
    effects : sequence of str
        Components added to the base model.
    components : sequence of str
        The plant's full component list.

    Returns
    -------
    dict
        :meth:`Response.summary` (``peak_current_A`` [A], ``final_current_A``
        [A], ``settle_time_s`` [s] or None, ``burden_mode_final``,
        ``n_events``, micro: ``peak_stress_Pa``, ``final_stress_Pa`` [Pa]),
        plus ``friction_law``, ``effects``, ``components`` and the PID
        ``gains`` used.
    """
    s = resp.summary()
    p = resp.params
    s.update({
        "friction_law": friction_law,
        "effects": list(effects),
        "components": list(components),
        "gains": {"k_p": p.k_p, "k_I": p.k_I, "k_D": p.k_D},
    })
    return s


def _fmt(v, unit="", scale=1.0, fmt=".0f") -> str:
    return "n/a (not settled)" if v is None else f"{v / scale:{fmt}}{unit}"


def _gain(v: float) -> str:
    """Format a gain with four significant digits."""
    return f"{v:.4g}"
