"""Design the speed-loop PID gains by root locus and compare the stick and slip conditions.

The paper designs k_p, k_I, k_D by root locus (eq. 21, Fig. 3) and does not
print them.  This study runs the repeatable design with the default
requirements, prints the closed-loop figures for the burden sticking and
slipping side by side, shows why PI alone is not enough (the paper: "P, PI,
and PD ... not satisfactory"), and follows the closed-loop poles over the
accretion range of the burden mass (240 to 974 t, Fig. 14).

Run: ``python studies/design_gains.py`` (writes studies/out/design_gains/).
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from kilnctl import Parameters  # noqa: E402
from kilnctl.design import PIDGains, analyse, design_pid  # noqa: E402
from kilnctl.figures import save_figure  # noqa: E402

OUT = Path(__file__).parent / "out" / "design_gains"


def main(out: Path = OUT) -> None:
    """Run the design, print its tables, write figures and JSON into ``out``.

    Parameters
    ----------
    out : path-like, optional
        Output folder (default ``studies/out/design_gains``).
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    params = Parameters()
    result = design_pid(params)
    print(result.summary())

    g = result.gains
    print("\nWhy the derivative term (paper: PI 'not satisfactory'): damping of the slowest-damped pole")
    for name, gains in (("PID (designed)", g), ("PI (k_D = 0)", PIDGains(g.k_p, g.k_I, 0.0))):
        r = {c: analyse(params, gains, c) for c in ("stick", "slip")}
        print(f"  {name:<16} stick {r['stick'].zeta_min_all:.3f}   slip {r['slip'].zeta_min_all:.3f}")

    mass = result.parameter_locus()  # m_v over the paper's 240-974 t, J_v scaled with it
    wn, zeta, J = mass.dominant_wn("stick"), mass.pair_zeta("stick"), mass.inertias["stick"]
    print(f"\nAccretion, stick, m_v {mass.values[0] / 1e3:.0f} -> {mass.values[-1] / 1e3:.0f} t "
          f"(J {J[0]:.2f} -> {J[-1]:.2f} kg*m^2): dominant wn {wn[0]:.3f} -> {wn[-1]:.3f} rad/s "
          f"(wn_max {result.requirements.wn_max:.3f}), pair zeta {zeta[0]:.3f} -> {zeta[-1]:.3f} "
          f"(zeta_min {result.requirements.zeta_min:g}); slip: the burden's inertia drops out, no change")

    for name, fig in (("root_locus.png", result.locus().plot()), ("step_response.png", result.step_responses().plot()),
                      ("param_locus.png", mass.plot())):
        save_figure(fig, out / name)
    (out / "design.json").write_text(json.dumps(result.to_dict(), indent=2, allow_nan=False) + "\n")
    print(f"\nfigures and design.json written to {out}")


if __name__ == "__main__":
    main()
