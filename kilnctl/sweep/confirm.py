"""Confirm a sweep's worst point with a second engine, and say how to reproduce it.

A sweep's worst case is what a user acts on (a fatigue decision, a gear
upgrade), so it must be a property of the plant, not of the integrator.
:func:`confirm_worst` re-runs the point with the largest value of an output on
the CVODES engine at rtol 1e-10 (a second integrator with its own event
location) and reports both values, whether they agree within the documented
accuracy of a default run (2e-4 relative, ``benchmarks/differential.py``), and
the point's parameters in full precision as a TOML setup that reproduces it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..params import Parameters

__all__ = ["WorstPoint", "confirm_worst", "reproduce_command", "AGREEMENT"]

#: relative agreement required between the sweep's value and the CVODES re-run (the documented
#: accuracy of a default run for peaks, see simulate())
AGREEMENT = 2e-4


@dataclass
class WorstPoint:
    """The worst point of a sweep, re-run on a second engine.

    Attributes
    ----------
    output : str
        The output the point is worst in.
    index : int
        Row of the point in the sweep table.
    variables : dict
        The sweep variables at that point, in full precision.
    value : float
        The output there, as the sweep computed it.
    reference : float or None
        The same output from the CVODES engine at rtol 1e-10 (None when the
        re-run failed; ``error`` then says why).
    agree : bool
        True when |value - reference| <= AGREEMENT * |reference|.
    setup_toml : str
        A setup file reproducing the point (parameters that differ from the
        defaults, all in full precision).
    command : str
        The ``kilnctl simulate`` command to run with that setup.
    """

    output: str
    index: int
    variables: dict
    value: float
    reference: float | None
    agree: bool
    setup_toml: str
    command: str
    error: str = ""
    extra: dict = field(default_factory=dict)

    def describe(self, fmt=None) -> str:
        """Lines for the sweep summary: the worst point, its confirmation, how to reproduce it."""
        fmt = fmt or (lambda v: f"{v:.6g}")
        where = ", ".join(f"{k} = {v!r}" for k, v in self.variables.items())
        if self.reference is None:
            head = (f"  worst point    {self.output} {fmt(self.value)} at point {self.index} ({where}); "
                    f"NOT confirmed: the CVODES re-run failed ({self.error})")
        elif self.agree:
            head = (f"  worst point    {self.output} {fmt(self.value)} at point {self.index} ({where}); confirmed by "
                    f"CVODES at rtol 1e-10: {fmt(self.reference)}")
        else:
            head = (f"  worst point    {self.output} {fmt(self.value)} at point {self.index} ({where}); "
                    f"CVODES at rtol 1e-10 gives {fmt(self.reference)}: the two engines DISAGREE beyond "
                    f"{AGREEMENT:.0e}; treat this maximum as suspect and report it (with the setup below)")
        return head + f"\n  reproduce      {self.command}  with the setup:\n" + "".join(
            f"                 {ln}\n" for ln in self.setup_toml.strip().splitlines())


def _setup_toml(params: Parameters) -> str:
    base = Parameters()
    lines = []
    for k, v in params.as_dict().items():
        if v != base[k]:
            lines.append(f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"')
    return "\n".join(lines) if lines else "# (all defaults)"


def confirm_worst(study, result, output: str | None = None, rtol: float = 1e-10) -> WorstPoint | None:
    """Re-run the worst point of a sweep on the CVODES engine and compare.

    Parameters
    ----------
    study : Study
        The study that produced ``result``.
    result : SweepResult
        Its result table.
    output : str, optional
        Output column (default: the study's first output).  Must be numeric.
    rtol : float, default 1e-10
        Relative tolerance of the re-run (atol = rtol/10).

    Returns
    -------
    WorstPoint or None
        None when no point finished or the output is not numeric.
    """
    from ..errors import KilnctlError
    from ..simulate import simulate

    output = study.outputs[0] if output is None else output
    ok = result.table[result.table["status"] == "ok"]
    if ok.empty or output == "burden_mode_final":
        return None
    col = ok[output].astype(float)
    if not col.notna().any():
        return None
    idx = int(col.idxmax())
    value = float(col.loc[idx])
    params = study.parameter_sets()[idx]
    options = {**study.options, "method": "cvodes", "rtol": rtol, "atol": rtol / 10}
    ref, err = None, ""
    try:
        resp = simulate(params, components=study.structure, t_end=study.t_end, **options)
        ref = study.custom_outputs[output](resp) if output in study.custom_outputs else resp.summary().get(output)
        ref = None if ref is None else float(ref)
    except KilnctlError as exc:
        err = f"{type(exc).__name__}: {exc}"
    agree = ref is not None and math.isfinite(ref) and abs(value - ref) <= AGREEMENT * abs(ref)
    variables = {v: (float(ok.at[idx, v]) if not isinstance(ok.at[idx, v], str) else ok.at[idx, v])
                 for v in result.variables}
    return WorstPoint(output, idx, variables, value, ref, agree, _setup_toml(params), reproduce_command(study),
                      err)


def reproduce_command(study, config: str = "worst.toml") -> str:
    """The ``kilnctl simulate`` command that runs one point of ``study`` from its setup file.

    Parameters
    ----------
    study : Study
        The study (its structure, horizon and options).
    config : str, default 'worst.toml'
        Name of the setup file holding the point's parameters.

    Returns
    -------
    str
        The command; study options ``kilnctl simulate`` cannot take (``dt``,
        ``rtol`` ...) are named after it, for a run from Python.
    """
    flags = f" --effects {','.join(study.effects)}" if study.effects else ""
    flags += f" --remove {','.join(study.remove)}" if study.remove else ""
    if study.options.get("max_samples") is not None:
        flags += f" --max-samples {study.options['max_samples']}"
    command = f"kilnctl simulate --model {study.model} --t-end {study.t_end!r}{flags} --config {config} --json"
    other = {k: v for k, v in study.options.items() if k != "max_samples"}
    if other:
        command += (" (and the study's options " + ", ".join(f"{k}={v!r}" for k, v in other.items())
                    + ", which kilnctl simulate does not take: pass them to kilnctl.simulate.simulate in Python)")
    return command
