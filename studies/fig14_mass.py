"""Fig. 14 of the paper: burden mass 240 000 to 974 000 kg and the steady-state bending stress.

Paper: +100 % burden mass gives +120 % steady-state stress.  This study runs
the micro model to steady running (30 s) with the designed gains of the
Table 1 kiln, scaling the burden inertia with its mass (J_v = 1.678e6 kg m^2
x m_v / 580 000 kg: same radius of gyration), and repeats it with J_v held at
Table 1 to show that the steady state does not depend on J_v.

Run: ``python studies/fig14_mass.py`` (writes studies/out/fig14_mass/).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from kilnctl import Parameters
from kilnctl.report import PaperTable
from kilnctl.simulate import simulate
from kilnctl.sweep import Grid, Study

STUDY = "fig14_mass"
OUT = Path(__file__).parent / "out" / STUDY
T_END = 30.0  # s
MASSES = (240e3, 360e3, 487e3, 580e3, 730e3, 974e3)  # kg: the paper's range; 487 t is half of 974 t
PAPER_RATIO = 2.2  # paper, Fig. 14: +100 % mass -> +120 % stress


def mean_Pa(r) -> float:
    """Mean tooth bending stress of the last 5 s [Pa] (a sweep output)."""
    return r.window_mean("sigma", 5.0)


def current_peak_A(r) -> float:
    """Largest armature current of the run [A] (a sweep output)."""
    return float(np.max(r["i_a"]))


def limited(r) -> float:
    """1 if the current limit was reached during the run, else 0 (a sweep output)."""
    return float(np.any(r.modes.get("current_limit", np.array(["free"])) != "free"))


OUTPUTS = {"mean": mean_Pa, "i_peak": current_peak_A, "limited": limited}


def main(out: Path = OUT) -> PaperTable:
    """Run the study, write its figure and table, print the table.

    Parameters
    ----------
    out : path-like, optional
        Output folder (default ``studies/out/fig14_mass``).

    Returns
    -------
    PaperTable
        The comparison with the paper.
    """
    table1 = Parameters()
    # burden = m_v / Table 1; the gains designed for Table 1 are kept for every burden (Study's default)
    burden = [m / table1.m_v for m in MASSES]
    scaled = Study(Grid({"burden": burden}), OUTPUTS, model="micro", t_end=T_END, base=table1,
                   factors={"burden": ("m_v", "J_v")}, name=STUDY)  # J_v scaled with m_v
    fixed = Study(Grid({"burden": burden}), OUTPUTS, model="micro", t_end=T_END, base=table1,
                  factors={"burden": ("m_v",)}, name=STUDY)  # J_v held at Table 1
    res = {}  # (J_v scaled, m_v) -> outputs
    for is_scaled, st in ((True, scaled), (False, fixed)):
        table = st.run(executor="serial", progress=False).table
        res.update({(is_scaled, m): row._asdict() for m, row in zip(MASSES, table.itertuples())})
    base = scaled.controlled_base()  # Table 1 with the designed gains
    runs = {m: simulate(scaled.params_at({"burden": b}), "micro", t_end=T_END)
            for m, b in zip(MASSES, burden)}  # the transients of panel (a): the sweep keeps only the outputs

    # --- figure --------------------------------------------------------------------------------
    fig = Figure(figsize=(11, 8.5))
    ax, bx = fig.subplots(2, 1)
    colors = dict(zip(MASSES, ("#c6dbef", "#9ecae1", "#6baed6", "k", "#2171b5", "#08306b")))
    for m in MASSES:
        r = runs[m]
        ax.plot(r.t, r["sigma"] / 1e6, color=colors[m], lw=2.0 if m == base.m_v else 1.2,
                label=f"m_v = {m / 1e3:.0f} t" + (" (Table 1)" if m == base.m_v else ""))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tooth bending stress [MPa]")
    ax.set_title("(a) stress during start-up and running, J_v scaled with m_v", loc="left", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", ncol=2)
    ax.grid(True, alpha=0.3)
    mt = np.array(MASSES) / 1e3
    s0 = res[True, base.m_v]["mean"] / 1e6
    mm = np.linspace(mt[0], mt[-1], 100)
    bx.plot(mm, s0 * (mm / (base.m_v / 1e3)) ** math.log2(PAPER_RATIO), color="C3", ls="--", lw=1.2,
            label="paper's trend through the Table 1 point: +100 % mass -> +120 % stress")
    bx.plot(mm, s0 * mm / (base.m_v / 1e3), color="0.5", ls=":", lw=1.2, label="proportional to m_v")
    bx.plot(mt, [res[True, m]["mean"] / 1e6 for m in MASSES], "o", color="k", ms=7,
            label="kilnctl, J_v scaled with m_v (mean of the last 5 s)")
    bx.plot(mt, [res[False, m]["mean"] / 1e6 for m in MASSES], "x", color="C1", ms=9, mew=2,
            label="kilnctl, J_v fixed at Table 1")
    bx.set_xlabel("burden mass m_v [t]")
    bx.set_ylabel("steady-state stress [MPa]")
    bx.set_title("(b) Fig. 14: steady-state stress against burden mass", loc="left", fontsize=10)
    bx.legend(fontsize=8, loc="upper left")
    bx.grid(True, alpha=0.3)
    fig.suptitle("Fig. 14 reproduced: burden mass, micro model, designed PID gains", fontsize=12)
    fig.tight_layout()
    Path(out).mkdir(parents=True, exist_ok=True)
    fig.savefig(Path(out) / "fig14_mass.png", dpi=110)

    # --- table -----------------------------------------------------------------------------------
    s = {m: res[True, m]["mean"] for m in MASSES}
    r1 = s[487e3] / s[240e3]  # 240 -> 487 t (+103 %)
    r2 = s[974e3] / s[487e3]  # 487 -> 974 t (+100 %)
    slope = np.polyfit(np.log(MASSES), np.log([s[m] for m in MASSES]), 1)[0]
    dj = max(abs(res[True, m]["mean"] - res[False, m]["mean"]) / res[False, m]["mean"] for m in MASSES)
    tab = PaperTable(STUDY, "micro-model steady-state stress, m_v = 240-974 t (J_v scaled with m_v)")
    tab.add("stress increase for +100 % mass", "+120 %",
            f"+{100 * (r2 - 1):.0f} % (487 -> 974 t); +{100 * (r1 - 1):.0f} % (240 -> 487 t, +103 % mass)",
            "differs",
            "kilnctl's steady kiln torque is m_v g L sin(atan(mu_c R/L)) + T_brg: proportional to m_v with L, R "
            "and mu fixed (Table 1), less the constant bearing term. A +120 % rise needs something that grows "
            "with the fill (torque arm L, friction, or a load-dependent factor), which the paper does not give")
    tab.add("log-log slope d ln(sigma)/d ln(m_v)", f"{math.log2(PAPER_RATIO):.2f} (from +120 %)", f"{slope:.3f}",
            "differs", "")
    tab.add("steady-state stress, 240 / 580 / 974 t", "Fig. 14 (values not in the text)",
            " / ".join(f"{s[m] / 1e6:.1f}" for m in (240e3, 580e3, 974e3)) + " MPa", "not in paper",
            f"Lewis form, module {base.module * 1e3:g} mm, face width {base.face_width:g} m, Y = {base.Y_lewis:g} "
            "(assumed, docs/model_reference.md)")
    tab.add("effect of scaling J_v with m_v", "-", f"at most {100 * dj:.2f} % on the steady stress",
            "not in paper", "a static equilibrium does not depend on inertia")
    lim = [m for m in MASSES if res[True, m]["limited"]]
    tab.add("drive limits", "-",
            f"peak current {res[True, 974e3]['i_peak']:.0f} A at 974 t (I_max = {base.I_max:.0f} A); "
            + ("current limit reached at " + ", ".join(f"{m / 1e3:.0f} t" for m in lim) if lim
               else "current limit never reached"),
            "not in paper", "")
    tab.write(out)
    print(tab.to_text())
    return tab


if __name__ == "__main__":
    main()
