"""The ramp-optimization step of ``make demo`` (called from :mod:`kilnctl.demo`).

A demo step, so it sits with the demo above the optimizer and the pages it writes (it lived in
``optimize/`` and made the optimizer import the pages above it)."""

from __future__ import annotations

from pathlib import Path

from .optimize.problem import RampProblem
from .optimize.result import RampResult
from .optimize.solve import optimize_ramp
from .params import Parameters

__all__ = ["demo_ramp"]


def demo_ramp(out, params: Parameters | None = None, profile: str = "scurve", t_max: float = 10.0,
              objective: str = "dynamic") -> RampResult:
    """Optimize the start-up ramp, write the comparison figure and table, print the result and the table.

    The demo optimizes the start-up (dynamic) stress: the peak stress of a
    kiln with the paper's burden is its running load, which no ramp changes
    (``docs/tutorial_ramp.md``); the result's headline gives both.

    Parameters
    ----------
    out : path-like
        Output folder (created); receives ``ramp_optimization.png``,
        ``ramp_optimization.txt`` and the one-page report
        ``ramp/optimize_ramp.html``.
    params : Parameters, optional
        Parameter set (default: Table 1 with the designed gains).
    profile : str, default 'scurve'
        Profile family (``'constant'``, ``'scurve'``, ``'pwl:N'``).
    t_max : float, default 10.0
        Time by which the motor must reach 95 % of its set point [s].
    objective : {'dynamic', 'peak'}, default 'dynamic'
        What the ramp minimizes (see :data:`~kilnctl.optimize.problem.OBJECTIVES`).

    Returns
    -------
    RampResult
    """
    from matplotlib.figure import Figure

    from .figures import save_figure

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    result = optimize_ramp(RampProblem(Parameters() if params is None else params, profile=profile, t_max=t_max,
                                       objective=objective))
    save_figure(result.plot(fig=Figure(figsize=(10, 8.5))), out / "ramp_optimization.png")
    text = result.table()
    (out / "ramp_optimization.txt").write_text(result.headline() + "\n\n" + text + "\n")
    from .pages import write_ramp_report

    write_ramp_report(result, out / "ramp")
    print("  " + result.headline() + ".")
    print("  " + text.replace("\n", "\n  "))
    print(f"  wrote {out / 'ramp_optimization.png'}, {out / 'ramp_optimization.txt'}; "
          f"report: {out / 'ramp' / 'optimize_ramp.html'}")
    return result
