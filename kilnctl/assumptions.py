"""Render the assumptions table (docs/assumptions.md) from the parameter declarations.

Run ``python -m kilnctl.assumptions > docs/assumptions.md``; a test checks the
file is up to date, so the documentation cannot drift from the code.
"""

from __future__ import annotations

import sys

from .params import GROUPS, SPECS, Parameters

_READINGS = """\
## Readings of the paper (NOTES.md), each a named option or parameter

| question | kilnctl's reading | where to change it |
|---|---|---|
| `k` is both the bearing arm and the speed feedback `K` | bearing arms `l_brg`, `k_brg`; feedback `K_fb` = 60/(2 pi) rpm*s/rad | parameters `k_brg`, `K_fb` |
| garbled `k_b k_i` | `k_b` = `k_i` = 4.6 in SI (V*s/rad = N*m/A): 241 V back-emf at 500 rpm | parameter `k_b` |
| `J_e` printed 8.476e6 vs `J_o + J_v` = 8.656e6 | `J_e_mode = 'sum'` (consistent); `'table'` uses the printed J_e with a shell of J_e - J_v | option `J_e_mode` |
| derivative in eq. 21 line 2 | ideal PID on the error, the derivative realised through L_a: state x_a = i_a - (k_D/L_a) e_f | components `pid`, `dc_motor` |
| friction law not torque-consistent | `friction_law = 'paper'` (force comparison for breakaway, eq. 3) or `'torque'` (torque comparison, mu_s*N*R); both with kinetic torque mu_c*N*R against the relative velocity and re-sticking | option `friction_law` |
| printed law chatters after breakaway | Filippov sliding mode `held`: the burden moves with the wall, held by kinetic friction, until the holding torque exceeds mu_c*N*R | component `burden` |
| eq. 16 has no sign of the relative velocity | the kinetic torque opposes v_rel = omega_kiln - omega_burden | component `burden` |
| ramp constant 74 | speed reference rate 74 rpm/s (500 rpm after 6.76 s) | parameter `ramp_rate` |
| k_po, C_po "equivalent" | a lumped torsional spring-damper at the kiln axis, added by the effect `drivetrain_compliance` (not in the base models) | component `drivetrain_compliance` |
| bearing friction sign at standstill | T_brg*tanh(omega/1e-4 rad/s) (numerical regularisation; the torque is 0.2 % of the running torque) | `kilnctl/model/kiln.py` |
| voltage limit | applies to the PI voltage; the derivative action lives in the current path | component `voltage_limit` |
| current limit | the drive holds the current at +-I_max and freezes the integrator until the unlimited current would fall back | component `current_limit` |
| mesh damping pulling teeth together | clipped at zero force, as Modelica's ElastoBacklash | component `mesh` |
"""


def render(params: Parameters | None = None) -> str:
    """Return the assumptions page as Markdown.

    Parameters
    ----------
    params : Parameters, optional
        Values to show (the defaults if None).

    Returns
    -------
    str
    """
    params = Parameters() if params is None else params
    out = ["# Assumptions and parameter sources", "",
           "Generated from the parameter declarations of the components in `kilnctl/model/` by",
           "`python -m kilnctl.assumptions`; do not edit by hand.",
           "Every value is in SI units unless the unit says otherwise. A source `Table 1` or `eq. N` is the",
           "paper; `assumed: ...` is a choice kilnctl makes, with its reason. All are parameters: override",
           "them in a TOML file (`kilnctl params --config FILE`).", "", _READINGS, ""]
    groups: dict[str, list] = {}
    for spec in sorted(SPECS.values(), key=lambda s: GROUPS.index(s.group)):
        groups.setdefault(spec.group, []).append(spec)
    for group, specs in groups.items():
        out += [f"## [{group}]", "", "| name | value | unit | what | source |", "|---|---|---|---|---|"]
        for s in specs:
            v = params[s.name]
            val = f"`{v}`" if isinstance(v, str) else f"{v:.6g}"
            what = s.description.replace("|", "/")
            src = s.source.replace("|", "/")
            out.append(f"| `{s.name}` | {val} | {s.unit} | {what} | {src} |")
        out.append("")
    assumed = [s.name for s in SPECS.values() if s.source.startswith("assumed")]
    out += ["## Values the paper does not give", "",
            "These are assumptions (source starts with 'assumed'): " + ", ".join(f"`{a}`" for a in assumed) + ".", ""]
    return "\n".join(out)


if __name__ == "__main__":  # pragma: no cover
    sys.stdout.write(render())
